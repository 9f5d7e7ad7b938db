#!/usr/bin/env bash
# train-segmenter, segment --model and evaluate classes: outputs, JSON keys
# and bad input (one line naming the file and the reason, exit 2, nothing
# half-written). The training itself is tested in app/learned_model_test.cc.
# usage: learning_cli_test.sh PLANTSCALE WORKDIR SOURCE_DIR
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
bin="$1"; work="$2"; src="$3"
model="$src/config/models/peanut.onnx"
rm -rf "$work"; mkdir -p "$work"

# Labelled frames made by the simulator (a clone has no photographs): grey
# near-infrared (field) and colour (sanchiz_pla).
"$bin" simulate --preset field --length-m 2 --every 10 --out "$work/grey" --quiet >/dev/null
"$bin" simulate --preset sanchiz_pla --length-m 2 --every 10 --out "$work/colour" --quiet >/dev/null

bad() {  # bad NAME: a copy of the grey pass to spoil
  rm -rf "$work/$1"; cp -r "$work/grey" "$work/$1"
}
train() { "$bin" train-segmenter --quiet --epochs 1 --out "$work/m/$1.onnx" "${@:2}"; }

# A photograph without its label.
bad nolabel; rm "$work/nolabel/labels/000010.png"
expect 2 'frames/000010.png: no label' -- train a --images "$work/nolabel/frames" --labels "$work/nolabel/labels"
# A label of another size (a colour pass's label for a grey frame).
bad size; cp "$work/colour/labels/000000.png" "$work/size/labels/000000.png"
cmp -s "$work/colour/labels/000000.png" "$work/grey/labels/000000.png" && fail "the two presets' labels are alike"
expect 2 'labels/000000.png: label is [0-9]+×[0-9]+, its photograph 640×480' -- \
  train b --images "$work/size/frames" --labels "$work/size/labels"
# Ids outside 0–2 (a frame given as its own label).
bad ids; cp "$work/ids/frames/000000.png" "$work/ids/labels/000000.png"
expect 2 'labels/000000.png: label id [0-9]+ at \([0-9]+, [0-9]+\) is outside 0–2' -- \
  train c --images "$work/ids/frames" --labels "$work/ids/labels"
# An empty folder; an input size that is no multiple of 16.
mkdir -p "$work/empty"
expect 2 'empty: no PNG or JPEG images' -- train d --images "$work/empty" --labels "$work/grey/labels"
expect 2 'input-size.*multiple of 16' -- train e --images "$work/grey/frames" --labels "$work/grey/labels" \
  --input-size 300x200
# Missing training packages: said, with the apt-get line, nothing installed.
PLANTSCALE_PYTHON=/bin/false expect 2 'python3-torch.*apt-get install' -- \
  train f --images "$work/grey/frames" --labels "$work/grey/labels"
[[ ! -e "$work/m" ]] || [[ -z "$(ls -A "$work/m")" ]] || fail "bad input left files in $work/m: $(ls -A "$work/m")"

# The shipped model on colour frames: classes, overlay, JSON fractions.
expect 0 'segmented' -- "$bin" segment --model "$model" --json --quiet "$work/colour/frames" --out "$work/seg"
"$bin" segment --model "$model" --json --quiet "$work/colour/frames" --out "$work/seg" >"$work/seg.json"
for f in "$work"/colour/frames/*.png; do
  n=$(basename "$f" .png)
  [[ -s "$work/seg/${n}_classes.png" && -s "$work/seg/${n}_overlay.png" ]] || fail "no classes/overlay for $n"
done
grep -q '"crop_fraction"' "$work/seg.json" || fail "segment --json has no crop_fraction"
[[ "$(head -c 1 "$work/seg.json")" == "{" ]] || fail "segment --json: standard output is not the JSON alone"
grep -q '"weed_fraction"' "$work/seg.json" || fail "segment --json has no weed_fraction"
# A colour model on grey frames: each frame refused by name, exit 1.
expect 1 '000000.png: the model takes colour photographs and this one is grey' -- \
  "$bin" segment --model "$model" --quiet "$work/grey/frames" --out "$work/seg_grey"

# evaluate classes: JSON keys; the IoUs are fractions.
"$bin" evaluate classes --images "$work/colour/frames" --labels "$work/colour/labels" --model "$model" \
  --json --quiet >"$work/classes.json"
for key in miou soil crop weed confusion crop_min_share ms_per_megapixel photographs; do
  grep -q "\"$key\"" "$work/classes.json" || fail "evaluate classes --json lacks $key"
done
miou=$(num miou "$work/classes.json")
awk -v m="$miou" 'BEGIN { exit !(m > 0 && m <= 1) }' || fail "model mIoU $miou is not in (0, 1]"

# A corrupt model file, and a card that is not one: exit 2 naming the file.
mkdir -p "$work/corrupt"
echo "not an onnx graph" >"$work/corrupt/m.onnx"
cp "${model%.onnx}.json" "$work/corrupt/m.json"
expect 2 'corrupt/m.onnx: not an ONNX model' -- \
  "$bin" segment --model "$work/corrupt/m.onnx" --quiet "$work/colour/frames" --out "$work/seg_c"
cp "$model" "$work/corrupt/n.onnx"; echo '{"format": "other"}' >"$work/corrupt/n.json"
expect 2 'corrupt/n.json: not a plantscale model card' -- \
  "$bin" evaluate classes --images "$work/colour/frames" --labels "$work/colour/labels" --model "$work/corrupt/n.onnx"
[[ ! -e "$work/seg_c" ]] || [[ -z "$(ls -A "$work/seg_c")" ]] || fail "a model that failed to load left outputs"

# SIGTERM while training (a service manager stopping it): the optimiser stops
# as on Ctrl-C, the best model so far is written with its card saying so,
# and no work folder (the photographs as arrays) is left beside it.
if /usr/bin/python3 -c 'import torch, onnx' 2>/dev/null; then
  mkdir -p "$work/term"
  "$bin" train-segmenter --quiet --epochs 500 --max-minutes 0 --input-size 128x96 --width 4 \
    --images "$work/grey/frames" --labels "$work/grey/labels" --out "$work/term/m.onnx" \
    >"$work/term/out" 2>&1 &
  trainer=$!
  for _ in $(seq 1 600); do  # until the first epoch's model is written (at most 60 s)
    compgen -G "$work/term/.m.training-*/model.onnx" >/dev/null && break
    sleep 0.1
  done
  kill -TERM "$trainer"
  wait "$trainer"; status=$?
  [[ $status -eq 0 ]] || fail "train-segmenter stopped by SIGTERM: exit $status: $(tail -3 "$work/term/out")"
  [[ -s "$work/term/m.onnx" && -s "$work/term/m.json" ]] || fail "SIGTERM: no model written"
  grep -q '"interrupted": true' "$work/term/m.json" || fail "SIGTERM: the card does not say interrupted"
  ! compgen -G "$work/term/.m.training-*" >/dev/null || fail "SIGTERM: the work folder was left behind"
fi

# On the vehicle (crop profile segmenter.model, or --segmenter-model): a model
# that does not load leaves the grid's rule; the run goes on and says so in
# an event. A model that is not there, or an evaluation with one that does
# not load: exit 2 naming it.
"$bin" simulate --preset field --seed 3 --length-m 4 --publish --fast --lcm-url memq:// --quiet \
  --log "$work/bad.lcmlog" --segmenter-model "$work/corrupt/m.onnx" >"$work/bad_sim.out" 2>&1 ||
  fail "simulate --publish with a model that does not load stopped: $(tail -3 "$work/bad_sim.out")"
"$bin" report "$work/bad.lcmlog" --out "$work/bad_report" >/dev/null 2>&1 || fail "report of that run failed"
grep -q "segmenter_model_not_loaded" "$work/bad_report/index.html" ||
  fail "the run's report has no segmenter_model_not_loaded event"
grep -q "corrupt/m.onnx: not loaded" "$work/bad_report/index.html" ||
  fail "the event does not name the model"
# The shipped model on the vehicle: the report counts the weeds it classified
# (agronomy.weeds_by_model) and says what it does to the weed count; the run
# whose model did not load has none.
"$bin" simulate --preset field --seed 3 --length-m 6 --publish --fast --lcm-url memq:// --quiet \
  --log "$work/model.lcmlog" --segmenter-model field-grey >"$work/model_sim.out" 2>&1 ||
  fail "simulate --publish with the shipped model: $(tail -3 "$work/model_sim.out")"
"$bin" report "$work/model.lcmlog" --out "$work/model_report" >/dev/null 2>&1 || fail "report of the model's run failed"
by_model() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["agronomy"]["weeds_by_model"])' "$1"; }
n=$(by_model "$work/model_report/summary.json")
[[ "$n" -gt 0 ]] || fail "the model's run: agronomy.weeds_by_model is $n"
grep -q "learned model classified $n of the weeds" "$work/model_report/index.html" ||
  fail "the model's run: the report does not say the model classified $n weeds"
[[ "$(by_model "$work/bad_report/summary.json")" -eq 0 ]] || fail "a run without a model has weeds_by_model"
expect 2 '--segmenter-model: no-such-model: no model' -- \
  "$bin" evaluate treatment --preset field --seeds 1 --length-m 2 --segmenter-model no-such-model
expect 2 'corrupt/m.onnx: segmenter model: not loaded' -- \
  "$bin" evaluate treatment --preset field --seeds 1 --length-m 2 --segmenter-model "$work/corrupt/m.onnx"

finish learning_cli
