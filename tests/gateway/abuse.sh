#!/usr/bin/env bash
# The gateway under a flood of bad connection attempts (issue 58's goal:
# "1,000 connection attempts a second ... nothing crashes, the run goes
# on"). Not a ctest (it needs a few minutes of both cores): a measurement
# for docs/results/2026-12-07-gateway-abuse.md, run by hand after the
# cli.gateway test has installed the npm client:
#   bash tests/gateway/abuse.sh build/app/plantscale /tmp/gateway_abuse build/tests/gateway_node [RATE] [SECONDS]
# In a private network namespace (unshare -rn, multicast on its loopback):
# `plantscale gateway` over wss:// (self-signed P-256 certificate) serving a
# real-time testbed run (`simulate --publish`), one viewer subscribed, then
# tests/gateway/abuse.mjs: RATE (default 1000) bad attempts a second for
# SECONDS (default 10) from 127.0.0.2, a second viewer connecting from
# 127.0.0.1 in the middle. Prints abuse.mjs's JSON and the gateway's summary;
# exits 1 when abuse.mjs found a problem or the gateway did not stop cleanly.
set -uo pipefail
plantscale="$1"; work="$2"; node_dir="$3"; rate="${4:-1000}"; seconds="${5:-10}"
here="$(cd "$(dirname "$0")" && pwd)"
rm -rf "$work" && mkdir -p "$work"
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=127.0.0.1 \
  -addext "subjectAltName=IP:127.0.0.1" -keyout "$work/key.pem" -out "$work/cert.pem" >/dev/null 2>&1
"$plantscale" users add viewer --role viewer --users "$work/users.yaml" | tail -n1 >"$work/viewer.token"
cp "$here/abuse.mjs" "$node_dir/"
unshare -rn bash -s "$plantscale" "$work" "$node_dir" "$rate" "$seconds" <<'INNER'
set -uo pipefail
plantscale="$1"; work="$2"; node_dir="$3"; rate="$4"; seconds="$5"
ip link set lo up && ip route add 224.0.0.0/4 dev lo
url="udpm://239.255.76.67:7667?ttl=0"
"$plantscale" gateway --lcm-url "$url" --listen 127.0.0.1:18765 --cert "$work/cert.pem" --key "$work/key.pem" \
  --users "$work/users.yaml" >"$work/gateway.txt" 2>&1 &
gateway=$!
for _ in $(seq 300); do grep -q "^gateway: wss://" "$work/gateway.txt" && break; sleep 0.1; done
"$plantscale" simulate --preset testbed --length-m 24 --seed 3 --publish --lcm-url "$url" >"$work/run.txt" 2>&1 &
vehicle=$!  # 24 m: about 80 s in real time, longer than the measurement
status=0
(cd "$node_dir" && node abuse.mjs 127.0.0.1 18765 "$(cat "$work/viewer.token")" "$work/cert.pem" $gateway "$rate" \
  "$seconds") >"$work/abuse.json" 2>"$work/abuse.err" || status=1
kill -TERM $vehicle 2>/dev/null; wait $vehicle
kill -TERM $gateway && wait $gateway || { echo "the gateway did not stop cleanly (exit $?)"; status=1; }
exit $status
INNER
status=$?
cat "$work/abuse.json" "$work/abuse.err"
grep "^gateway: stopped" "$work/gateway.txt"
exit $status
