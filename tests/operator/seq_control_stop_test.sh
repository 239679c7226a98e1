#!/usr/bin/env bash
# The operator's control commands and the end of a named private bus, on a real stack
# (configs/deploy/sim.yaml launched as the guide says, on a bus of the test's own):
#   - seq pause, resume and abort with no sequence running say there is nothing to act on
#     and exit 4 (the executor's status says it is idle); on a running sequence pause holds
#     it, resume goes on, abort ends it (exit 0), and then there is nothing to pause again;
#   - ./rover private --name NAME --stop ends every process that joined the bus: none is
#     left in its network namespace.
# usage: seq_control_stop_test.sh ROOT BUILD
set -u
root="$1"
build="$2"
export ROVER_BUILD_DIR="$build" XDG_RUNTIME_DIR="$build/test-out/seq_control_stop"
out="$XDG_RUNTIME_DIR"
rm -rf "$out"
mkdir -p "$out"
rover="$root/rover"
name="s$$"
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; [ -n "${3:-}" ] && cat "$3" 2>/dev/null; fail=1; fi; }
cleanup() { "$rover" private --name "$name" --stop >/dev/null 2>&1; }
trap cleanup EXIT
on_bus() { "$rover" private --name "$name" "$@"; }
seq_cmd() { on_bus "$build/bin/rover_seq" "$@"; }
# Waits (up to $1 s) until the executor's status line matches $2.
wait_state() {
  local end=$((SECONDS + $1))
  while [ "$SECONDS" -lt "$end" ]; do
    seq_cmd status --once >"$out/state.txt" 2>&1 && grep -q "$2" "$out/state.txt" && return 0
    sleep 0.2
  done
  return 1
}
in_ns() {  # the pids in network namespace $1
  local p
  for p in /proc/[0-9]*; do [ "$(readlink "$p/ns/net" 2>/dev/null)" = "$1" ] && echo "${p#/proc/}"; done
}

# The stack, from the build folder: the deployment's path is from the repository root.
(cd "$build" && exec "$rover" private --name "$name" "$rover" launch configs/deploy/sim.yaml) >"$out/launch.txt" 2>&1 &
stack=$!
check "the executor reports (idle) within 90 s" 'wait_state 90 "^\[idle"' "$out/launch.txt"

for sub in pause resume abort; do
  seq_cmd "$sub" >"$out/$sub.txt" 2>&1
  rc=$?
  check "seq $sub with nothing running: exit 4, one line saying so" \
    '[ "$rc" -eq 4 ] && [ "$(wc -l <"$out/$sub.txt")" -eq 1 ] && grep -q "nothing to $sub: the executor is idle" "$out/$sub.txt"' "$out/$sub.txt"
done

# A sequence of many short steps (pauses take effect between steps).
printf 'vo off step 20 cm\nlimit time 3600 s distance 30 m\ndrive 20 m\n' >"$out/long.seq"
seq_cmd submit --no-follow "$out/long.seq" >"$out/submit.txt" 2>&1
check "the sequence runs" 'wait_state 30 "^\[running"' "$out/submit.txt"
seq_cmd pause >"$out/pause_run.txt" 2>&1
check "pause on a running sequence: exit 0" '[ $? -eq 0 ] && grep -q "pause sent" "$out/pause_run.txt"' "$out/pause_run.txt"
check "it pauses between steps" 'wait_state 60 "^\[paused"' "$out/state.txt"
seq_cmd pause >"$out/pause_again.txt" 2>&1
check "pause on a paused sequence: exit 4, already paused" '[ $? -eq 4 ] && grep -q "already paused" "$out/pause_again.txt"' "$out/pause_again.txt"
seq_cmd resume >"$out/resume.txt" 2>&1
check "resume: exit 0, its status shows it running" '[ $? -eq 0 ] && grep -q "^\[running" "$out/resume.txt"' "$out/resume.txt"
seq_cmd abort "test over" >"$out/abort.txt" 2>&1
check "abort: exit 0, its status shows the operator's abort" \
  '[ $? -eq 0 ] && grep -q "^\[aborted.*abort_reason=operator.*test over" "$out/abort.txt"' "$out/abort.txt"
seq_cmd pause >"$out/pause_after.txt" 2>&1
check "pause after the abort: exit 4, naming the last sequence" \
  '[ $? -eq 4 ] && grep -q "nothing to pause: the last sequence, .*long.seq, aborted (operator)" "$out/pause_after.txt"' "$out/pause_after.txt"

# --stop ends every process on the bus: the launcher and the four it started.
ns="$(on_bus readlink /proc/self/ns/net)"
before="$(in_ns "$ns" | wc -l)"
check "the set runs in the bus's namespace ($before processes, the holder with them)" '[ "$before" -ge 6 ]'
"$rover" private --name "$name" --stop >"$out/stop.txt" 2>&1
rc=$?
check "--stop: exit 0, says how many ended" '[ "$rc" -eq 0 ] && grep -q "stopped ([0-9]* processes on it ended)" "$out/stop.txt"' "$out/stop.txt"
left="$(in_ns "$ns" | tr '\n' ' ')"
check "no process is left in the namespace (left: '$left')" '[ -z "$left" ]'
for _ in $(seq 50); do kill -0 "$stack" 2>/dev/null || break; sleep 0.1; done
check "the launch command ended" '! kill -0 "$stack" 2>/dev/null'
exit "$fail"
