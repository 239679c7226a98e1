#!/bin/sh
# The bench deployment (configs/deploy/bench_genicam.yaml) on Aravis's two simulated GigE
# Vision cameras, for SECONDS of wall time, recorded twice, by lcm-logger (log.lcm) and by
# rover_recorder (recorder.lcm), each checked with logcheck (docs/HARDWARE.md, "A bench"):
# lcm-logger 1.3.1 drops messages when its thread is starved (README, "Recording and
# checking logs"), so a loss in log.lcm alone is the logger's, one in both is the bus's. Everything runs in a user and network namespace
# of its own whose loopback has 127.0.0.1 (camera GV01) and 127.0.0.2 (camera GV02) and the
# multicast route: nothing leaves the machine. Exit 0 when every process lived to the end
# and rover_recorder's log is complete, 77 when it cannot run here (no simulated camera, no namespaces).
#   tools/launch/bench_fake_cameras.sh [SECONDS] [OUT_DIR] (default 600, out/bench)
set -eu
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
BIN="${ROVER_BUILD_DIR:-$ROOT/build}/bin"
SECONDS_TO_RUN="${1:-600}"
OUT="${2:-$ROOT/out/bench}"
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
command -v arv-fake-gv-camera-0.8 >/dev/null || { echo "bench: arv-fake-gv-camera-0.8 is not installed (aravis-tools): skipped"; exit 77; }
if [ -z "${ROVER_BENCH_NETNS:-}" ]; then
  unshare -rn true 2>/dev/null || { echo "bench: cannot make a network namespace (unshare -rn): skipped"; exit 77; }
  exec env ROVER_BENCH_NETNS=1 unshare -rn sh -c 'ip link set lo up && ip addr add 127.0.0.2/8 dev lo &&
    ip route add 224.0.0.0/4 dev lo && exec sh "$0" "$@"' "$0" "$SECONDS_TO_RUN" "$OUT"
fi
cd "$ROOT"
arv-fake-gv-camera-0.8 -i 127.0.0.1 -s GV01 > "$OUT/gv01.log" 2>&1 &
CAM1=$!
arv-fake-gv-camera-0.8 -i 127.0.0.2 -s GV02 > "$OUT/gv02.log" 2>&1 &
CAM2=$!
sleep 2
lcm-logger -f "$OUT/log.lcm" > "$OUT/logger.log" 2>&1 &
LOGGER=$!
"$BIN/rover_recorder" "$OUT/recorder.lcm" > "$OUT/recorder.log" 2>&1 &
RECORDER=$!
sleep 1
"$BIN/launcher" configs/deploy/bench_genicam.yaml > "$OUT/launch.log" 2>&1 &
LAUNCHER=$!
sleep "$SECONDS_TO_RUN"
alive=1
if kill -0 "$LAUNCHER" 2>/dev/null; then
  echo "bench: every process ran for $SECONDS_TO_RUN s"
else
  alive=0
  echo "bench: the launcher stopped early (a process died): see $OUT/launch.log"
fi
kill -INT "$LAUNCHER" 2>/dev/null || true
wait "$LAUNCHER" || true
sleep 1
kill -INT "$LOGGER" "$RECORDER"; wait "$LOGGER" || true; wait "$RECORDER" || true
kill "$CAM1" "$CAM2"
complete=0
"$BIN/logcheck" "$OUT/log.lcm" > "$OUT/logcheck.txt" 2>&1 || true
"$BIN/logcheck" "$OUT/recorder.lcm" > "$OUT/recorder_logcheck.txt" 2>&1 && complete=1
echo "lcm-logger:     $(tail -1 "$OUT/logcheck.txt")"
echo "rover_recorder: $(tail -1 "$OUT/recorder_logcheck.txt")"
echo "capture failures: $(grep -c 'capture failed' "$OUT/launch.log" || true)"
[ "$alive" -eq 1 ] && [ "$complete" -eq 1 ]
