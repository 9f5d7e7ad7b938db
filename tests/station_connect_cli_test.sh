#!/usr/bin/env bash
# The station over the gateway (issue 58 item 3, docs/remote.md):
#   - bad input exits 2 with one line naming it: a URL that is not wss://,
#     ws:// beyond 127.0.0.1, a token in the URL, no or a missing or open
#     token file, an unreadable CA, a bad --press;
#   - in a private network namespace (unshare -rn, multicast on its
#     loopback), `plantscale gateway` over wss:// (a certificate made here)
#     serves a real-time `simulate --publish` run signed with a command key:
#       * a wrong token is refused at the upgrade: exit 2, one line;
#       * a CA that did not sign the gateway's certificate: exit 2, one line;
#       * gateways serving an expired certificate and one for another name
#         (the expired one warned at its start): exit 2, one line saying
#         "has expired: not valid after DATE" and "is not for address
#         127.0.0.1: it names DNS:...";
#       * a viewer's station gets the run and its command is refused;
#       * an operator's station, through a TCP relay that is stopped for 10 s
#         (SIGSTOP: a silent cut), sends a signed command that the vehicle
#         obeys (its `command` event comes back through the gateway), sees the
#         link go down, reconnects within 5 s of the link's return by itself,
#         and ends with the whole map: every tile at its newest revision, the
#         same as the log's (`station --review`), and a screenshot.
#   (The vehicle runs with --command-key and without
#   --accept-unsigned-commands: its event without "(unverified" is a verified
#   signature.)
# Skips (exit 77) without DISPLAY, openssl, node (the relay) or network
# namespaces.
set -uo pipefail
plantscale="$1"
work="$2"
src="$3"
source "$(dirname "$0")/cli_lib.sh"
rm -rf "$work" && mkdir -p "$work"
[[ -n "${DISPLAY:-}" ]] || { echo "skip: no DISPLAY (run under xvfb-run -a)"; exit 77; }
command -v openssl >/dev/null || { echo "skip: openssl not installed"; exit 77; }
command -v node >/dev/null || { echo "skip: node not installed (the test's TCP relay)"; exit 77; }

users="$work/users.yaml"
"$plantscale" users add vera --role viewer --users "$users" >"$work/add_vera.txt" 2>&1 || fail "users add vera"
"$plantscale" users add otto --role operator --users "$users" >"$work/add_otto.txt" 2>&1 || fail "users add otto"
(umask 077 && tail -n1 "$work/add_vera.txt" >"$work/vera.token" && tail -n1 "$work/add_otto.txt" >"$work/otto.token" \
  && echo 0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef >"$work/wrong.token")
cp "$work/vera.token" "$work/open.token" && chmod 644 "$work/open.token"
"$plantscale" keygen "$work/command.key" >/dev/null 2>&1 || fail "keygen"
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=127.0.0.1 \
  -addext "subjectAltName=IP:127.0.0.1,DNS:localhost" -keyout "$work/key.pem" -out "$work/cert.pem" \
  >"$work/openssl.txt" 2>&1 || { cat "$work/openssl.txt"; fail "openssl req"; }
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=other \
  -keyout "$work/other_key.pem" -out "$work/other_cert.pem" >/dev/null 2>&1
make_bad_certificates "$work"

# Bad input: exit 2 and one line, before any window or connection.
st=("$plantscale" station --offscreen --seconds 1)
tok=(--token-file "$work/vera.token")
expect 2 "--connect http://h:1: must start with wss://" -- "${st[@]}" --connect http://h:1 "${tok[@]}"
expect 2 "plain ws:// only to 127.0.0.1" -- "${st[@]}" --connect ws://10.0.0.7:8765 "${tok[@]}"
expect 2 "the token belongs in --token-file" -- "${st[@]}" --connect "wss://h:1/?token=abc" "${tok[@]}"
expect 2 "port '0' is not|not 1-65535" -- "${st[@]}" --connect wss://h:0 "${tok[@]}"
expect 2 "--token-file: required with --connect" -- "${st[@]}" --connect wss://h:1
expect 2 "--token-file .*/missing.token: cannot read" -- "${st[@]}" --connect wss://h:1 --token-file "$work/missing.token"
expect 2 "open.token: has mode 0644" -- "${st[@]}" --connect wss://h:1 --token-file "$work/open.token"
expect 2 "--ca .*/missing.pem: cannot be read" -- "${st[@]}" --connect wss://h:1 "${tok[@]}" --ca "$work/missing.pem"
expect 2 "--ca .*/users.yaml: not a PEM certificate" -- "${st[@]}" --connect wss://127.0.0.1:1 "${tok[@]}" --ca "$users"
expect 2 "--token-file: only with --connect" -- "${st[@]}" "${tok[@]}"
expect 2 "--press 'C3': expected KEY@SECONDS" -- "${st[@]}" --connect wss://h:1 "${tok[@]}" --press C3

unshare -rn true 2>/dev/null || { echo "skip: cannot create a network namespace (unshare -rn)"; finish station_connect; }

unshare -rn bash -s "$plantscale" "$work" "$src" <<'INNER'
set -uo pipefail
plantscale="$1"; work="$2"; src="$3"
ip link set lo up && ip route add 224.0.0.0/4 dev lo || { echo "skip: no multicast route"; exit 77; }
url="udpm://239.255.76.67:7667?ttl=0"
"$plantscale" gateway --lcm-url "$url" --listen 127.0.0.1:18780 --cert "$work/cert.pem" --key "$work/key.pem" \
  --users "$work/users.yaml" >"$work/gateway.txt" 2>&1 &
gateway=$!
node "$src/relay.mjs" 18781 18780 >"$work/relay.txt" 2>&1 &
relay=$!
for _ in $(seq 100); do grep -q "^gateway: wss://" "$work/gateway.txt" && grep -q "^relay:" "$work/relay.txt" && break; sleep 0.1; done
grep -q "^gateway: wss://127.0.0.1:18780/" "$work/gateway.txt" || { cat "$work/gateway.txt"; kill $gateway $relay; exit 1; }
status=0
st=("$plantscale" station --offscreen --ca "$work/cert.pem")
"${st[@]}" --connect wss://127.0.0.1:18780 --token-file "$work/wrong.token" --seconds 5 >"$work/wrong.txt" 2>&1
echo $? >"$work/wrong.status"
"$plantscale" station --offscreen --ca "$work/other_cert.pem" --connect wss://127.0.0.1:18780 \
  --token-file "$work/vera.token" --seconds 5 >"$work/untrusted.txt" 2>&1
echo $? >"$work/untrusted.status"
# Certificates the station must refuse: expired, and for another name.
for bad in expired:18782 elsewhere:18783; do
  "$plantscale" gateway --lcm-url "$url" --listen 127.0.0.1:${bad#*:} --cert "$work/${bad%:*}_cert.pem" \
    --key "$work/${bad%:*}_key.pem" --users "$work/users.yaml" >"$work/gateway_${bad%:*}.txt" 2>&1 &
  echo $! >"$work/gateway_${bad%:*}.pid"
done
for _ in $(seq 100); do
  grep -q "^gateway: wss://" "$work/gateway_expired.txt" && grep -q "^gateway: wss://" "$work/gateway_elsewhere.txt" && break
  sleep 0.1
done
for bad in expired:18782 elsewhere:18783; do
  "$plantscale" station --offscreen --ca "$work/${bad%:*}_cert.pem" --connect wss://127.0.0.1:${bad#*:} \
    --token-file "$work/vera.token" --seconds 5 >"$work/${bad%:*}.txt" 2>&1
  echo $? >"$work/${bad%:*}.status"
  kill -TERM "$(cat "$work/gateway_${bad%:*}.pid")"; wait "$(cat "$work/gateway_${bad%:*}.pid")"
done
"${st[@]}" --connect wss://127.0.0.1:18780 --token-file "$work/vera.token" --seconds 10 --press C@4 \
  --screenshot "$work/viewer.png" >"$work/viewer.txt" 2>&1 &
viewer=$!
"${st[@]}" --connect wss://127.0.0.1:18781 --token-file "$work/otto.token" --command-key "$work/command.key" \
  --seconds 70 --press W@4 --screenshot "$work/operator.png" >"$work/operator.txt" 2>&1 &
operator=$!  # 70 s: the run is 30 s in real time, longer on a loaded machine, and its end must be seen
sleep 1
"$plantscale" simulate --preset testbed --length-m 9 --seed 3 --publish --lcm-url "$url" \
  --command-key "$work/command.key" --log "$work/run.lcmlog" >"$work/run.txt" 2>&1 &
vehicle=$!
# The link cut for 10 s: the relay's process stopped, then let go.
sleep 9
kill -STOP $relay
date +%s.%N >"$work/cut.time"
sleep 10
kill -CONT $relay
date +%s.%N >"$work/back.time"
wait $vehicle || { echo "FAIL: simulate"; cat "$work/run.txt"; status=1; }
wait $viewer || { echo "FAIL: viewer station exited $?"; status=1; }
wait $operator || { echo "FAIL: operator station exited $?"; status=1; }
kill -TERM $gateway $relay; wait $gateway
exit $status
INNER
inner=$?
[[ $inner -eq 77 ]] && { echo "skip: no multicast route in the namespace"; finish station_connect; }
for f in wrong untrusted expired elsewhere gateway_expired gateway_elsewhere viewer operator gateway; do echo "--- $f"; cat "$work/$f.txt"; done
((inner == 0)) || fail "the namespace run (gateway, relay, stations, simulate) failed"

# A wrong token and an untrusted certificate: exit 2, one line saying so.
[[ "$(cat "$work/wrong.status")" == 2 ]] || fail "a wrong token: exit $(cat "$work/wrong.status"), expected 2"
grep -q "^plantscale: error: station: wss://127.0.0.1:18780: the gateway refused the token (HTTP 401: unknown token" \
  "$work/wrong.txt" || fail "a wrong token: no clear refusal"
[[ "$(cat "$work/untrusted.status")" == 2 ]] || fail "an untrusted certificate: exit $(cat "$work/untrusted.status")"
grep -q "the gateway's certificate is not trusted: self-signed certificate (the gateway's certificate (CN=127.0.0.1); checked against --ca .*other_cert.pem)" "$work/untrusted.txt" \
  || fail "an untrusted certificate: no clear refusal"

# An expired certificate and one for another name: exit 2, one line saying
# which and why; the expired one said so at the gateway's start, and neither
# gateway let a client through.
[[ "$(cat "$work/expired.status")" == 2 ]] || fail "an expired certificate: exit $(cat "$work/expired.status"), expected 2"
grep -q "^plantscale: error: station: wss://127.0.0.1:18782: the gateway's certificate (CN=127.0.0.1) has expired: not valid after 2020-01-02 00:00:00 UTC" \
  "$work/expired.txt" || fail "an expired certificate: no clear refusal"
grep -q "^plantscale: warning: --cert: certificate .*expired_cert.pem expired 2020-01-02 00:00:00 UTC: every client will refuse it" \
  "$work/gateway_expired.txt" || fail "the gateway did not warn at start that its certificate expired"
[[ "$(cat "$work/elsewhere.status")" == 2 ]] || fail "a certificate for another name: exit $(cat "$work/elsewhere.status"), expected 2"
grep -q "^plantscale: error: station: wss://127.0.0.1:18783: the gateway's certificate (CN=vehicle) is not for address 127.0.0.1: it names DNS:vehicle.farm.example" \
  "$work/elsewhere.txt" || fail "a certificate for another name: no clear refusal"
for bad in expired elsewhere; do
  grep -q "^gateway: stopped; 0 connections" "$work/gateway_$bad.txt" || fail "the $bad certificate's gateway let a client through"
done

# The viewer: the run arrived (grid states at >= 2 Hz over its ~8 s), its command refused.
grep -q "station: gateway: .* connected to wss://127.0.0.1:18780 as vera (viewer)" "$work/viewer.txt" \
  || fail "the viewer's station did not say it connected as a viewer"
grep -q "station: command: command spray the crop refused: vera has role viewer" "$work/viewer.txt" \
  || fail "the viewer's command was not refused"
vgrid=$(grep -oE "station: model: [0-9]+ messages, [0-9]+ grid states" "$work/viewer.txt" | awk '{print $5}')
((${vgrid:-0} >= 16)) || fail "the viewer got ${vgrid:-no} grid states in ~8 s (expected >= 16: 2 Hz)"

# The operator: the signed command obeyed by the vehicle (event back through the gateway).
grep -q "station: command: sent to the vehicle through the gateway: spray the weeds" "$work/operator.txt" \
  || fail "the operator's command was not sent"
grep -qE "station: event: command: mode: spray the weeds by station@[^ ]+$" "$work/operator.txt" \
  || fail "the vehicle did not obey the operator's signed command (no command event came back)"
grep -q "forwarded command" "$work/gateway.txt" || grep -q "1 commands forwarded" "$work/gateway.txt" \
  || fail "the gateway did not forward the command"

# The cut: the link seen down, and connected again within 5 s of its return.
grep -q "station: gateway: .* GATEWAY LINK DOWN: link lost" "$work/operator.txt" \
  || fail "the operator's station did not see the link go down"
back=$(cat "$work/back.time")
reconnected_within "$work/operator.txt" "$back" 5.0

# The map caught up: every tile at its newest revision, as in the log.
"$plantscale" station --review "$work/run.lcmlog" --offscreen --seconds 1 >"$work/review.txt" 2>&1 \
  || fail "station --review of the run's log"
tiles() { station_tiles "$1"; }
echo "map: over the gateway $(tiles "$work/operator.txt"), in the log $(tiles "$work/review.txt")"
[[ -n "$(tiles "$work/review.txt")" ]] || fail "the log's review printed no map"
[[ "$(tiles "$work/operator.txt")" == "$(tiles "$work/review.txt")" ]] \
  || fail "the map over the gateway ($(tiles "$work/operator.txt")) differs from the log's ($(tiles "$work/review.txt"))"
for png in viewer operator; do
  size=$(stat -c %s "$work/$png.png" 2>/dev/null || echo 0)
  ((size > 30000)) || fail "$png.png is $size bytes (empty or blank?)"
done
finish station_connect
