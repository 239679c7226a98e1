#!/usr/bin/env bash
# ./rover logplayer-gui LOG.lcm [--lcm-url URL] [--paused] [--filter REGEX]: LCM's own log
# player with a window (lcm.logging.LogPlayer in liblcm-java's lcm.jar): play, pause, seek
# with a slider, change the speed, and choose channels. Debian's /usr/bin/lcm-logplayer-gui
# cannot be used on Java 17: it passes -Xincgc (gone since Java 9; "Unrecognized option"),
# the same fault tools/spy/spy.sh works around for lcm-spy. It plays onto the bus: play a
# recording onto a bus no rover listens to (a private one, ./rover private).
#
# The bus: --lcm-url URL, else $ROVER_LCM_URL, else the project's default bus.
set -euo pipefail

JAVA_DIR=/usr/share/java
DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"  # common/bus/bus.hpp

# shellcheck source=java_window.sh
source "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/java_window.sh"

die() { echo "rover logplayer-gui: $*" >&2; exit 2; }

usage() {
  cat <<'USAGE'
usage: ./rover logplayer-gui LOG.lcm [--lcm-url URL] [--paused] [--filter REGEX]

Starts lcm-logplayer-gui, LCM's log player with a window, on LOG.lcm: it plays the log onto
the bus (play, pause, a slider to seek, speed, and a channel table to turn channels off).
--paused starts paused; --filter REGEX turns off the channels that match REGEX.
The bus: --lcm-url URL, else $ROVER_LCM_URL, else udpm://239.255.76.67:7667?ttl=0.
Needs an X display (a desktop, ssh -X, or xvfb-run), liblcm-java and openjdk-17-jre.
USAGE
}

url="${ROVER_LCM_URL:-$DEFAULT_URL}"
log=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --lcm-url) [ $# -ge 2 ] || die "--lcm-url: missing URL (expected --lcm-url udpm://ADDR:PORT?ttl=0)"
               url="$2"; shift 2 ;;
    --lcm-url=*) url="${1#--lcm-url=}"; shift ;;
    --paused) extra+=(--paused); shift ;;
    --filter) [ $# -ge 2 ] || die "--filter: missing REGEX"
              extra+=("--filter=$2"); shift 2 ;;
    -*) die "argument '$1': unexpected (expected LOG.lcm [--lcm-url URL] [--paused] [--filter REGEX])" ;;
    *) [ -z "$log" ] || die "argument '$1': a second log (expected one LOG.lcm)"
       log="$1"; shift ;;
  esac
done
[ -n "$log" ] || die "missing LOG.lcm (expected ./rover logplayer-gui LOG.lcm [--lcm-url URL])"
[ -f "$log" ] && [ -r "$log" ] || die "$log: not a readable file (expected an LCM log)"
[ -n "$url" ] || die "--lcm-url: empty URL (expected udpm://ADDR:PORT?ttl=0)"

require_java_window
require_display

# Debian's lcm-logplayer-gui options less -Xincgc, with the serial collector (a small heap).
exec "$java_bin" -Djava.net.preferIPv4Stack=true -XX:+UseSerialGC -Xms32m -Xmx128m -ea \
  -cp "$JAVA_DIR/lcm.jar" lcm.logging.LogPlayer "--lcm-url=$url" "${extra[@]}" "$log"
