# Sourced by spy.sh and logplayer_gui.sh (LCM's Java tools with a window). Sets java_bin to a
# Java that can open X11 windows and checks lcm.jar and the display; dies (the caller's die)
# with one line naming what to install otherwise. Needs JAVA_DIR.
require_java_window() {
  java_bin="$(command -v java || true)"
  [ -n "$java_bin" ] || die "java not found (install openjdk-17-jre: apt-get install openjdk-17-jre)"
  local java_home
  java_home="$(dirname "$(dirname "$(readlink -f "$java_bin")")")"
  [ -f "$java_home/lib/libawt_xawt.so" ] \
    || die "$java_home is a headless Java without X11 windows (install openjdk-17-jre)"
  [ -f "$JAVA_DIR/lcm.jar" ] || die "$JAVA_DIR/lcm.jar is missing (install liblcm-java)"
}
require_display() {
  [ -n "${DISPLAY:-}" ] || die "no X display (DISPLAY is not set): run it on a desktop, over ssh -X, or under xvfb-run"
}
