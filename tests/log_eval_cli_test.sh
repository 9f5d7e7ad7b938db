#!/usr/bin/env bash
# plantscale evaluate log: a simulated run's log scored from its own truth
# (JSON keys of evaluate treatment and evaluate tracking, the table), and the
# exit codes: 1 for a log that cannot be read, 2 for a log that does not say
# which simulated run it came from (no run_config event: `plantscale run`).
# usage: log_eval_cli_test.sh PLANTSCALE WORKDIR
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
# shellcheck source=/dev/null

log="$work/run.lcmlog"
expect 0 "PLANTSCALE_SIM_TRUTH" -- "$plantscale" simulate --preset field --length-m 8 --seed 11 \
  --publish --fast --lcm-url memq:// --log "$log"
"$plantscale" evaluate log "$log" --json >"$work/log.json" || fail "evaluate log --json exited $?"
for key in '"log"' '"preset": "field"' '"seed": 11' '"distance_m"' '"treatment"' '"tracking"' \
  '"crop_hit_rate"' '"placement_rms_along_m"' '"placement_rms_across_m"' '"weed_hit_rate"' \
  '"treated_area_fraction"' '"lateral_rmse_m"' '"nees_in_bounds_fraction"' '"frames_scored"' \
  '"pixels": null'; do
  grep -q -- "$key" "$work/log.json" || fail "log.json lacks $key"
done
expect 0 "placement RMS along +[0-9.]+ mm" -- "$plantscale" evaluate log "$log"
grep -q -- '"row_spacing_events": \[\]' "$work/log.json" || fail "the right profile's log has row spacing events"
# A crop profile 55 mm narrower than the bed: the vehicle said so within 12 m,
# and the log's evaluation repeats it.
sed 's/^row_spacing_m: .*/row_spacing_m: 0.42/' "$(dirname "$0")/../config/crops/cauliflower-6-week.yaml" \
  >"$work/narrow.yaml"
"$plantscale" simulate --preset field --length-m 12 --seed 11 --crop "$work/narrow.yaml" --publish --fast \
  --lcm-url memq:// --log "$work/narrow.lcmlog" >/dev/null || fail "simulate with a narrow crop profile"
expect 0 "the vehicle said: row spacing measured 0\.4[6-9][0-9] m .* the crop profile says 0\.420 m" -- \
  "$plantscale" evaluate log "$work/narrow.lcmlog"
expect 0 "lateral RMSE +[0-9.]+ mm" -- "$plantscale" evaluate log "$log" --config-dir "$(dirname "$0")/../config"

expect 1 "absent.lcmlog: cannot open" -- "$plantscale" evaluate log "$work/absent.lcmlog"
printf 'not a log at all\n' >"$work/text.lcmlog"
expect 1 "text.lcmlog: not an LCM log" -- "$plantscale" evaluate log "$work/text.lcmlog"
# A camera run's log: no run_config, no truth.
"$plantscale" simulate --preset testbed --length-m 1 --seed 4 --quiet --out "$work/frames" >/dev/null ||
  fail "simulate --out for run's frames"
"$plantscale" run --camera "$work/frames/frames" --fast --lcm-url memq:// \
  --log "$work/camera.lcmlog" >/dev/null || fail "run on a folder of images"
expect 2 "camera.lcmlog: run_config: the log has no run_config event" -- \
  "$plantscale" evaluate log "$work/camera.lcmlog"

finish "evaluate log CLI"
