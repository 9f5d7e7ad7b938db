#!/usr/bin/env bash
# Command-line contract of `plantscale station --review` (issue 36) on a real
# simulated run: a log and the GeoPackage `plantscale export` makes of it
# open whole (the tour draws frames and prints their times), a log cut
# mid-event opens with the problem stated, and an empty log, a log of
# another program, a file that is not a log, a GeoPackage without its plants
# layer and a missing file exit 2 naming the file. `station --help` lists the
# keys. Rendering needs an X display: run under xvfb-run -a (skipped, 77,
# without).
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
expect 0 "Up/Down zoom.*" -- "$plantscale" station --help
expect 0 "h or \? shows" -- "$plantscale" station --help
if [[ -z "${DISPLAY:-}" ]]; then echo "skip: no DISPLAY (run under xvfb-run -a)"; exit 77; fi

log="$work/run.lcmlog"
"$plantscale" simulate --preset testbed --length-m 4 --seed 2 --publish --fast --lcm-url memq:// \
  --log "$log" >/dev/null || fail "simulate exited $?"
expect 0 "station: tour 20 frames: mean [0-9.]+ ms" -- \
  "$plantscale" station --review "$log" --tour 20 --offscreen --screenshot "$work/review.png"
[[ -s "$work/review.png" ]] || fail "--review --screenshot wrote no picture"
expect 0 "peak resident [0-9.]+ MB" -- "$plantscale" station --review "$log" --offscreen --seconds 0.5

"$plantscale" export "$log" --out "$work/maps" --origin 52.0063,-0.4206 --heading 0 --quiet >/dev/null ||
  fail "export exited $?"
expect 0 "station: tour 5 frames" -- "$plantscale" station --review "$work/maps/map.gpkg" --tour 5 --offscreen

head -c $(($(stat -c %s "$log") / 2 + 7)) "$log" >"$work/cut.lcmlog"
expect 0 "problem: log: .*cut.lcmlog: event cut off" -- \
  "$plantscale" station --review "$work/cut.lcmlog" --offscreen --seconds 0.5
: >"$work/empty.lcmlog"
expect 2 "error: station --review: .*empty.lcmlog: no events to review" -- \
  "$plantscale" station --review "$work/empty.lcmlog" --offscreen --seconds 0.5
echo "this is not a log" >"$work/garbage.lcmlog"
expect 2 "error: station --review: .*garbage.lcmlog: no events to review: .*not an LCM log" -- \
  "$plantscale" station --review "$work/garbage.lcmlog" --offscreen --seconds 0.5
# Another program's log: whole LCM events on a channel of its own.
"$plantscale" simulate --preset testbed --length-m 1 --seed 3 --publish --fast --lcm-url memq:// \
  --log "$work/ours.lcmlog" >/dev/null || fail "simulate exited $?"
python3 - "$work/ours.lcmlog" "$work/foreign.lcmlog" <<'PY' || fail "could not write the foreign log"
import struct, sys
data = open(sys.argv[1], 'rb').read()
out, at = bytearray(), 0
while at + 28 <= len(data):
    sync, num, utime, clen, dlen = struct.unpack('>IqqII', data[at:at + 28])
    body = data[at + 28 + clen: at + 28 + clen + dlen]
    out += struct.pack('>IqqII', sync, num, utime, 5, len(body)) + b'OTHER' + body
    at += 28 + clen + dlen
open(sys.argv[2], 'wb').write(out)
PY
expect 2 "error: station --review: .*foreign.lcmlog: no plantscale messages in [0-9]+ events" -- \
  "$plantscale" station --review "$work/foreign.lcmlog" --offscreen --seconds 0.5
if command -v ogr2ogr >/dev/null; then
  ogr2ogr -f GPKG "$work/no_plants.gpkg" "$work/maps/map.gpkg" rows 2>/dev/null || fail "ogr2ogr failed"
  expect 2 "error: station --review: .*no_plants.gpkg: has no .plants. layer" -- \
    "$plantscale" station --review "$work/no_plants.gpkg" --offscreen --seconds 0.5
fi
expect 2 "error: station --review: .*missing.lcmlog: no such file" -- \
  "$plantscale" station --review "$work/missing.lcmlog" --offscreen --seconds 0.5
finish "station --review CLI"
