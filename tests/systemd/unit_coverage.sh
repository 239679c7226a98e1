#!/usr/bin/env bash
# Every process has a systemd unit that runs it the way the rover needs:
#  - every program in configs/deploy/*.yaml (the launcher's process lists) and every
#    process folder in processes/ has a unit in configs/systemd/ whose ExecStart runs
#    /opt/rover/bin/<program>;
#  - that unit is WantedBy= and PartOf= rover.target (rover-sim.target for rover_sim),
#    restarts on failure, takes the bus from /etc/rover/rover.env, Requires= and is
#    After= rover-lcm-route.service, runs as the rover user, and sets no WatchdogSec
#    (the processes do not call sd_notify).
#
# usage: unit_coverage.sh SOURCE_DIR [UNIT_DIR]
set -uo pipefail

SRC="${1:?usage: unit_coverage.sh SOURCE_DIR [UNIT_DIR]}"
UNIT_DIR="${2:-$SRC/configs/systemd}"
errors=0
err() { echo "FAIL: $*" >&2; errors=$((errors + 1)); }

# The programs a deployment file starts: `program:` when given, else `name:`.
deploy_programs() {
  awk '
    function flush() { if (name != "") print (program != "" ? program : name); name = ""; program = "" }
    /^[[:space:]]*-[[:space:]]*name:/ { flush(); sub(/^[[:space:]]*-[[:space:]]*name:[[:space:]]*/, ""); name = $1 }
    /^[[:space:]]+program:/ { sub(/^[[:space:]]+program:[[:space:]]*/, ""); program = $1 }
    END { flush() }
  ' "$1" | tr -d "\"'" | sed 's|.*/||'
}

declare -A wanted  # program -> where it was listed
shopt -s nullglob
deploys=("$SRC"/configs/deploy/*.yaml)
[ "${#deploys[@]}" -gt 0 ] || err "no deployment files in $SRC/configs/deploy"
for f in "${deploys[@]}"; do
  programs="$(deploy_programs "$f")"
  # A format this parser does not read must not pass as "no processes".
  [ -n "$programs" ] || err "${f#"$SRC"/}: no '- name:' entries found (format changed? update this test)"
  grep -Eq '^[[:space:]]*-[[:space:]]*\{' "$f" &&
    err "${f#"$SRC"/}: a flow-style entry ('- {name: ...}') this test cannot read: use '- name:' blocks"
  for p in $programs; do wanted[$p]="${f#"$SRC"/}"; done
done
for d in "$SRC"/processes/*/; do
  [ -f "$d/CMakeLists.txt" ] && wanted[$(basename "$d")]="processes/$(basename "$d")/"
done
[ "${#wanted[@]}" -gt 0 ] || err "no processes found"

for p in $(printf '%s\n' "${!wanted[@]}" | sort); do
  units=()
  for u in "$UNIT_DIR"/*.service; do
    grep -Eq "^ExecStart=/opt/rover/bin/$p( |$)" "$u" && units+=("$u")
  done
  if [ "${#units[@]}" -eq 0 ]; then
    err "$p (from ${wanted[$p]}) has no unit in ${UNIT_DIR#"$SRC"/}/ running /opt/rover/bin/$p"
    continue
  fi
  [ "${#units[@]}" -eq 1 ] || err "$p is run by ${#units[@]} units: ${units[*]##*/}"
  before=$errors
  u="${units[0]}"
  n="$(basename "$u")"
  target=rover.target
  [ "$p" = rover_sim ] && target=rover-sim.target
  has() { grep -Eq "^$1\$" "$u" || err "$n (for $p): expected the line '$1'"; }
  has "WantedBy=$target"
  has "PartOf=$target"
  has "Restart=on-failure"
  has "RestartSec=[0-9]+s?"
  has "StartLimitBurst=[0-9]+"
  has "EnvironmentFile=/etc/rover/rover.env"
  has "Requires=rover-lcm-route.service"
  has "After=rover-lcm-route.service"
  has "User=rover"
  has "NoNewPrivileges=yes"
  has "ExecStart=/opt/rover/bin/$p --config /etc/rover/(rover|vo).yaml( .*)?"
  grep -q '^WatchdogSec=' "$u" && err "$n sets WatchdogSec= but $p never calls sd_notify: systemd would kill it"
  [ $errors -eq $before ] && echo "ok: $p -> $n"
done

# The bus itself: the route unit and the env file the units read.
grep -q '^ExecStart=/usr/sbin/ip route replace 224.0.0.0/4 dev ${ROVER_LCM_IFACE}$' "$UNIT_DIR/rover-lcm-route.service" ||
  err "rover-lcm-route.service does not route 224.0.0.0/4 through \${ROVER_LCM_IFACE}"
grep -Eq '^ROVER_LCM_URL=udpm://[0-9.]+:[0-9]+\?ttl=1&recv_buf_size=[0-9]+$' "$UNIT_DIR/rover.env" ||
  err "rover.env: ROVER_LCM_URL is not a udpm URL with ttl=1 and recv_buf_size"
grep -Eq '^ROVER_LCM_IFACE=[A-Za-z0-9._-]+$' "$UNIT_DIR/rover.env" || err "rover.env: ROVER_LCM_IFACE missing"
# The logger records with rover_recorder (lcm-logger loses messages), rotating at each start.
grep -Eq '^ExecStart=/opt/rover/bin/rover_recorder /var/log/rover/[^ ]+$' "$UNIT_DIR/rover-logger.service" ||
  err "rover-logger.service does not record the bus with rover_recorder under /var/log/rover"
grep -Eq '^ExecStartPre=/opt/rover/bin/rover-log-rotate /var/log/rover/[^ ]+ [0-9]+$' "$UNIT_DIR/rover-logger.service" ||
  err "rover-logger.service does not rotate its logs (ExecStartPre=rover-log-rotate)"
grep -q '^ExecStart=.*lcm-logger' "$UNIT_DIR/rover-logger.service" &&
  err "rover-logger.service runs lcm-logger, which loses messages"

[ $errors -eq 0 ] || { echo "$errors problem(s)" >&2; exit 1; }
echo "every process (${#wanted[@]}) has a unit"
