#!/usr/bin/env bash
# The station live over real udpm:// (issue 9), inside a private network
# namespace (unshare -rn) with a multicast route on its loopback: the vehicle
# (`simulate --publish`, real time) publishes, the station subscribes
# off-screen, closes 3 s after the last message and must then say that the
# run finished (the vehicle's run_finished event: quiet, not a lost link); then `demo-system` (vehicle, station, log, report) on the same
# bus writes its report. Skips (77) without DISPLAY or network namespaces.
set -uo pipefail
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
[[ -n "${DISPLAY:-}" ]] || { echo "skip: no DISPLAY (run under xvfb-run -a)"; exit 77; }
unshare -rn true 2>/dev/null || { echo "skip: cannot create a network namespace (unshare -rn)"; exit 77; }

unshare -rn bash -s "$plantscale" "$work" <<'INNER'
set -uo pipefail
plantscale="$1"; work="$2"
ip link set lo up && ip route add 224.0.0.0/4 dev lo || { echo "skip: no multicast route in the namespace"; exit 77; }
url="udpm://239.255.76.67:7667?ttl=0"
"$plantscale" station --lcm-url "$url" --offscreen --close-when-quiet 3 --seconds 60 >"$work/station.txt" 2>&1 &
station=$!
sleep 1
"$plantscale" simulate --preset testbed --length-m 1 --seed 2 --publish --lcm-url "$url" \
  --log "$work/run.lcmlog" >"$work/vehicle.txt" 2>&1 || { cat "$work/vehicle.txt"; exit 1; }
wait "$station" || { echo "FAIL: station exited $?"; cat "$work/station.txt"; exit 1; }
"$plantscale" demo-system --preset testbed --length-m 2 --out "$work/demo" --lcm-url "$url" >"$work/demo.txt" 2>&1 \
  || { echo "FAIL: demo-system exited $?"; cat "$work/demo.txt"; exit 1; }
INNER
status=$?
[[ $status -eq 0 ]] || exit $status
cat "$work/station.txt"
grep -qE "station: [1-9][0-9]* frames" "$work/station.txt" || { echo "FAIL: station rendered nothing"; exit 1; }
grep -q "station: link: run finished after [1-9][0-9]* frames; last heartbeat" "$work/station.txt" \
  || { echo "FAIL: the run's end not reported"; exit 1; }
if grep -q "LINK LOST" "$work/station.txt"; then echo "FAIL: a finished run reported as a lost link"; exit 1; fi
echo "ok: station live over udpm, the run's end reported after the vehicle stopped"
cat "$work/demo.txt"
grep -q "<th>distance</th><td>[12]\.[0-9][0-9] m</td>" "$work/demo/report/index.html" \
  || { echo "FAIL: demo-system report lacks the ~2 m distance"; exit 1; }
echo "ok: demo-system wrote its report"
grep -q "demo: archive .*archive.gpkg" "$work/demo.txt" || { echo "FAIL: demo-system did not archive its run"; exit 1; }
"$plantscale" archive query --to "$work/demo/archive.gpkg" --field demo | grep -q "field 'demo': 1 run(s)" \
  || { echo "FAIL: the demo's archive lacks its run"; exit 1; }
echo "ok: demo-system archived its run"
