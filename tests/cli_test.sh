#!/usr/bin/env bash
# Command-line contract of `plantscale simulate` (issue: bad input gets a
# clear message naming file, key and reason, exit code 2, nothing written).
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"


expect 2 "unknown preset \(known: .*field" -- "$plantscale" simulate --preset nope --out "$work/a"
expect 2 "length_m: must be in \(0, 10000\]" -- "$plantscale" simulate --preset testbed --length-m -3 --out "$work/a"
printf 'camera: {height_m: -1}\n' >"$work/neg.yaml"
expect 2 "neg.yaml: camera.height_m: must be > 0 \(got -1\)" -- "$plantscale" simulate --preset "$work/neg.yaml" --out "$work/a"
printf 'camera: {tilt_deg: 120}\n' >"$work/tilt.yaml"
expect 2 "tilt.yaml: camera.tilt_rad: must be in \(0, 1.5708\]" -- "$plantscale" simulate --preset "$work/tilt.yaml" --out "$work/a"
printf 'camera: {image_width_px: 0}\n' >"$work/size.yaml"
expect 2 "camera.image_width_px: must be > 0" -- "$plantscale" simulate --preset "$work/size.yaml" --out "$work/a"
printf 'field:\n  rows: [3\n' >"$work/broken.yaml"
expect 2 "broken.yaml: \(file\): malformed YAML at line" -- "$plantscale" simulate --preset "$work/broken.yaml" --out "$work/a"
printf 'field: {weeds: 3}\n' >"$work/typo.yaml"
expect 2 "typo.yaml: field.weeds: unknown key \(line 1\)" -- "$plantscale" simulate --preset "$work/typo.yaml" --out "$work/a"
expect 2 "cannot be read" -- "$plantscale" simulate --preset "$work/absent.yaml" --out "$work/a"
expect 2 "out is required|--out" -- "$plantscale" simulate --preset testbed
[[ -e "$work/a" ]] && fail "a failed run left $work/a behind"

expect 0 "driven +1\.[0-9]+ m in" -- "$plantscale" simulate --preset testbed --length-m 1 --seed 4 --quiet --out "$work/good"
for f in run.json truth/frames.csv truth/visible_plants.csv truth/plants.csv truth/lines.csv truth/odometry.csv frames/000000.png labels/000000.png instances/000000.png; do
  [[ -s "$work/good/$f" ]] || fail "missing $work/good/$f"
done
grep -q '"preset": "testbed"' "$work/good/run.json" || fail "run.json lacks the preset"

finish "simulate CLI"
