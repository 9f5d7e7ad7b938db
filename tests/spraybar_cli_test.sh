#!/usr/bin/env bash
# Command-line contract of --can IFACE (issue 6, telemetry/can): the spray
# bar is opened before anything else, and an interface that cannot be opened
# ends `plantscale run` and `plantscale simulate --publish` with exit 1 and a
# message naming the interface, the call and the errno text, before any
# telemetry is published or logged. This machine's kernel has no SocketCAN;
# the interface names used here never exist, so the expectations hold on a
# kernel with SocketCAN too.
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"

missing="cannot open CAN interface 'nocanbus9': .*no such network interface \(No such device"
expect 1 "$missing" -- "$plantscale" simulate --preset testbed --length-m 2 --publish \
  --lcm-url memq:// --log "$work/sim.lcmlog" --can nocanbus9
[[ -e "$work/sim.lcmlog" ]] && fail "simulate wrote a log although the spray bar could not be opened"
mkdir -p "$work/empty"
expect 1 "$missing" -- "$plantscale" run --camera "$work/empty" --lcm-url memq:// \
  --log "$work/run.lcmlog" --can nocanbus9
[[ -e "$work/run.lcmlog" ]] && fail "run wrote a log although the spray bar could not be opened"

# `lo` exists everywhere and is not a CAN interface: without SocketCAN the
# socket call fails (this machine), with it the bind does.
expect 1 "cannot open CAN interface 'lo': (socket\(PF_CAN, SOCK_RAW, CAN_RAW\): Address family not supported by protocol \(this kernel has no SocketCAN|bind: )" \
  -- "$plantscale" simulate --preset testbed --length-m 2 --publish --lcm-url memq:// --can lo
if python3 -c 'import socket,sys; socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)' 2>/dev/null; then
  echo "skip: this kernel has SocketCAN (no EAFNOSUPPORT case)"
else
  expect 1 "socket\(PF_CAN, SOCK_RAW, CAN_RAW\): Address family not supported by protocol" \
    -- "$plantscale" run --camera "$work/empty" --lcm-url memq:// --can lo
fi

expect 1 "cannot open CAN interface 'a_very_long_can_name0': name longer than 15 characters" \
  -- "$plantscale" simulate --preset testbed --publish --lcm-url memq:// --can a_very_long_can_name0
expect 2 "--can: not with --fast" -- "$plantscale" simulate --preset testbed --publish --fast \
  --lcm-url memq:// --can nocanbus9
expect 2 "--can: only with --publish" -- "$plantscale" simulate --preset testbed --out "$work/x" \
  --can nocanbus9
[[ -e "$work/x" ]] && fail "simulate wrote output with a bad --can"

# The whole vehicle path with the bar played in process over a socketpair
# (same codec and SprayBar as on SocketCAN): the treatment scheduler drives
# the bar at 200 Hz (four ticks per 50 Hz odometry sample), two command
# frames per tick (the 64-nozzle bar has two sections), sixteen ticks per
# 12.5 Hz frame; every
# command but those of the last frame is acknowledged, heartbeats arrive,
# nothing is malformed, the bar opened nozzles, and it is out of fail-safe
# at the end.
out=$("$plantscale" simulate --preset testbed --length-m 2 --publish --fast --lcm-url memq:// \
  --can simulated 2>&1)
status=$?
[[ $status -eq 0 ]] || fail "simulate --can simulated exited $status"
line=$(grep -E "^  spray bar +simulated: " <<<"$out")
read -r commands acks heartbeats rejected gaps < <(sed -E \
  's/.*: ([0-9]+) commands, ([0-9]+) acks, ([0-9]+) heartbeats, ([0-9]+) frames rejected, ([0-9]+) sequence gaps.*/\1 \2 \3 \4 \5/' <<<"$line")
read -r received changes bad < <(grep -E "^  simulated bar " <<<"$out" | sed -E \
  's/.* ([0-9]+) commands received, ([0-9]+) valve changes, ([0-9]+) bad frames.*/\1 \2 \3/')
frames=$(grep -oE "[0-9]+ frames \(" <<<"$out" | grep -oE "^[0-9]+")
if [[ -z "${commands:-}" || -z "${frames:-}" || -z "${received:-}" ]]; then
  fail "no spray bar summary in: $out"
else
  [[ $((commands % 2)) -eq 0 && $commands -ge $((32 * (frames - 1))) && $commands -le $((32 * (frames + 1))) ]] ||
    fail "spray bar: $commands commands for $frames frames (expected 32 per frame)"
  [[ $acks -le $commands && $acks -ge $((commands - 64)) ]] || fail "spray bar: $acks acks for $commands commands"
  [[ $heartbeats -ge $((frames - 1)) ]] || fail "spray bar: $heartbeats heartbeats over $frames frames"
  [[ $rejected -eq 0 && $gaps -eq 0 ]] || fail "spray bar: $rejected rejected, $gaps gaps"
  grep -q "fail-safe" <<<"$line" && fail "spray bar fail-safe at the end: $line"
  [[ $received -eq $commands && $bad -eq 0 ]] || fail "simulated bar received $received of $commands, $bad bad"
  [[ $changes -gt 0 ]] || fail "the treatment scheduler never opened a nozzle through the bar"
  echo "ok: simulated bar: $commands commands, $acks acks, $heartbeats heartbeats, $changes valve changes over $frames frames"
fi
expect 2 "--can: 'simulated' only with simulate --publish" -- "$plantscale" run --camera "$work/empty" \
  --lcm-url memq:// --can simulated

# The diagnostic command: the same error for a missing interface; on the
# simulated bar, a walking test pattern in real time, every command
# acknowledged and the bar healthy at the end.
expect 1 "$missing" -- "$plantscale" spraybar --can nocanbus9 --seconds 0.2
expect 2 "num_nozzles: must be in \[1, 64\] \(got 65\)" -- "$plantscale" spraybar --can simulated --nozzles 65
json=$("$plantscale" spraybar --can simulated --nozzles 4 --seconds 0.6 --test-pattern --json)
status=$?
[[ $status -eq 0 ]] || fail "spraybar --can simulated exited $status: $json"
for key in interface nozzles commands acks heartbeats frames_rejected sequence_gaps failsafe reasons \
  nozzle_faults; do
  grep -q "\"$key\"" <<<"$json" || fail "spraybar --json lacks $key"
done
python3 - "$json" <<'PY' || fail "spraybar --json values"
import json, sys
j = json.loads(sys.argv[1])
assert j["commands"] == 30, j            # 0.6 s at 50 Hz
assert j["acks"] == j["commands"], j
assert j["heartbeats"] >= 6, j           # 20 Hz bar, allowing for a loaded machine
assert j["frames_rejected"] == 0 and j["sequence_gaps"] == 0, j
assert j["failsafe"] is False and j["reasons"] == [], j
assert j["nozzle_faults"] == ["ok"] * 4, j
print("ok: spraybar simulated:", j["commands"], "commands,", j["heartbeats"], "heartbeats")
PY

finish "spraybar CLI"
