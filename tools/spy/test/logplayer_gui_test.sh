#!/usr/bin/env bash
# ctest LogplayerGui.plays_a_log (label spy); run it on a private bus:
#   ./rover private ctest --test-dir build -R LogplayerGui
# Records a log of project messages (spy_test_publisher, rover_recorder), then plays it
# with tools/spy/logplayer_gui.sh (the script ./rover logplayer-gui runs) under Xvfb onto a
# second bus, where a second recorder must receive the log's channels.
# Exit 77 (ctest: skipped) when Java with X11, lcm.jar or Xvfb are absent.
set -u

SRC="${ROVER_SOURCE_DIR:?set by ctest}"
BUILD="${ROVER_BUILD_DIR:?set by ctest}"
OUT="$BUILD/test-out/logplayer_gui"
skip() { echo "SKIP: $* (lcm-logplayer-gui test not run)"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }

command -v Xvfb >/dev/null || skip "Xvfb not found (install xvfb)"
java_bin="$(command -v java || true)"
[ -n "$java_bin" ] || skip "java not found (install openjdk-17-jre)"
java_home="$(dirname "$(dirname "$(readlink -f "$java_bin")")")"
[ -f "$java_home/lib/libawt_xawt.so" ] || skip "$java_home has no X11 windows (install openjdk-17-jre)"
[ -f /usr/share/java/lcm.jar ] || skip "/usr/share/java/lcm.jar not found (install liblcm-java)"
[ -x "${SPY_PUBLISHER:-}" ] || fail "spy_test_publisher not built (SPY_PUBLISHER='${SPY_PUBLISHER:-}')"
recorder="$BUILD/bin/rover_recorder"
[ -x "$recorder" ] || fail "$recorder not built"

rm -rf "$OUT"
mkdir -p "$OUT" || fail "cannot create $OUT"
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; wait "$p" 2>/dev/null; done; }
trap cleanup EXIT

Xvfb -displayfd 3 -screen 0 1024x768x24 -nolisten tcp 3>"$OUT/display" >"$OUT/xvfb.log" 2>&1 &
pids+=($!)
for _ in $(seq 300); do [ -s "$OUT/display" ] && break; sleep 0.1; done
[ -s "$OUT/display" ] || fail "Xvfb did not report a display within 30 s (see $OUT/xvfb.log)"
display=":$(tr -d '[:space:]' <"$OUT/display")"

# 1. A log: the publisher's messages for 2 s.
url1="udpm://239.255.76.70:$((32000 + $$ % 380 * 2))?ttl=0"
url2="udpm://239.255.76.71:$((32000 + $$ % 380 * 2))?ttl=0"
"$recorder" --lcm-url "$url1" "$OUT/in.lcm" 2>"$OUT/recorder_in.log" &
rec=$!
sleep 0.5
"$SPY_PUBLISHER" --lcm-url "$url1" --seconds 2 --period-ms 50 >"$OUT/publisher.log" 2>&1 || fail "spy_test_publisher failed"
kill "$rec"; wait "$rec"
grep -qa POSE "$OUT/in.lcm" || fail "the recorded log holds no POSE (see $OUT/recorder_in.log)"

# 2. Played by the wrapper onto a second bus, recorded there.
"$recorder" --lcm-url "$url2" "$OUT/played.lcm" 2>"$OUT/recorder_played.log" &
rec=$!
sleep 0.5
DISPLAY="$display" "$SRC/tools/spy/logplayer_gui.sh" "$OUT/in.lcm" --lcm-url "$url2" >"$OUT/player.log" 2>&1 &
player=$!
pids+=("$player")
for _ in $(seq 200); do grep -qa POSE "$OUT/played.lcm" 2>/dev/null && break; kill -0 "$player" 2>/dev/null || break; sleep 0.1; done
sleep 1
kill -0 "$player" 2>/dev/null || { cat "$OUT/player.log"; fail "the log player exited (see $OUT/player.log)"; }
kill "$rec"; wait "$rec"
grep -q "Unrecognized option" "$OUT/player.log" && fail "Java refused an option: $(head -2 "$OUT/player.log")"
for ch in POSE IMU WHEEL_ODOMETRY; do
  grep -qa "$ch" "$OUT/played.lcm" || fail "$ch was not played onto the bus (see $OUT/player.log)"
done
echo "ok: lcm-logplayer-gui played POSE, IMU and WHEEL_ODOMETRY from $OUT/in.lcm onto $url2"
