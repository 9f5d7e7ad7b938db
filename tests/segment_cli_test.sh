#!/usr/bin/env bash
# plantscale segment / evaluate segmentation: outputs, JSON keys, bad input.
# usage: segment_cli_test.sh PLANTSCALE WORKDIR
set -euo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
bin="$1"; work="$2"
rm -rf "$work"; mkdir -p "$work/in" "$work/empty"

# Test images made by the simulator (a clone has no photographs).
"$bin" simulate --preset C --length-m 2 --every 10 --out "$work/sim" --quiet >/dev/null
cp "$work/sim/frames/000000.png" "$work/in/good.png"
"$bin" simulate --preset sanchiz_pla --length-m 2 --every 10 --out "$work/simrgb" --quiet >/dev/null
cp "$work/simrgb/frames/000000.png" "$work/in/colour.png"
: > "$work/in/zero.jpg"
head -c 3000 "$work/in/good.png" > "$work/in/truncated.png"
echo "not an image" > "$work/in/text.png"

set +e
"$bin" segment "$work/in" "$work/empty" --out "$work/out" --quiet >"$work/stdout" 2>"$work/stderr"
rc=$?
set -e
[[ $rc -eq 1 ]] || fail "exit code $rc with bad images, want 1"
for f in zero.jpg truncated.png text.png; do
  grep -q "$f" "$work/stderr" || fail "no error naming $f"
done
grep -q "empty: no PNG or JPEG images" "$work/stderr" || fail "no error for the empty folder"
for n in good colour; do
  [[ -s "$work/out/${n}_mask.png" && -s "$work/out/${n}_blobs.csv" ]] || fail "missing outputs for $n"
done
head -1 "$work/out/good_blobs.csv" | grep -q "^id,centroid_u,centroid_v,area_px,bbox_u,bbox_v,bbox_width,bbox_height$" \
  || fail "blob CSV header"
blobs=$(($(wc -l < "$work/out/good_blobs.csv") - 1))
[[ $blobs -ge 3 ]] || fail "only $blobs blobs on a 6-week frame"
ls "$work/out" | grep -q partial && fail "staging files left behind"

# The mask is the input's size, 8-bit, 0/255.
"$bin" segment "$work/in/good.png" --out "$work/out2" --method adaptive --quiet >/dev/null
[[ -s "$work/out2/good_mask.png" ]] || fail "adaptive mask"
set +e
"$bin" segment "$work/in/colour.png" --out "$work/out3" --method nir --quiet 2>"$work/stderr3"
rc=$?
set -e
[[ $rc -eq 1 ]] && grep -q "near-infrared" "$work/stderr3" || fail "nir on a colour photo must fail clearly"

# evaluate segmentation --json: the contract's keys.
"$bin" evaluate segmentation --preset B --seeds 1 --frames 2 --json > "$work/eval.json"
for key in preset auc plant_pixel_recall plant_pixel_precision soil_pixel_accuracy threshold_method; do
  grep -q "\"$key\"" "$work/eval.json" || fail "JSON key $key missing"
done
"$bin" evaluate segmentation --preset B --seeds 1 --frames 2 --roc-csv "$work/roc.csv" >/dev/null
head -1 "$work/roc.csv" | grep -q "^method,threshold,tpr,fpr$" || fail "ROC CSV header"
finish "segment CLI"
