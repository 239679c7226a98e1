#!/usr/bin/env bash
# ctest Spy.decodes_project_messages (label spy); run it on a private bus:
#   ./rover private ctest --test-dir build -R Spy
# Starts Xvfb on a free display, publishes project messages with spy_test_publisher (C++),
# starts lcm-spy through tools/spy/spy.sh, the script ./rover spy runs, with SpyProbe
# (tools/spy/test/SpyProbe.java) as its main class, which starts lcm.spy.Spy and passes when
# lcm-spy's own table names and decodes HEARTBEAT, POSE, IMU and WHEEL_ODOMETRY (with the
# published field values) and lists SPY_TEST_UNKNOWN as unknown; it saves a screenshot.
# Also checks lcm-spy's "Found N LCM types" line against lcmtypes/*.lcm.
# Exit 77 (ctest: skipped) when Java with X11, lcm.jar, jchart2d, the jars or Xvfb are absent.
set -u

SRC="${ROVER_SOURCE_DIR:?set by ctest}"
BUILD="${ROVER_BUILD_DIR:?set by ctest}"
OUT="$BUILD/test-out/spy"
t0="$(date +%s%N)"
stamp() { echo "[$((($(date +%s%N) - t0) / 1000000)) ms] $*"; }
skip() { echo "SKIP: $* (lcm-spy test not run)"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }

command -v Xvfb >/dev/null || skip "Xvfb not found (install xvfb)"
java_bin="$(command -v java || true)"
[ -n "$java_bin" ] || skip "java not found (install openjdk-17-jre)"
java_home="$(dirname "$(dirname "$(readlink -f "$java_bin")")")"
[ -f "$java_home/lib/libawt_xawt.so" ] || skip "$java_home has no X11 windows (install openjdk-17-jre)"
[ -f /usr/share/java/lcm.jar ] || skip "/usr/share/java/lcm.jar not found (install liblcm-java)"
[ -f /usr/share/java/jchart2d.jar ] || skip "/usr/share/java/jchart2d.jar not found (install libjchart2d-java)"
[ -n "${SPY_PROBE_JAR:-}" ] && [ -f "$SPY_PROBE_JAR" ] \
  || skip "no Java types built (a JDK and liblcm-java were absent when cmake configured build/)"
[ -f "$BUILD/share/java/rover_msgs.jar" ] || skip "$BUILD/share/java/rover_msgs.jar not built"
[ -x "${SPY_PUBLISHER:-}" ] || fail "spy_test_publisher not built (SPY_PUBLISHER='${SPY_PUBLISHER:-}')"

mkdir -p "$OUT" || fail "cannot create $OUT"
rm -f "$OUT/screenshot.png" "$OUT/spy.log" "$OUT/display" "$OUT/xvfb.log" "$OUT/publisher.log"

xvfb_pid=""
pub_pid=""
cleanup() {
  [ -n "$pub_pid" ] && kill "$pub_pid" 2>/dev/null
  [ -n "$xvfb_pid" ] && kill "$xvfb_pid" 2>/dev/null
  [ -n "$pub_pid" ] && wait "$pub_pid" 2>/dev/null
  [ -n "$xvfb_pid" ] && wait "$xvfb_pid" 2>/dev/null
}
trap cleanup EXIT

# Wait up to $1 seconds for "$2" (a shell test) to hold; polls every 0.1 s.
wait_for() {
  local limit=$(($1 * 10)) i=0
  while ! eval "$2"; do
    i=$((i + 1))
    [ "$i" -ge "$limit" ] && return 1
    sleep 0.1
  done
}

# Xvfb picks a free display itself and writes its number to fd 3 once it accepts clients.
Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$OUT/display" >"$OUT/xvfb.log" 2>&1 &
xvfb_pid=$!
wait_for 30 '[ -s "$OUT/display" ] || ! kill -0 $xvfb_pid 2>/dev/null' \
  || fail "Xvfb did not report a display within 30 s (see $OUT/xvfb.log)"
kill -0 "$xvfb_pid" 2>/dev/null || fail "Xvfb exited: $(tail -3 "$OUT/xvfb.log")"
display=":$(tr -d '[:space:]' <"$OUT/display")"
stamp "Xvfb on display $display"

# A bus of this test's own (group and port no other test uses), loopback only.
url="udpm://239.255.76.69:$((32000 + $$ % 380 * 2))?ttl=0"
"$SPY_PUBLISHER" --lcm-url "$url" --seconds 120 --period-ms 50 >"$OUT/publisher.log" 2>&1 &
pub_pid=$!

n_types="$(ls "$SRC"/lcmtypes/*.lcm | wc -l)"
DISPLAY="$display" ROVER_SPY_MAIN=rover.spy.SpyProbe ROVER_SPY_EXTRA_CLASSPATH="$SPY_PROBE_JAR" \
ROVER_SPY_PROBE_EXPECT="HEARTBEAT=heartbeat_t,POSE=pose_t,IMU=imu_t,WHEEL_ODOMETRY=wheel_odometry_t,SPY_TEST_UNKNOWN=??" \
ROVER_SPY_PROBE_FIELDS="HEARTBEAT.process=spy_test_publisher;POSE.position=[1.5, -2.25, 0.125];POSE.site_index=7;IMU.accel=[0.0, 0.0, -3.71];WHEEL_ODOMETRY.num_wheels=6" \
ROVER_SPY_PROBE_MIN=5 ROVER_SPY_PROBE_TIMEOUT_S=30 ROVER_SPY_PROBE_SCREENSHOT="$OUT/screenshot.png" \
  timeout -k 5 100 "$SRC/tools/spy/spy.sh" --lcm-url "$url" >"$OUT/spy.log" 2>&1
rc=$?
stamp "lcm-spy with the probe exited $rc; its output:"
cat "$OUT/spy.log"
kill -0 "$pub_pid" 2>/dev/null || fail "spy_test_publisher exited early: $(cat "$OUT/publisher.log")"
[ "$rc" -eq 0 ] || fail "lcm-spy with the probe exited $rc (log: $OUT/spy.log)"
grep -qx "Found $n_types LCM types" "$OUT/spy.log" \
  || fail "lcm-spy did not report 'Found $n_types LCM types' (one per lcmtypes/*.lcm)"
[ -s "$OUT/screenshot.png" ] || fail "no screenshot at $OUT/screenshot.png"
stamp "PASS: lcm-spy found $n_types types and decoded the project's messages; screenshot: $OUT/screenshot.png"
