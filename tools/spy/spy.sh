#!/usr/bin/env bash
# ./rover spy [--lcm-url URL]: LCM's own message inspector, lcm-spy (lcm.spy.Spy in
# liblcm-java's lcm.jar), with the project's message types (build/share/java/rover_msgs.jar,
# made by lcmtypes/java.cmake), so it names and decodes every channel. Debian's
# /usr/bin/lcm-spy cannot be used as is: it passes -Xincgc, which Java 17 rejects, and
# leaves the project's types off its classpath.
#
# The bus: --lcm-url URL, else $ROVER_LCM_URL, else the project's default bus.
# For tools/spy/test only: ROVER_SPY_MAIN names another main class (which starts lcm.spy.Spy
# itself) and ROVER_SPY_EXTRA_CLASSPATH adds to the classpath.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${ROVER_BUILD_DIR:-$ROOT/build}"
JAVA_DIR=/usr/share/java
DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"  # common/bus/bus.hpp

# shellcheck source=java_window.sh
source "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/java_window.sh"

die() { echo "rover spy: $*" >&2; exit 2; }

usage() {
  cat <<'USAGE'
usage: ./rover spy [--lcm-url URL]

Starts lcm-spy, LCM's message inspector, with the project's message types: one row per
channel (type, count, rate, bandwidth); double-click a row to see the last message's fields.
The bus: --lcm-url URL, else $ROVER_LCM_URL, else udpm://239.255.76.67:7667?ttl=0.
Needs an X display (a desktop, ssh -X, or xvfb-run) and the Debian packages liblcm-java,
libjchart2d-java, openjdk-17-jre, and openjdk-17-jdk-headless to build the types.
USAGE
}

url="${ROVER_LCM_URL:-$DEFAULT_URL}"
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --lcm-url) [ $# -ge 2 ] || die "--lcm-url: missing URL (expected --lcm-url udpm://ADDR:PORT?ttl=0)"
               url="$2"; shift 2 ;;
    --lcm-url=*) url="${1#--lcm-url=}"; shift ;;
    *) die "argument '$1': unexpected (expected [--lcm-url URL])" ;;
  esac
done
[ -n "$url" ] || die "--lcm-url: empty URL (expected udpm://ADDR:PORT?ttl=0)"

require_java_window
# jchart2d.jar's manifest brings in jide-oss.jar and xmlgraphics-commons.jar.
jchart2d="$JAVA_DIR/jchart2d.jar"
[ -f "$jchart2d" ] || die "$jchart2d is missing (install libjchart2d-java)"
msgs_jar="$BUILD/share/java/rover_msgs.jar"
[ -f "$msgs_jar" ] || die "$msgs_jar is missing (install openjdk-17-jdk-headless and liblcm-java, then ./rover build)"
require_display

classpath="$JAVA_DIR/lcm.jar:$jchart2d:$msgs_jar${ROVER_SPY_EXTRA_CLASSPATH:+:$ROVER_SPY_EXTRA_CLASSPATH}"
# Debian's lcm-spy options less -Xincgc (gone since Java 9); a little more heap for images,
# and the serial collector, which suits a heap this small on a 2-core machine.
exec "$java_bin" -Djava.net.preferIPv4Stack=true -XX:+UseSerialGC -Xms64m -Xmx256m -ea -cp "$classpath" \
  "${ROVER_SPY_MAIN:-lcm.spy.Spy}" --lcm-url "$url"
