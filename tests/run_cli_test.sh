#!/usr/bin/env bash
# Command-line contract of `plantscale run` with a calibration (the whole
# pipeline on a folder of images): a good run publishes the grid and the
# nozzles; bad calibrations, presets, frame-time and odometry CSVs exit 2
# naming the file, the key or line and the reason. That a folder written by
# simulate --out runs as simulate --publish is app_test's RunContract.
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
# shellcheck source=/dev/null

pass="$work/pass"
"$plantscale" simulate --preset testbed --length-m 1 --seed 4 --quiet --out "$pass" >/dev/null ||
  fail "simulate --out for run's frames"
frames="$pass/frames" times="$pass/truth/frames.csv" odometry="$pass/truth/odometry.csv"
run=(run --camera "$frames" --fast --lcm-url memq://)

expect 0 "plantscale run: camera .*frames, calibration thesis, crop testbed-plants, vehicle silsoe-testbed, preset testbed" -- "$plantscale" "${run[@]}" \
  --calibration thesis --preset testbed --frame-times "$times" --odometry "$odometry" --log "$work/run.lcmlog"
"$plantscale" telemetry-stats "$work/run.lcmlog" >"$work/run.txt"
for channel in PLANTSCALE_GRID PLANTSCALE_NOZZLES PLANTSCALE_PLANTS PLANTSCALE_HEALTH; do
  grep -q "^$channel" "$work/run.txt" || fail "run --calibration published nothing on $channel"
done
grep -q "SIM_TRUTH" "$work/run.txt" && fail "run published simulator truth"
# Another camera's image size: frames refused as faults in the heartbeat.
expect 0 "preset testbed, [0-9]+ frames \(0 dropped\)" -- "$plantscale" "${run[@]}" --calibration sanchiz_pla_66 --preset testbed \
  --frame-times "$times" --odometry "$odometry" --log "$work/size.lcmlog"
grep -aq "is 640x480 px, the calibration is 768x576 px" "$work/size.lcmlog" ||
  fail "no heartbeat fault names the image size"

# Calibration files.
expect 2 "absent.yaml: \(file\): cannot be read" -- "$plantscale" "${run[@]}" --calibration "$work/absent.yaml"
printf 'height_m: [1.5\ntilt_deg: 45\n' >"$work/bad.yaml"
expect 2 "bad.yaml: \(file\): malformed YAML at line" -- "$plantscale" "${run[@]}" --calibration "$work/bad.yaml"
printf 'height_m: 1.5\nfocal_len: 0.004\n' >"$work/typo.yaml"
expect 2 "typo.yaml: focal_len: unknown key \(line 2\)" -- "$plantscale" "${run[@]}" --calibration "$work/typo.yaml"
printf 'height_m: -1\n' >"$work/neg.yaml"
expect 2 "neg.yaml: height_m: must be > 0" -- "$plantscale" "${run[@]}" --calibration "$work/neg.yaml"
expect 2 "nosuchcam: unknown camera" -- "$plantscale" "${run[@]}" --calibration nosuchcam
# A calibration of another camera than the vehicle's: refused at start, naming both.
expect 2 "sanchiz_pla_66.yaml: image size: is 768x576 px, the camera of .*silsoe.yaml .*thesis.yaml. takes 640x480 px" -- \
  "$plantscale" "${run[@]}" --calibration sanchiz_pla_66 --vehicle silsoe --crop cauliflower-6-week
sed 's/^focal_length_m: .*/focal_length_m: 0.0072/' "$PLANTSCALE_CONFIG_DIR/cameras/thesis.yaml" >"$work/longlens.yaml"
expect 2 "longlens.yaml: focal_length_m: focal length 837 px, the camera of .*silsoe.yaml .* 558 px: more than 20 % apart" -- \
  "$plantscale" "${run[@]}" --calibration "$work/longlens.yaml" --vehicle silsoe --crop cauliflower-6-week
sed 's/^focal_length_m: .*/focal_length_m: 0.0050/' "$PLANTSCALE_CONFIG_DIR/cameras/thesis.yaml" >"$work/recalibrated.yaml"
expect 0 "calibration .*recalibrated.yaml, crop cauliflower-6-week, vehicle silsoe" -- \
  "$plantscale" "${run[@]}" --calibration "$work/recalibrated.yaml" --vehicle silsoe --crop cauliflower-6-week
expect 2 "nosuch: unknown preset" -- "$plantscale" "${run[@]}" --calibration thesis --preset nosuch
expect 2 "preset requires --calibration" -- "$plantscale" "${run[@]}" --preset field

# Frame times and odometry CSVs.
"$plantscale" simulate --preset testbed --length-m 1 --seed 4 --quiet --every 2 --out "$work/every2" >/dev/null ||
  fail "simulate --out --every 2"
expect 2 "every2/truth/frames.csv: rows: [0-9]+ frame times for [0-9]+ images .*--every 1" -- "$plantscale" \
  run --camera "$work/every2/frames" --fast --lcm-url memq:// --calibration thesis \
  --frame-times "$work/every2/truth/frames.csv"
sed '3s/^1,[0-9]*,/1,soon,/' "$times" >"$work/badtime.csv"
expect 2 "badtime.csv: line 3: utime: expected an integer, got 'soon'" -- "$plantscale" "${run[@]}" \
  --calibration thesis --frame-times "$work/badtime.csv"
sed '4s/,.*//' "$times" >"$work/short.csv"
expect 2 "short.csv: line 4: 1 fields, the header has 17" -- "$plantscale" "${run[@]}" \
  --calibration thesis --frame-times "$work/short.csv"
awk 'NR == 3 { line = $0; next } { print } NR == 4 { print line }' "$times" >"$work/order.csv"
expect 2 "order.csv: line 4: utime [0-9]+ is not after the previous row's" -- "$plantscale" "${run[@]}" \
  --calibration thesis --frame-times "$work/order.csv"
cut -d, -f1,3 "$odometry" >"$work/noleft.csv"
expect 2 "noleft.csv: line 1: no column 'left_m_s'" -- "$plantscale" "${run[@]}" \
  --calibration thesis --odometry "$work/noleft.csv"
sed '5s/^\([0-9]*\),[^,]*,/\1,nan,/' "$odometry" >"$work/nan.csv"
expect 2 "nan.csv: line 5: left_m_s: must be finite" -- "$plantscale" "${run[@]}" \
  --calibration thesis --odometry "$work/nan.csv"
head -1 "$odometry" >"$work/empty.csv"
expect 2 "empty.csv: line 1: no odometry samples" -- "$plantscale" "${run[@]}" \
  --calibration thesis --odometry "$work/empty.csv"
expect 2 "absent.csv: \(file\): cannot be read" -- "$plantscale" "${run[@]}" \
  --calibration thesis --odometry "$work/absent.csv"
expect 2 "--odometry: only with a folder of images" -- "$plantscale" run --camera /dev/video99 \
  --lcm-url memq:// --odometry "$odometry"

finish "run CLI"
