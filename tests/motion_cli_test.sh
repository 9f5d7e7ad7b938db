#!/usr/bin/env bash
# plantscale evaluate motion: the JSON contract's keys, the table with the
# paper's figures, bad arguments.
# usage: motion_cli_test.sh PLANTSCALE WORKDIR
set -euo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
bin="$1"; work="$2"
rm -rf "$work"; mkdir -p "$work"

"$bin" evaluate motion --preset sanchiz_pla --seeds 1 --frames 8 --json > "$work/eval.json"
for key in correct_correspondence_rate rotation_rmse_deg translation_rmse_m drift_cm_per_m \
           drift_along_cm_per_m drift_across_cm_per_m \
           row_fit_rms_m row_angle_deg row_spacing_m true_row_spacing_m preset seeds \
           baseline_paper published; do
  grep -q "\"$key\"" "$work/eval.json" || fail "JSON key $key missing"
done
grep -q '"preset": "sanchiz_pla"' "$work/eval.json" || fail "preset name"
grep -q '"seeds": 1' "$work/eval.json" || fail "seeds"
python3 -c "import json,sys; json.load(open(sys.argv[1]))" "$work/eval.json" || fail "not one JSON object"

"$bin" evaluate motion --seeds 1 --frames 8 --baseline paper > "$work/table.txt"
grep -q "paper's m." "$work/table.txt" || fail "no column for the paper's method"
grep -q "0.0327, 0.0272, 0.0086" "$work/table.txt" || fail "no published row-fit RMS"
grep -q "correct correspondences" "$work/table.txt" || fail "no correspondence row"

set +e
"$bin" evaluate motion --preset no_such_preset --seeds 1 >"$work/out" 2>"$work/err"
rc=$?
"$bin" evaluate motion --seeds 0 >"$work/out0" 2>"$work/err0"
rc0=$?
set -e
[[ $rc -ne 0 ]] || fail "an unknown preset succeeded"
grep -q "no_such_preset" "$work/err" || fail "no error naming the preset"
[[ $rc0 -ne 0 ]] || fail "--seeds 0 accepted"
finish "evaluate motion CLI"
