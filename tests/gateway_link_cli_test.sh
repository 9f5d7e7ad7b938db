#!/usr/bin/env bash
# The station over a slow, lossy link (issue 58 item 4, docs/remote.md):
# linkem (tests/gateway/linkem.cc) joins two network namespaces by an
# emulated IP link of 1 Mbit/s, 150 ms one-way delay and 2 % random loss in
# each direction (netem's limit of 1000 packets), and cuts it for 10 s
# mid-run (every packet dropped: no FIN, no RST).
#   namespace A (10.77.0.1): `simulate --publish --gateway` (the vehicle with
#     its gateway in-process), LCM multicast on A's loopback only;
#   namespace B (10.77.0.2): `station --connect wss://10.77.0.1:PORT`.
# Asserted, each against the issue's goal:
#   - the station stays <= 1 s behind the vehicle: the 95th percentile of
#     each grid message's reception minus its stamp (the vehicle's camera
#     time; one host clock in both namespaces) <= 1000 ms;
#   - after the cut it reconnects by itself within 5 s of the link's return;
#   - its map catches up: every tile at its newest revision, the same as the
#     log's (`station --review`), and the same plants as the log's;
#   - thumbnails delivered (the fraction of those published) and the bytes
#     per second over the link are printed, and the link stayed below its
#     rate.
# usage: gateway_link_cli_test.sh PLANTSCALE WORK LINKEM
# LINK_LENGTH_M (default 20), LINK_CUT_AT_S (default 12 s after the start;
# "none": no cut) and LINK_SEED (default 7) make the longer runs of
# docs/results/2026-12-07-gateway-link.md.
# Skips (exit 77) without DISPLAY, openssl, network namespaces or TUN.
set -uo pipefail
plantscale="$1"
work="$2"
linkem="$3"
source "$(dirname "$0")/cli_lib.sh"
rm -rf "$work" && mkdir -p "$work"
length_m="${LINK_LENGTH_M:-20}"
cut_at="${LINK_CUT_AT_S:-12}"
seed="${LINK_SEED:-7}"
[[ -n "${DISPLAY:-}" ]] || { echo "skip: no DISPLAY (run under xvfb-run -a)"; exit 77; }
command -v openssl >/dev/null || { echo "skip: openssl not installed"; exit 77; }
unshare -rn true 2>/dev/null || { echo "skip: cannot create a network namespace (unshare -rn)"; exit 77; }
unshare -rn "$linkem" --a true --b true >"$work/probe.txt" 2>&1 \
  || { cat "$work/probe.txt"; echo "skip: linkem cannot make its TUN link here"; exit 77; }

"$plantscale" users add vera --role viewer --users "$work/users.yaml" >"$work/add_vera.txt" 2>&1 || fail "users add"
(umask 077 && tail -n1 "$work/add_vera.txt" >"$work/vera.token")
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=10.77.0.1 \
  -addext "subjectAltName=IP:10.77.0.1" -keyout "$work/key.pem" -out "$work/cert.pem" \
  >"$work/openssl.txt" 2>&1 || { cat "$work/openssl.txt"; fail "openssl req"; finish gateway_link; }

url="udpm://239.255.76.67:7667?ttl=0"
# LINK_BASELINE=1: also a station on the vehicle's own LCM in namespace A
# (no link): its lag is the vehicle's share (camera stamp to publication).
baseline=""
[[ "${LINK_BASELINE:-0}" == 1 ]] && baseline="\"$plantscale\" station --offscreen --lcm-url \"$url\" --seconds 9999 \
  --close-when-quiet 5 >\"$work/baseline.txt\" 2>&1 &"
cat >"$work/a.sh" <<EOF
$baseline
"$plantscale" simulate --preset field --length-m $length_m --seed $seed --publish --lcm-url "$url" \
  --log "$work/run.lcmlog" --gateway 10.77.0.1:18790 --cert "$work/cert.pem" --key "$work/key.pem" \
  --users "$work/users.yaml" >"$work/run.txt" 2>&1
status=\$?
wait
exit \$status
EOF
# The station closes 16 s after its last message (longer than the cut and a
# reconnect) or at a cap well past the run's real time.
cap=$(awk -v l="$length_m" 'BEGIN {printf "%d", l / 0.7 + 120}')
cat >"$work/b.sh" <<EOF
sleep 2
exec "$plantscale" station --offscreen --ca "$work/cert.pem" --connect wss://10.77.0.1:18790 \
  --token-file "$work/vera.token" --seconds $cap --close-when-quiet 16 --screenshot "$work/station.png" \
  >"$work/station.txt" 2>&1
EOF
cut=()
[[ "$cut_at" != none ]] && cut=(--cut-at "$cut_at" --cut-for 10)
unshare -rn "$linkem" --rate 1000000 --delay 0.150 --loss 0.02 --limit 1000 --seed "$seed" "${cut[@]}" \
  --stats "$work/link.json" --a "bash $work/a.sh" --b "bash $work/b.sh" >"$work/linkem.txt" 2>&1
status=$?
for f in linkem run station; do echo "--- $f"; cat "$work/$f.txt"; done
((status == 0)) || fail "linkem exited $status (the vehicle or the station failed, or linkem itself)"
[[ -s "$work/link.json" ]] || { fail "linkem wrote no counters"; finish gateway_link; }

# Behind the vehicle: the grid messages' reception minus their stamps.
lag=$(grep -m1 "^station: lag: " "$work/station.txt")
field() { sed -nE "s/.*$1 ([0-9]+)$2.*/\1/p" <<<"$lag"; }
p50=$(field p50 " ms")
p95=$(field p95 " ms")
grids=$(field grid " messages")
echo "lag: ${grids:-?} grid messages, p50 ${p50:-?} ms, p95 ${p95:-?} ms"
[[ -s "$work/baseline.txt" ]] && echo "baseline, on the vehicle's LCM: $(grep -m1 "^station: lag: " "$work/baseline.txt")"
[[ -n "$p95" ]] || fail "the station printed no lag line"
((${p95:-99999} <= 1000)) || fail "the station was ${p95} ms behind the vehicle at the 95th percentile (> 1000 ms)"
# 12.5 Hz grid states over the run, less the cut's 10 s and the reconnect:
# at least half of them arrive (the gateway keeps the grid at >= 2 Hz).
frames=$(grep -oE "[0-9]+ frames \([0-9]+ dropped\)" "$work/run.txt" | awk '{print $1}')
((${grids:-0} * 2 >= ${frames:-1} - 12 * 16)) || fail "only ${grids:-0} grid states of ${frames:-?} frames arrived"

# Thumbnails delivered and bytes over the link.
sent=$(awk '$1 == "PLANTSCALE_THUMBNAIL" {print $2; exit}' "$work/run.txt")
got=$(field ";" " thumbnails")
bps=$(grep -oE '"a_to_b": \{[^}]*' "$work/link.json" | grep -oE '"bytes_per_s": [0-9.]+' | awk '{print $2}')
awk -v g="${got:-0}" -v s="${sent:-0}" -v b="${bps:-0}" 'BEGIN {
  printf "thumbnails: %d of %d delivered (%.2f); link vehicle->station %.0f bytes/s (%.0f kbit/s of 1000)\n",
    g, s, s ? g / s : 0, b, 8e-3 * b }'
((${sent:-0} > 0 && ${got:-0} > 0)) || fail "no thumbnails published (${sent:-?}) or delivered (${got:-?})"
awk -v b="${bps:-0}" 'BEGIN {exit !(b > 0 && b <= 125000 * 1.01)}' || fail "the link carried ${bps:-?} bytes/s (rate 125000)"

# The cut: connected again within 5 s of the link's return.
if [[ "$cut_at" != none ]]; then
  back=$(grep -oE '"end_unix": [0-9.]+' "$work/link.json" | head -1 | awk '{print $2}')
  [[ -n "$back" ]] || fail "linkem reports no cut"
  grep -q "station: gateway: .* GATEWAY LINK DOWN" "$work/station.txt" || fail "the station did not see the link go down"
  reconnected_within "$work/station.txt" "${back:-0}" 5.0
fi

# The map caught up: every tile at its newest revision and every plant, as in the log.
"$plantscale" station --review "$work/run.lcmlog" --offscreen --seconds 1 >"$work/review.txt" 2>&1 \
  || fail "station --review of the run's log"
tiles() { station_tiles "$1"; }
plants() { grep -oE "station: model: .* [0-9]+ plants" "$1" | grep -oE "[0-9]+ plants"; }
echo "map: over the link $(tiles "$work/station.txt"), $(plants "$work/station.txt"); in the log $(tiles "$work/review.txt"), $(plants "$work/review.txt")"
[[ -n "$(tiles "$work/review.txt")" ]] || fail "the log's review printed no map"
[[ "$(tiles "$work/station.txt")" == "$(tiles "$work/review.txt")" ]] \
  || fail "the map over the link ($(tiles "$work/station.txt")) differs from the log's ($(tiles "$work/review.txt"))"
[[ "$(plants "$work/station.txt")" == "$(plants "$work/review.txt")" ]] \
  || fail "the plants over the link ($(plants "$work/station.txt")) differ from the log's ($(plants "$work/review.txt"))"
size=$(stat -c %s "$work/station.png" 2>/dev/null || echo 0)
((size > 30000)) || fail "station.png is $size bytes (empty or blank?)"
finish gateway_link
