#!/usr/bin/env bash
# Command-line contract of the telemetry commands (issue 8): a simulated run
# published over memq:// with a log, telemetry-stats on it within the
# 250 kbit/s budget, replay, lcm-logplayer reading the log unchanged, and bad
# input (not a log, a truncated log, options without --publish) exiting 2
# with a message naming the file and offset.
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
# shellcheck source=/dev/null

log="$work/run.lcmlog"
expect 0 "PLANTSCALE_SIM_TRUTH +[0-9]+" -- "$plantscale" simulate --preset testbed --length-m 4 --seed 2 \
  --publish --fast --lcm-url memq:// --log "$log"
"$plantscale" telemetry-stats "$log" --json >"$work/stats.json" || fail "telemetry-stats exited $?"
for key in '"total_kbit_s"' '"PLANTSCALE_SIM_TRUTH"' '"PLANTSCALE_THUMBNAIL"' '"PLANTSCALE_HEALTH"' \
  '"messages"' '"rate_hz"' '"kbit_s"'; do
  grep -q "$key" "$work/stats.json" || fail "stats.json lacks $key"
done
total=$(grep -oE '"total_kbit_s": [0-9.e+-]+' "$work/stats.json" | awk '{print $2}')
awk -v t="$total" 'BEGIN { exit !(t > 10 && t <= 250) }' || fail "total_kbit_s $total not in (10, 250]"
echo "ok: total_kbit_s $total <= 250"
# The grid tracker publishes on its own channel (issue 5); truth stays on
# PLANTSCALE_SIM_TRUTH (checked above).
grep -q '"PLANTSCALE_GRID"' "$work/stats.json" || fail "no grid tracker state on PLANTSCALE_GRID"
grep -q '"PLANTSCALE_NOZZLES"' "$work/stats.json" || fail "no nozzle states on PLANTSCALE_NOZZLES (treatment stage)"

expect 0 "republished" -- "$plantscale" replay "$log" --speed 100 --lcm-url memq:// --channels 'PLANTSCALE_HEALTH'
if command -v lcm-logplayer >/dev/null; then
  expect 0 "PLANTSCALE_SIM_TRUTH" -- lcm-logplayer -v -s 1000 -l memq:// "$log"
else
  echo "skip: lcm-logplayer not installed (liblcm-bin)"
fi

# The run's maps from its log (map tiles with treated cells, plants).
expect 0 "plantscale export: [0-9]+ plants, .* [1-9][0-9]* treated cells; EPSG:32630" -- \
  "$plantscale" export "$log" --out "$work/maps" --origin 52.0063,-0.4206 --heading 30 --quiet
[[ -s "$work/maps/map.tif" && -s "$work/maps/map_northup.tif" && -s "$work/maps/plants.csv" ]] || fail "export of the log wrote no maps"
printf 'not a log at all\n' >"$work/text.lcmlog"
expect 2 "text.lcmlog: not an LCM log.*byte offset 0" -- "$plantscale" telemetry-stats "$work/text.lcmlog" --json
size=$(stat -c %s "$log")
head -c $((size - 7)) "$log" >"$work/cut.lcmlog"
expect 2 "cut.lcmlog: event cut off or corrupt at byte offset [0-9]+" -- "$plantscale" telemetry-stats "$work/cut.lcmlog"
expect 2 "cut.lcmlog: event cut off" -- "$plantscale" replay "$work/cut.lcmlog" --speed 1000 --lcm-url memq://
expect 1 "absent.lcmlog: cannot open" -- "$plantscale" replay "$work/absent.lcmlog" --lcm-url memq://
expect 2 "text.lcmlog.*neither an LCM log .* nor a plantscale map file" -- "$plantscale" export "$work/text.lcmlog" --out "$work/no_maps" --origin 52,0 --quiet
expect 0 "warning: .*cut.lcmlog.*byte offset" -- "$plantscale" export "$work/cut.lcmlog" --out "$work/cut_maps" --origin 52,0 --quiet
expect 2 "speed: must be > 0" -- "$plantscale" replay "$log" --speed 0 --lcm-url memq://
expect 2 "only with --publish" -- "$plantscale" simulate --preset testbed --fast --out "$work/x"
expect 2 "excludes" -- "$plantscale" simulate --preset testbed --publish --out "$work/x"
expect 1 "LCM URL 'nosuch://': cannot start" -- "$plantscale" simulate --preset testbed --publish --lcm-url nosuch://

# plantscale run on a folder of images (frames written by simulate).
"$plantscale" simulate --preset testbed --length-m 1 --seed 4 --quiet --out "$work/frames_run" >/dev/null ||
  fail "simulate --out for run's frames"
expect 0 "plantscale run: camera .*frames" -- "$plantscale" run --camera "$work/frames_run/frames" --fast \
  --lcm-url memq:// --log "$work/run_camera.lcmlog"
"$plantscale" telemetry-stats "$work/run_camera.lcmlog" >"$work/run_camera.txt"
grep -q "^PLANTSCALE_THUMBNAIL" "$work/run_camera.txt" || fail "run published no thumbnails"
grep -q "^PLANTSCALE_HEALTH" "$work/run_camera.txt" || fail "run published no heartbeat"
grep -q "SIM_TRUTH" "$work/run_camera.txt" && fail "run published simulator truth"
expect 1 "video99: cannot open the camera" -- "$plantscale" run --camera /dev/video99 --lcm-url memq://
mkdir -p "$work/empty"
expect 1 "empty: no images" -- "$plantscale" run --camera "$work/empty" --lcm-url memq://

finish "telemetry CLI"
