#!/usr/bin/env bash
# The gateway's cost (issue 58's goal: 10 viewers and 1 operator at once,
# gateway <= 15 % of one core, the vehicle unaffected). Not a ctest: a
# measurement for docs/results, run by hand after the cli.gateway test has
# installed the npm client:
#   bash tests/gateway/load.sh build/app/plantscale /tmp/gateway_load build/tests/gateway_node [VIEWERS]
# In a private network namespace: a 6 m testbed run (20 s, real time) alone,
# then the same run behind `plantscale gateway` with VIEWERS (default 10)
# viewers and one operator subscribed to every channel. Prints the CPU
# seconds (user + system) of the vehicle in both runs and of the gateway
# during the served run (from /proc/PID/stat).
set -euo pipefail
plantscale="$1"; work="$2"; node_dir="$3"; viewers="${4:-10}"
rm -rf "$work" && mkdir -p "$work"
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=127.0.0.1 \
  -addext "subjectAltName=IP:127.0.0.1" -keyout "$work/key.pem" -out "$work/cert.pem" >/dev/null 2>&1
"$plantscale" users add viewer --role viewer --users "$work/users.yaml" | tail -n1 >"$work/viewer.token"
"$plantscale" users add operator --role operator --users "$work/users.yaml" | tail -n1 >"$work/operator.token"
unshare -rn bash -s "$plantscale" "$work" "$node_dir" "$viewers" <<'INNER'
set -euo pipefail
plantscale="$1"; work="$2"; node_dir="$3"; viewers="$4"
ip link set lo up && ip route add 224.0.0.0/4 dev lo
url="udpm://239.255.76.67:7667?ttl=0"
run() { /usr/bin/time -f "%U %S %e" -o "$1" "$plantscale" simulate --preset testbed --length-m 6 --seed 3 \
  --publish --lcm-url "$url" >"$1.out" 2>&1; }
run "$work/alone.time"
"$plantscale" gateway --lcm-url "$url" \
  --listen 127.0.0.1:18765 --cert "$work/cert.pem" --key "$work/key.pem" --users "$work/users.yaml" \
  >"$work/gateway.txt" 2>&1 &
gateway=$!
sleep 1
topics="PLANTSCALE_GRID,PLANTSCALE_PLANTS,PLANTSCALE_MAP_TILES,PLANTSCALE_THUMBNAIL,PLANTSCALE_HEALTH"
clients=()
for i in $(seq "$viewers"); do
  WATCH_FOR_S=26 node "$node_dir/client_test.mjs" watch wss://127.0.0.1:18765/ "$(cat "$work/viewer.token")" \
    "$work/cert.pem" "$work/ready.$i" "$topics" >"$work/viewer.$i.json" 2>&1 &
  clients+=($!)
done
WATCH_FOR_S=26 node "$node_dir/client_test.mjs" watch wss://127.0.0.1:18765/ "$(cat "$work/operator.token")" \
  "$work/cert.pem" "$work/ready.op" "$topics" >"$work/operator.json" 2>&1 &
clients+=($!)
for _ in $(seq 300); do (( $(ls "$work"/ready.* 2>/dev/null | wc -l) == viewers + 1 )) && break; sleep 0.1; done
ticks() { awk '{ print $14 + $15 }' "/proc/$gateway/stat"; }
before=$(ticks)
start=$(date +%s.%N)
run "$work/served.time"
echo "$(( $(ticks) - before )) $(getconf CLK_TCK) $(echo "$(date +%s.%N) - $start" | bc)" >"$work/gateway.ticks"
for c in "${clients[@]}"; do wait "$c" || echo "a client failed: see $work/*.json"; done
kill -TERM $gateway; wait $gateway || true
INNER
cpu() { awk '{ printf "%.2f s CPU (%.2f user + %.2f system) over %.1f s wall", $1 + $2, $1, $2, $3 }' "$1"; }
echo "vehicle alone:               $(cpu "$work/alone.time")"
echo "vehicle with $viewers viewers + 1 operator: $(cpu "$work/served.time")"
echo "gateway during the run:      $(awk '{ printf "%.2f s CPU over %.1f s wall: %.1f %% of one core", $1 / $2, $3, 100 * $1 / $2 / $3 }' "$work/gateway.ticks")"
grep "^gateway: stopped" "$work/gateway.txt"
echo "client received bytes: $(grep -ho '"bytes":[0-9]*' "$work"/viewer.1.json "$work"/operator.json | tr '\n' ' ')"
