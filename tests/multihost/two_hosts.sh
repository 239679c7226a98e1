#!/usr/bin/env bash
# A real sequence across two "hosts": two network namespaces joined by a veth pair, each
# with its own address (10.99.0.1/24, 10.99.0.2/24) and the multicast route 224.0.0.0/4 on
# its veth end, as a rover computer has on its LAN interface. Each host starts its share
# of configs/deploy/sim_vo_two_hosts.yaml with the real launcher (`launcher DEPLOYMENT
# --host NAME`): "rover" the simulated rover, cameras, VO, estimator and hazard monitor,
# "ground" the sequence executor.
#
#   two_hosts.sh SOURCE_DIR BUILD_DIR ttl1   the operator on "ground" submits a drive: it
#                                            completes on "rover" (every drive command and
#                                            the executor's heartbeat cross the veth), and
#                                            a status asked on "rover" is answered from "ground"
#   two_hosts.sh SOURCE_DIR BUILD_DIR ttl0   the same split on a ttl=0 bus: a submit from
#                                            "rover" reaches no executor and says so within
#                                            a few seconds, naming the likely causes
#
# Nothing leaves the machine: the script runs itself in a user + network namespace of its
# own (unshare -rn; also inside ./rover test's), and the two hosts are namespaces inside
# that, connected only to each other.
set -uo pipefail

SRC="${1:?usage: two_hosts.sh SOURCE_DIR BUILD_DIR ttl1|ttl0}"
BUILD="${2:?usage: two_hosts.sh SOURCE_DIR BUILD_DIR ttl1|ttl0}"
MODE="${3:?usage: two_hosts.sh SOURCE_DIR BUILD_DIR ttl1|ttl0}"
case "$MODE" in ttl1|ttl0) ;; *) echo "two_hosts.sh: mode '$MODE': expected ttl1 or ttl0" >&2; exit 2 ;; esac

if [ "${ROVER_MULTIHOST_INNER:-}" != 1 ]; then
  command -v unshare >/dev/null && command -v nsenter >/dev/null && command -v ip >/dev/null ||
    { echo "SKIP: needs unshare, nsenter (util-linux) and ip (iproute2)"; exit 77; }
  unshare -rn true 2>/dev/null || { echo "SKIP: cannot create a user + network namespace here"; exit 77; }
  ROVER_MULTIHOST_INNER=1 exec unshare -rn bash "$0" "$@"
fi

BUILD="$(cd "$BUILD" && pwd)" || exit 2
BIN="$BUILD/bin"
DEPLOY="configs/deploy/sim_vo_two_hosts.yaml"
OUT="$BUILD/test-out/multihost_$MODE"
rm -rf "$OUT" && mkdir -p "$OUT"
URL='udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608'
[ "$MODE" = ttl0 ] && URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608'
cd "$SRC" || exit 2

fail() { echo "FAIL: $*"; exit 1; }
pids=()
cleanup() {
  # The launchers first (SIGTERM: they stop their processes cleanly), then the namespace holders.
  for p in "${launchers[@]:-}"; do [ -n "$p" ] && kill -TERM "$p" 2>/dev/null; done
  for p in "${launchers[@]:-}"; do [ -n "$p" ] && wait "$p" 2>/dev/null; done
  for p in "${pids[@]:-}"; do [ -n "$p" ] && kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null
}
launchers=()
trap cleanup EXIT

# Two hosts: each a network namespace held open by a sleeping process. Nothing here
# outlives the test by long, even if it is killed: the holders sleep 150 s, the launchers
# are stopped by `timeout` after 120 s (their processes die with them, PR_SET_PDEATHSIG).
unshare -n sleep 150 & ROVER_NS=$!; pids+=("$ROVER_NS")
unshare -n sleep 150 & GROUND_NS=$!; pids+=("$GROUND_NS")
for _ in $(seq 50); do
  [ "$(readlink /proc/$ROVER_NS/ns/net)" != "$(readlink /proc/self/ns/net)" ] &&
    [ "$(readlink /proc/$GROUND_NS/ns/net)" != "$(readlink /proc/self/ns/net)" ] && break
  sleep 0.1
done
# A kernel without veth cannot run this test at all: a skip, said, not a failure.
ip link add vrover type veth peer name vground || { echo "SKIP: cannot create a veth pair here (kernel veth support?)"; exit 77; }
ip link set vrover netns "$ROVER_NS" && ip link set vground netns "$GROUND_NS" || fail "cannot move the veth ends"
on() { local pid="$1"; shift; nsenter -t "$pid" -n "$@"; }
# Background starts call nsenter directly, not `on`: a function run with & is a subshell,
# and $! would be that subshell, whose death leaves the launcher running.
host_setup() {  # PID IFACE ADDRESS
  on "$1" ip link set lo up &&
    on "$1" ip addr add "$3" dev "$2" &&
    on "$1" ip link set "$2" up &&
    on "$1" ip route add 224.0.0.0/4 dev "$2"
}
host_setup "$ROVER_NS" vrover 10.99.0.1/24 || fail "cannot set up host rover"
host_setup "$GROUND_NS" vground 10.99.0.2/24 || fail "cannot set up host ground"
echo "host rover:  $(on "$ROVER_NS" ip -brief addr show vrover); $(on "$ROVER_NS" ip route show 224.0.0.0/4)"
echo "host ground: $(on "$GROUND_NS" ip -brief addr show vground); $(on "$GROUND_NS" ip route show 224.0.0.0/4)"

# Each host starts its share of the deployment with the real launcher.
nsenter -t "$ROVER_NS" -n timeout 120 "$BIN/launcher" "$DEPLOY" --host rover --lcm-url "$URL" > "$OUT/rover.log" 2>&1 &
launchers+=($!)
nsenter -t "$GROUND_NS" -n timeout 120 "$BIN/launcher" "$DEPLOY" --host ground --lcm-url "$URL" > "$OUT/ground.log" 2>&1 &
launchers+=($!)

# Ready when each host hears the heartbeats it should: with ttl=1 every process of both
# hosts from both; with ttl=0 the executor on "ground" (so that the negative case fails for
# the bus, not because the executor had not started yet).
rover_procs="rover_sim camera_capture visual_odometry state_estimator hazard_monitor"
ground_procs="sequence_executor"
heard() {  # PID PROCESS...: every PROCESS's heartbeat is heard (not SILENT) from host PID
  local pid="$1" screen p; shift
  screen="$(on "$pid" "$BIN/rover_console" --once --wait 1.5 --lcm-url "$URL" 2>&1)" || return 1
  for p in "$@"; do
    echo "$screen" | grep -E "^ +$p +" | grep -vq SILENT || return 1
  done
}
if [ "$MODE" = ttl1 ]; then
  want_rover="$rover_procs $ground_procs"; want_ground="$rover_procs $ground_procs"
else
  want_rover=""; want_ground="$ground_procs"
fi
ready=0
for _ in $(seq 20); do
  for p in "${launchers[@]}"; do kill -0 "$p" 2>/dev/null || fail "a launcher exited early: $(tail -n 5 "$OUT"/*.log)"; done
  # Both hosts listen at once (each listen takes 1.5 s).
  # shellcheck disable=SC2086
  { [ -z "$want_rover" ] || heard "$ROVER_NS" $want_rover; } & r=$!
  # shellcheck disable=SC2086
  heard "$GROUND_NS" $want_ground; g=$?
  wait "$r" && [ "$g" -eq 0 ] && { ready=1; break; }
done
[ "$ready" -eq 1 ] || fail "not every process was heard where expected within 40 s ($(on "$GROUND_NS" "$BIN/rover_console" --once --lcm-url "$URL" 2>&1 | tail -n 8))"
echo "ready: rover hears [${want_rover:-(not waited for)}], ground hears [$want_ground]"

launcher_ok() {  # no process died on either host
  ! grep -h "unexpectedly" "$OUT/rover.log" "$OUT/ground.log" || fail "a process died (above)"
}

if [ "$MODE" = ttl1 ]; then
  # Host rover records its bus meanwhile: what it heard from host ground.
  nsenter -t "$ROVER_NS" -n timeout 120 "$BIN/rover_recorder" --lcm-url "$URL" "$OUT/rover.lcm" > "$OUT/recorder.log" 2>&1 &
  recorder=$!
  launchers+=("$recorder")
  for _ in $(seq 100); do [ -s "$OUT/rover.lcm" ] && break; sleep 0.1; done
  [ -s "$OUT/rover.lcm" ] || fail "rover_recorder on host rover recorded nothing within 10 s"
  SEQ="$OUT/two_hosts.seq"
  printf 'vo off step 50 cm\ndrive 1 m\nturn 20 deg\n' > "$SEQ"
  on "$GROUND_NS" timeout 45 "$BIN/rover_seq" submit "$SEQ" --lcm-url "$URL" > "$OUT/submit.log" 2>&1
  rc=$?
  sed 's/^/  submit| /' "$OUT/submit.log"
  # The operator on the rover asks too: the answer comes from the executor on "ground".
  on "$ROVER_NS" timeout 10 "$BIN/rover_seq" status --once --lcm-url "$URL" > "$OUT/status.log" 2>&1
  src=$?
  sed 's/^/  status on rover| /' "$OUT/status.log"
  kill -TERM "$recorder"; wait "$recorder"
  launcher_ok
  [ "$rc" -eq 0 ] || fail "the sequence did not complete (rover_seq submit exit $rc)"
  grep -q '^\[completed' "$OUT/submit.log" || fail "no completed status in rover_seq's output"
  [ "$src" -eq 0 ] && grep -q '^\[completed' "$OUT/status.log" || fail "rover_seq status on host rover did not hear the completed sequence"
  # What host rover heard from host ground: the submit went to "ground" only, but every
  # drive command came from there, and each step's report.
  "$BIN/logcheck" --joined "$OUT/rover.lcm" > "$OUT/logcheck.txt" 2>&1
  grep -E '^(channel|MOBILITY_COMMAND|STEP_REPORT|SEQUENCE_STATUS|HEARTBEAT|log complete)' "$OUT/logcheck.txt"
  count() { awk -v c="$1" '$1 == c { print $3 }' "$OUT/logcheck.txt"; }
  steps="$(count STEP_REPORT)"; commands="$(count MOBILITY_COMMAND)"
  [ "${steps:-0}" -ge 2 ] || fail "host rover recorded ${steps:-0} STEP_REPORTs from host ground (expected one per step, at least 2)"
  [ "${commands:-0}" -ge "$steps" ] || fail "host rover heard ${commands:-0} drive commands for $steps steps"
  grep -E '^HEARTBEAT ' "$OUT/logcheck.txt" | grep -q sequence_executor || fail "host rover heard no heartbeat of the executor"
  echo "PASS: the sequence submitted on host ground drove the rover on host rover to completion"
else
  # The operator on host rover submits; the executor runs on host ground, out of reach.
  SEQ="$OUT/two_hosts.seq"
  printf 'vo off step 50 cm\ndrive 1 m\n' > "$SEQ"
  start_ms=$(( $(date +%s%N) / 1000000 ))
  on "$ROVER_NS" timeout 30 "$BIN/rover_seq" submit "$SEQ" --lcm-url "$URL" > "$OUT/submit.log" 2>&1
  rc=$?
  took_ms=$(( $(date +%s%N) / 1000000 - start_ms ))
  took="$((took_ms / 1000)).$(printf '%03d' $((took_ms % 1000)))"
  sed 's/^/  submit| /' "$OUT/submit.log"
  echo "rover_seq submit: exit $rc after $took s"
  launcher_ok
  [ "$rc" -eq 3 ] || fail "expected rover_seq exit 3 (nothing answered), got $rc"
  [ "$took_ms" -lt 8000 ] || fail "the failure took $took s (expected a few seconds)"
  msg="$(grep '^rover_seq: ' "$OUT/submit.log")"
  [ "$(echo "$msg" | wc -l)" -eq 1 ] || fail "expected one message, got: $msg"
  for want in "no sequence_executor heard" "$URL" "ttl=0" "224.0.0.0/4" "vrover" "7667" \
              "sequence_executor not running"; do
    echo "$msg" | grep -qF -- "$want" || fail "the message does not mention '$want'"
  done
  # The executor was running all along, on the other host.
  heard "$GROUND_NS" sequence_executor || fail "the executor on host ground stopped"
  echo "PASS: on a ttl=0 bus the submit from host rover reports within $took s that no executor answered"
fi
