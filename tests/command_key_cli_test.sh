#!/usr/bin/env bash
# Signed station commands on the command line: `keygen` writes a 0600 key
# and never overwrites one; a key file readable by others stops the vehicle
# and the station at start (exit 2, naming the file and its mode); a vehicle
# without a key says it refuses every command; --accept-unsigned-commands
# warns. All over memq:// (no network, no display needed).
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"

key="$work/station.key"
expect 0 "keygen: .*station.key .*mode 0600" -- "$plantscale" keygen "$key"
[[ $(stat -c %a "$key") == 600 ]] || fail "keygen wrote mode $(stat -c %a "$key"), expected 600"
grep -qE '^[0-9a-f]{64}$' "$key" || fail "keygen did not write 64 hex digits"
before=$(cat "$key")
expect 1 "command key file .*station.key already exists: keygen never overwrites" -- "$plantscale" keygen "$key"
[[ $(cat "$key") == "$before" ]] || fail "keygen overwrote an existing key"
expect 2 "FILE is required" -- "$plantscale" keygen

sim=(simulate --preset testbed --length-m 0.5 --seed 2 --publish --fast --lcm-url memq://)
cp "$key" "$work/open.key" && chmod 644 "$work/open.key"
expect 2 "--command-key: command key file .*open.key has mode 0644: .*chmod 600" -- \
  "$plantscale" "${sim[@]}" --command-key "$work/open.key"
chmod 640 "$work/open.key"
expect 2 "--command-key: command key file .*open.key has mode 0640" -- \
  "$plantscale" station --lcm-url memq:// --command-key "$work/open.key" --offscreen --seconds 1
expect 2 "--command-key: command key file .*absent.key: cannot open" -- \
  "$plantscale" run --camera "$work" --command-key "$work/absent.key"

expect 0 "no --command-key: every station command will be refused" -- "$plantscale" "${sim[@]}"
expect 0 "warning: --accept-unsigned-commands" -- "$plantscale" "${sim[@]}" --accept-unsigned-commands
output=$("$plantscale" "${sim[@]}" --command-key "$key" 2>&1) || fail "simulate --publish with a good key: $output"
grep -q "every station command will be refused\|warning" <<<"$output" && fail "a keyed vehicle warned: $output"
expect 0 "--accept-unsigned-commands" -- "$plantscale" simulate --help
expect 0 "--command-key" -- "$plantscale" station --help

finish "command key CLI"
