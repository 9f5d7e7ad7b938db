#!/usr/bin/env bash
# plantscale evaluate tracking: the JSON contract (issue 5), the table, bad input.
# usage: tracking_cli_test.sh PLANTSCALE WORKDIR
set -euo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
bin="$1"; work="$2"
rm -rf "$work"; mkdir -p "$work"

"$bin" evaluate tracking --preset testbed --seeds 1 --length-m 4 --baseline thesis --json \
  >"$work/out.json" || fail "evaluate tracking --json exited $?"
for key in preset seeds lateral_rmse_m bearing_rmse_deg forward_drift_cm_per_m \
  row_spacing_error_m plant_spacing_error_m nees_in_bounds_fraction init_success_rate \
  init_frames_p95 baseline_thesis; do
  grep -q "\"$key\"" "$work/out.json" || fail "JSON lacks $key"
done
grep -q '"preset": "testbed"' "$work/out.json" || fail "preset not named"
# A real value: the test bed is tracked to better than a centimetre.
lat=$(grep -m1 -oE '"lateral_rmse_m": [0-9.e+-]+' "$work/out.json" | awk '{print $2}')
awk -v v="$lat" 'BEGIN { exit !(v > 0 && v < 0.01) }' || fail "lateral_rmse_m $lat not in (0, 0.01)"

"$bin" evaluate tracking --preset testbed --seeds 1 --length-m 3 >"$work/table.txt" \
  || fail "table exited $?"
grep -q "lateral RMSE" "$work/table.txt" || fail "table lacks lateral RMSE"
grep -q "thesis: 15.3 mm" "$work/table.txt" || fail "table lacks the thesis figure"

set +e
"$bin" evaluate tracking --preset nosuch --seeds 1 >/dev/null 2>"$work/err"; rc=$?
set -e
[[ $rc -eq 2 ]] || fail "unknown preset exited $rc, want 2"
grep -q "nosuch" "$work/err" || fail "error does not name the preset"
set +e
"$bin" evaluate tracking --preset testbed --seeds 0 >/dev/null 2>&1; rc=$?
set -e
[[ $rc -ne 0 ]] || fail "--seeds 0 accepted"
# --odometry-fault (issue 38): a bad kind exits 2 naming the option; a stop
# over 4 m reports the stretch under "odometry_fault".
set +e
"$bin" evaluate tracking --preset testbed --odometry-fault bogus >/dev/null 2>"$work/fault.err"; rc=$?
set -e
[[ $rc -eq 2 ]] || fail "--odometry-fault bogus exited $rc, expected 2"
grep -q -- "--odometry-fault" "$work/fault.err" || fail "--odometry-fault bogus: message does not name the option"
"$bin" evaluate tracking --preset field --seeds 1 --length-m 14 --odometry-fault stop \
  --fault-start-m 6 --fault-length-m 4 --visual-motion --json >"$work/fault.json" \
  || fail "evaluate tracking --odometry-fault stop failed"
for key in kind start_m length_m frames frames_tracking losses lateral_rmse_m forward_rmse_m; do
  grep -q "\"$key\"" "$work/fault.json" || fail "odometry_fault lacks $key"
done
frames=$(num frames "$work/fault.json")
awk -v f="$frames" 'BEGIN { exit !(f >= 40) }' || fail "a 4 m stretch at 12.5 Hz scored $frames frames (>= 40 expected)"
grep -q '"visual_motion": true' "$work/fault.json" || fail "visual_motion not reported"
finish "evaluate tracking CLI"
