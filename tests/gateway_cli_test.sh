#!/usr/bin/env bash
# The gateway (issue 58, docs/remote.md) with real clients:
#   - `users add` prints the token alone on its last line and keeps only a
#     hash in a file of mode 0600; bad input exits 2 naming file and reason;
#   - in a private network namespace (unshare -rn, multicast on its
#     loopback), `plantscale gateway` over wss:// (a certificate made here
#     with openssl req) serves a `simulate --publish` run to npm's
#     @foxglove/ws-protocol client (tests/gateway/client_test.mjs): a wrong
#     token is refused with 401, a client trusting another certificate
#     fails the TLS handshake, and so does one connecting to a gateway
#     whose certificate has expired (CERT_HAS_EXPIRED) or is for another
#     name (ERR_TLS_CERT_ALTNAME_INVALID); a viewer and an operator subscribe to every
#     channel and get each topic, every message valid against its JSON
#     Schema; the viewer's command is refused, the operator's reaches the
#     vehicle (its `command` event comes back through the gateway).
# The npm packages are installed into the build tree (npm ci from
# tests/gateway/package-lock.json). Skips (exit 77) without node/npm, the
# npm registry, openssl or network namespaces.
set -uo pipefail
plantscale="$1"
work="$2"
src="$3"
source "$(dirname "$0")/cli_lib.sh"
rm -rf "$work" && mkdir -p "$work"
command -v node >/dev/null && command -v npm >/dev/null || { echo "skip: node and npm not installed"; exit 77; }
command -v openssl >/dev/null || { echo "skip: openssl not installed"; exit 77; }

# The client's npm packages, once per lock file.
node_dir="$(dirname "$work")/gateway_node"
if ! cmp -s "$src/package-lock.json" "$node_dir/package-lock.json" || [[ ! -d "$node_dir/node_modules" ]]; then
  rm -rf "$node_dir" && mkdir -p "$node_dir"
  cp "$src/package.json" "$src/package-lock.json" "$node_dir/"
  (cd "$node_dir" && npm ci --no-audit --no-fund --loglevel=error) >"$work/npm.txt" 2>&1 \
    || { cat "$work/npm.txt"; rm -rf "$node_dir"; echo "skip: npm ci failed (no registry?)"; exit 77; }
fi
cp "$src/client_test.mjs" "$node_dir/"

# users add: the token alone on the last line, only its hash in the file.
users="$work/users.yaml"
"$plantscale" users add vera --role viewer --users "$users" >"$work/add_vera.txt" 2>&1 || fail "users add vera"
"$plantscale" users add otto --role operator --users "$users" >"$work/add_otto.txt" 2>&1 || fail "users add otto"
viewer_token=$(tail -n1 "$work/add_vera.txt")
operator_token=$(tail -n1 "$work/add_otto.txt")
[[ "$viewer_token" =~ ^[0-9a-f]{64}$ ]] || fail "users add: last line is not a 64-hex token: '$viewer_token'"
[[ "$(stat -c %a "$users")" == 600 ]] || fail "users file mode $(stat -c %a "$users"), expected 600"
grep -q "$viewer_token" "$users" && fail "the token itself is in the users file"
grep -q "role: operator" "$users" || fail "users file lacks otto's role"
expect 2 "user 'vera' exists" -- "$plantscale" users add vera --role viewer --users "$users"
expect 2 "--role: must be viewer or operator" -- "$plantscale" users add x --role admin --users "$users"

# Certificates: the gateway's, and one that does not match its key.
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=127.0.0.1 \
  -addext "subjectAltName=IP:127.0.0.1,DNS:localhost" -keyout "$work/key.pem" -out "$work/cert.pem" \
  >"$work/openssl.txt" 2>&1 || { cat "$work/openssl.txt"; fail "openssl req"; }
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -subj /CN=other \
  -keyout "$work/other_key.pem" -out "$work/other_cert.pem" >/dev/null 2>&1
make_bad_certificates "$work"

# Bad input: exit 2, one line naming the file or option and the reason.
gw=("$plantscale" gateway --lcm-url memq://)
cp "$users" "$work/open.yaml" && chmod 644 "$work/open.yaml"
expect 2 "open.yaml: has mode 0644" -- "${gw[@]}" --cert "$work/cert.pem" --key "$work/key.pem" --users "$work/open.yaml"
expect 2 "missing.yaml: cannot read" -- "${gw[@]}" --cert "$work/cert.pem" --key "$work/key.pem" --users "$work/missing.yaml"
expect 2 "--cert: .*required" -- "${gw[@]}" --users "$users"
expect 2 "--cert: certificate .*nocert.pem" -- "${gw[@]}" --cert "$work/nocert.pem" --key "$work/key.pem" --users "$users"
expect 2 "does not belong to certificate" -- "${gw[@]}" --cert "$work/other_cert.pem" --key "$work/key.pem" --users "$users"
expect 2 "only on 127.0.0.1" -- "${gw[@]}" --insecure-loopback --listen 0.0.0.0:8765 --users "$users"
expect 2 "--listen: 'nowhere'" -- "${gw[@]}" --listen nowhere --cert "$work/cert.pem" --key "$work/key.pem" --users "$users"

unshare -rn true 2>/dev/null || { echo "skip: cannot create a network namespace (unshare -rn)"; finish gateway; }

unshare -rn bash -s "$plantscale" "$work" "$node_dir" "$viewer_token" "$operator_token" <<'INNER'
set -uo pipefail
plantscale="$1"; work="$2"; node_dir="$3"; viewer_token="$4"; operator_token="$5"
ip link set lo up && ip route add 224.0.0.0/4 dev lo || { echo "skip: no multicast route"; exit 77; }
url="udpm://239.255.76.67:7667?ttl=0"
"$plantscale" gateway --lcm-url "$url" --listen 127.0.0.1:18765 --cert "$work/cert.pem" --key "$work/key.pem" \
  --users "$work/users.yaml" >"$work/gateway.txt" 2>&1 &
gateway=$!
for _ in $(seq 100); do grep -q "^gateway: wss://" "$work/gateway.txt" && break; sleep 0.1; done
grep -q "^gateway: wss://127.0.0.1:18765/" "$work/gateway.txt" || { cat "$work/gateway.txt"; kill $gateway; exit 1; }
wss="wss://127.0.0.1:18765/"
client=(node "$node_dir/client_test.mjs")
status=0
"${client[@]}" refused "$wss" "0123wrong" "$work/cert.pem" >"$work/refused.json" 2>&1 || { echo "FAIL: wrong token"; status=1; }
"${client[@]}" untrusted "$wss" "$viewer_token" "$work/other_cert.pem" >"$work/untrusted.json" 2>&1 \
  || { echo "FAIL: a client that does not trust the certificate connected"; status=1; }
# Gateways with an expired certificate and one for another name: the
# client refuses each with the certificate's own error code.
for bad in expired:18769:CERT_HAS_EXPIRED elsewhere:18770:ERR_TLS_CERT_ALTNAME_INVALID; do
  IFS=: read -r name port code <<<"$bad"
  "$plantscale" gateway --lcm-url "$url" --listen 127.0.0.1:$port --cert "$work/${name}_cert.pem" \
    --key "$work/${name}_key.pem" --users "$work/users.yaml" >"$work/gateway_$name.txt" 2>&1 &
  pid=$!
  for _ in $(seq 100); do grep -q "^gateway: wss://" "$work/gateway_$name.txt" && break; sleep 0.1; done
  EXPECT_CODE=$code "${client[@]}" untrusted "wss://127.0.0.1:$port/" "$viewer_token" "$work/${name}_cert.pem" \
    >"$work/$name.json" 2>&1 || { echo "FAIL: the $name certificate was not refused with $code"; status=1; }
  kill -TERM $pid; wait $pid
  grep -q "^gateway: stopped; 0 connections" "$work/gateway_$name.txt" \
    || { echo "FAIL: the $name certificate's gateway let a client through"; status=1; }
done
topics="PLANTSCALE_GRID,PLANTSCALE_GRID/scene,PLANTSCALE_PLANTS,PLANTSCALE_MAP_TILES,PLANTSCALE_THUMBNAIL"
topics+=",PLANTSCALE_EVENTS,PLANTSCALE_HEALTH,PLANTSCALE_NOZZLES,PLANTSCALE_ODOMETRY,PLANTSCALE_SIM_TRUTH"
topics+=",PLANTSCALE_SIM_TRUTH_POSE,PLANTSCALE_GATEWAY_EVENTS"
"${client[@]}" watch "$wss" "$viewer_token" "$work/cert.pem" "$work/viewer.ready" "$topics" command \
  >"$work/viewer.json" 2>&1 &
viewer=$!
"${client[@]}" watch "$wss" "$operator_token" "$work/cert.pem" "$work/operator.ready" "$topics" command \
  >"$work/operator.json" 2>&1 &
operator=$!
for _ in $(seq 200); do [[ -f "$work/viewer.ready" && -f "$work/operator.ready" ]] && break; sleep 0.1; done
"$plantscale" simulate --preset testbed --length-m 6 --seed 3 --publish --lcm-url "$url" \
  --accept-unsigned-commands >"$work/run.txt" 2>&1 || { echo "FAIL: simulate"; cat "$work/run.txt"; status=1; }
wait $viewer || { echo "FAIL: viewer"; status=1; }
wait $operator || { echo "FAIL: operator"; status=1; }
kill -TERM $gateway; wait $gateway || { echo "FAIL: gateway exit"; status=1; }
# One process on a small vehicle computer: simulate --publish --gateway
# serves its own run; a viewer connects once it listens.
"$plantscale" simulate --preset testbed --length-m 6 --seed 3 --publish --lcm-url "$url" \
  --gateway 127.0.0.1:18766 --cert "$work/cert.pem" --key "$work/key.pem" --users "$work/users.yaml" \
  --accept-unsigned-commands >"$work/inproc.txt" 2>&1 &
inproc=$!
for _ in $(seq 100); do grep -q "^gateway: wss://" "$work/inproc.txt" && break; sleep 0.1; done
grep -q "^gateway: wss://127.0.0.1:18766/" "$work/inproc.txt" || { echo "FAIL: no in-process gateway"; status=1; }
"${client[@]}" watch "wss://127.0.0.1:18766/" "$viewer_token" "$work/cert.pem" "$work/inproc.ready" \
  "PLANTSCALE_GRID,PLANTSCALE_HEALTH,PLANTSCALE_THUMBNAIL,PLANTSCALE_GRID/scene" >"$work/inproc.json" 2>&1 \
  || { echo "FAIL: viewer of the in-process gateway"; status=1; }
wait $inproc || { echo "FAIL: simulate --gateway"; cat "$work/inproc.txt"; status=1; }
exit $status
INNER
inner=$?
[[ $inner -eq 77 ]] && { echo "skip: no multicast route in the namespace"; finish gateway; }
for f in refused untrusted expired elsewhere viewer operator; do echo "$f: $(cat "$work/$f.json" 2>/dev/null)" | cut -c1-600; done
cat "$work/gateway.txt"
((inner == 0)) || fail "the namespace run (gateway, clients, simulate) failed"
grep -q '"httpStatus":401' "$work/refused.json" || fail "a wrong token was not refused with 401"
grep -q 'unknown token' "$work/refused.json" || fail "the refusal does not say why"
grep -qE '"errors":\["[A-Z_]*(CERT|SIGNATURE|SELF_SIGNED|UNABLE_TO)' "$work/untrusted.json" \
  || fail "an untrusted certificate did not fail the TLS handshake"
grep -q '"commandRefused":true' "$work/viewer.json" || fail "the viewer's command was not refused"
grep -q '"role":"viewer"' "$work/viewer.json" || fail "the viewer's serverInfo lacks its role"
grep -q '"commandEvent":"mode: spray the crop by foxglove-test@operator' "$work/operator.json" \
  || fail "the operator's command did not reach the vehicle"
grep -q '"invalid":\[\]' "$work/viewer.json" || fail "viewer: messages not valid against their schemas"
grep -q '"invalid":\[\]' "$work/operator.json" || fail "operator: messages not valid against their schemas"
grep -qE "gateway: stopped; 2 connections, [1-9][0-9]* refused" "$work/gateway.txt" || fail "gateway summary: connections/refused"
grep -q "1 commands forwarded, 2 refused" "$work/gateway.txt" || fail "gateway summary: commands"
grep -q '"invalid":\[\]' "$work/inproc.json" || fail "in-process gateway: messages missing or invalid"
grep -qE "^gateway: stopped; 1 connections, 0 refused .* [1-9][0-9]* LCM messages" "$work/inproc.txt" \
  || fail "in-process gateway summary"
expect 2 "--gateway: needs a udpm:// LCM URL" -- "$plantscale" simulate --preset testbed --length-m 1 \
  --publish --lcm-url memq:// --gateway 127.0.0.1:18767 --cert "$work/cert.pem" --key "$work/key.pem" \
  --users "$users"
expect 2 "--gateway: only with --publish" -- "$plantscale" simulate --preset testbed --length-m 1 \
  --out "$work/noout" --gateway 127.0.0.1:18768
expect 2 "--cert/--key/--users: only with --gateway" -- "$plantscale" simulate --preset testbed \
  --length-m 1 --publish --lcm-url memq:// --users "$users"
finish gateway
