#!/usr/bin/env bash
# One run over real udpm:// multicast, inside a private network namespace
# (unshare -rn) with the multicast route on its loopback, so it needs no
# root and touches no real network. The vehicle (`simulate --publish --fast
# --log`) and LCM's own lcm-logger listening on udpm must hold the same
# messages per channel: nothing lost on loopback, and our log equals what
# lcm-logger records. Skips (exit 77) when namespaces or lcm-logger are
# unavailable. With a third argument (the telemetry test binary) it also runs
# that binary's udpm:// transport test in the namespace.
set -uo pipefail
plantscale="$1"
work="$2"
telemetry_test="${3:-}"
rm -rf "$work" && mkdir -p "$work"
command -v lcm-logger >/dev/null || { echo "skip: lcm-logger not installed (liblcm-bin)"; exit 77; }
unshare -rn true 2>/dev/null || { echo "skip: cannot create a network namespace (unshare -rn)"; exit 77; }

unshare -rn bash -s "$plantscale" "$work" "$telemetry_test" <<'INNER'
set -uo pipefail
plantscale="$1"; work="$2"; telemetry_test="$3"
ip link set lo up && ip route add 224.0.0.0/4 dev lo || { echo "skip: no multicast route in the namespace"; exit 77; }
url="udpm://239.255.76.67:7667?ttl=0"
if [[ -n "$telemetry_test" ]]; then
  PLANTSCALE_TEST_UDPM_URL="udpm://239.255.76.67:7669?ttl=0" "$telemetry_test" \
    --gtest_filter='LcmTransport.ABurstWaitingToBeHandledIsKeptWhole' >"$work/transport_test.txt" 2>&1 \
    || { cat "$work/transport_test.txt"; exit 1; }
  grep -q '\[       OK \] LcmTransport.ABurst' "$work/transport_test.txt" \
    || { echo "FAIL: the udpm transport test did not run"; cat "$work/transport_test.txt"; exit 1; }
fi
LCM_DEFAULT_URL="$url" lcm-logger -f -q "$work/logger.lcmlog" &
logger=$!
sleep 0.5
"$plantscale" simulate --preset testbed --length-m 4 --seed 2 --publish --fast --lcm-url "$url" \
  --log "$work/own.lcmlog" >"$work/run.txt" 2>&1 || { cat "$work/run.txt"; exit 1; }
sleep 0.5
kill -INT "$logger"; wait "$logger"
INNER
status=$?
[[ $status -eq 0 ]] || exit $status

counts() { "$plantscale" telemetry-stats "$1" | awk 'NR > 1 && $1 ~ /^PLANTSCALE_/ { print $1, $2 }'; }
counts "$work/own.lcmlog" >"$work/own.txt"
counts "$work/logger.lcmlog" >"$work/logger.txt"
cat "$work/own.txt"
[[ -s "$work/own.txt" ]] || { echo "FAIL: nothing published"; exit 1; }
if ! diff "$work/own.txt" "$work/logger.txt"; then
  echo "FAIL: lcm-logger over udpm received different counts than the vehicle published"; exit 1
fi
echo "ok: lcm-logger over udpm received every message the vehicle published"
