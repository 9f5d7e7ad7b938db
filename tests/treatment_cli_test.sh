#!/usr/bin/env bash
# plantscale evaluate treatment: the JSON contract (issue 6), the table, the
# MRROC, weed mode and bad input.
# usage: treatment_cli_test.sh PLANTSCALE WORKDIR
set -euo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
bin="$1"; work="$2"
rm -rf "$work"; mkdir -p "$work"

"$bin" evaluate treatment --preset field --seeds 1 --length-m 12 --json --mrroc \
  >"$work/out.json" || fail "evaluate treatment --json exited $?"
for key in preset seeds crop_plants crop_hit_rate weeds weed_hit_rate placement_bias_along_m \
  placement_bias_across_m placement_rms_m treated_area_fraction mode mrroc \
  operating_point example_why; do
  grep -q "\"$key\"" "$work/out.json" || fail "JSON lacks $key"
done
grep -q '"preset": "field"' "$work/out.json" || fail "preset not named"
grep -q '"mode": "crop"' "$work/out.json" || fail "mode not crop"
# Real values: crops are found and sprayed, the bed is not drenched.
crops=$(num crop_plants "$work/out.json")
hit=$(num crop_hit_rate "$work/out.json")
area=$(num treated_area_fraction "$work/out.json")
awk -v v="$crops" 'BEGIN { exit !(v >= 40) }' || fail "crop_plants $crops < 40"
awk -v v="$hit" 'BEGIN { exit !(v >= 0.95 && v <= 1) }' || fail "crop_hit_rate $hit not in [0.95, 1]"
awk -v v="$area" 'BEGIN { exit !(v > 0.05 && v < 0.2) }' || fail "treated_area_fraction $area"
auc=$(num auc "$work/out.json")
awk -v v="$auc" 'BEGIN { exit !(v > 0.6 && v <= 1) }' || fail "MRROC auc $auc"

# The thesis's chain alongside.
"$bin" evaluate treatment --preset field --seeds 1 --length-m 8 --json --baseline thesis \
  >"$work/thesis.json" || fail "--baseline thesis exited $?"
grep -q '"baseline_thesis"' "$work/thesis.json" || fail "JSON lacks baseline_thesis"

# Weed mode sprays weeds (a third of them now: small weeds are lost to
# segmentation, weeds under a crop's leaves are spared) and spares the crop.
"$bin" evaluate treatment --preset field --seeds 1 --length-m 12 --mode weed --json \
  >"$work/weed.json" || fail "--mode weed exited $?"
grep -q '"mode": "weed"' "$work/weed.json" || fail "mode not weed"
wh=$(num weed_hit_rate "$work/weed.json")
awk -v v="$wh" 'BEGIN { exit !(v > 0.25) }' || fail "weed mode weed_hit_rate $wh <= 0.25"
ch=$(num crop_hit_rate "$work/weed.json")
awk -v v="$ch" 'BEGIN { exit !(v < 0.1) }' || fail "weed mode crop_hit_rate $ch >= 0.1"

"$bin" evaluate treatment --preset field --seeds 1 --length-m 10 >"$work/table.txt" \
  || fail "table exited $?"
grep -q "crop hit rate" "$work/table.txt" || fail "table lacks crop hit rate"
grep -q "thesis: 33.6 mm" "$work/table.txt" || fail "table lacks the thesis figure"
grep -q "plant: " "$work/table.txt" || fail "table lacks a plant's why"

expect_exit2() {  # args...: exits 2 naming $name
  local name="$1"; shift
  set +e
  "$bin" evaluate treatment "$@" >/dev/null 2>"$work/err"; local rc=$?
  set -e
  [[ $rc -eq 2 ]] || fail "$* exited $rc, want 2"
  grep -q -- "$name" "$work/err" || fail "$* error does not name $name: $(cat "$work/err")"
}
expect_exit2 nosuch --preset nosuch --seeds 1
expect_exit2 --seeds --preset field --seeds 0
expect_exit2 --mode --preset field --mode fertilise
expect_exit2 --baseline --preset field --baseline hague
expect_exit2 --footprint-scale --preset field --footprint-scale 0
finish "evaluate treatment CLI"
