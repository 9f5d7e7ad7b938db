#!/usr/bin/env bash
# Command-line contract of `plantscale report` and `plantscale station`
# (issue 9) on a real simulated run (simulate --publish --fast --log over
# memq://): the report writes index.html and its pictures, the same log gives
# the same bytes, a missing display is a clear error (exit 2), and the
# station replays the log off-screen and says what is wrong with bad logs.
# Rendering needs an X display: run under xvfb-run -a (skipped, 77, without).
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
if [[ -z "${DISPLAY:-}" ]]; then echo "skip: no DISPLAY (run under xvfb-run -a)"; exit 77; fi

log="$work/run.lcmlog"
"$plantscale" simulate --preset testbed --length-m 4 --seed 2 --publish --fast --lcm-url memq:// \
  --log "$log" >/dev/null || fail "simulate exited $?"
expect 0 "report: .*index.html" -- "$plantscale" report "$log" --out "$work/a"
expect 0 "report: .*index.html" -- "$plantscale" report "$log" --out "$work/b"
for f in "$work"/a/*; do
  cmp -s "$f" "$work/b/$(basename "$f")" || fail "$(basename "$f") differs between two reports of one log"
done
grep -q "<th>distance</th><td>4\.[0-9][0-9] m</td>" "$work/a/index.html" || fail "index.html: distance not ~4 m"
grep -q "simulator truth" "$work/a/index.html" || fail "index.html: offset source not named"
[[ -s "$work/a/map.png" && -s "$work/a/offset_trace.png" ]] || fail "pictures missing"

expect 2 "needs an X display.*xvfb-run" -- env -u DISPLAY "$plantscale" report "$log" --out "$work/c"
echo "this is not a log" >"$work/garbage.lcmlog"
expect 0 "problem: log:" -- "$plantscale" report "$work/garbage.lcmlog" --out "$work/d"
expect 0 "station: [0-9]+ frames" -- "$plantscale" station --log "$log" --offscreen --seconds 1 --speed 4
expect 0 "problem: .*no plantscale messages|problem: log:" -- \
  "$plantscale" station --log "$work/garbage.lcmlog" --offscreen --seconds 1

expect 2 "memq:// stays inside one process" -- "$plantscale" demo --lcm-url memq:// --out "$work/e"
finish "station and report CLI"
