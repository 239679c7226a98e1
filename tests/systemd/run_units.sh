#!/usr/bin/env bash
# Runs the units' own command lines, as systemd would, on a private bus: installs into a
# staging root with install.sh --prefix, takes each unit's ExecStart= with /opt/rover,
# /etc/rover and /var/log/rover moved under the staging root and the environment of
# /etc/rover/rover.env, and starts them all (the logger too) in a private network
# namespace with the route rover-lcm-route.service would add (on lo). Then checks that
# each process is still running after a few seconds (its arguments and the installed
# config were accepted), published its heartbeat (seen in the logger's file), and exits
# 0 on SIGTERM, which is how `systemctl stop` ends it.
# Units whose binary is not built are left out (said in the output); exit 77 when none is
# built or no private namespace can be made.
#
# usage: run_units.sh SOURCE_DIR BUILD_DIR
set -uo pipefail

SRC="${1:?usage: run_units.sh SOURCE_DIR BUILD_DIR}"
BUILD="${2:?usage: run_units.sh SOURCE_DIR BUILD_DIR}"
SETTLE_S="${ROVER_UNITS_SETTLE_S:-4}"

fail() { echo "FAIL: $*" >&2; exit 1; }

if ! unshare -rn true 2>/dev/null; then
  echo "SKIP: cannot create a private network namespace (unshare -rn) for the bus"
  exit 77
fi

STAGE="$(mktemp -d "${TMPDIR:-/tmp}/rover-systemd-run.XXXXXX")" || fail "mktemp"
trap 'rm -rf "$STAGE"' EXIT
out="$(bash "$SRC/configs/systemd/install.sh" --prefix "$STAGE" --build-dir "$BUILD" --no-enable 2>&1)" ||
  fail "install.sh --prefix: $out"
echo "$out" | grep "not built" | sed 's/^install.sh: warning: /note: /'

units=()
for u in "$STAGE"/etc/systemd/system/rover-*.service; do
  [ "$(basename "$u")" = rover-logger.service ] && continue  # started first, stopped last (below)
  grep -q '^ExecStart=/opt/rover/bin/' "$u" && units+=("$(basename "$u" .service)")
done
[ -f "$STAGE/etc/systemd/system/rover-logger.service" ] || fail "rover_recorder not built: rover-logger.service was not installed"
# ExecStartPre: the rotation, run as systemd would before the logger starts.
sed -n 's/^ExecStartPre=//p' "$STAGE/etc/systemd/system/rover-logger.service" | grep -q rover-log-rotate ||
  fail "rover-logger.service has no ExecStartPre=rover-log-rotate"
mkdir -p "$STAGE/var/log/rover"
echo previous > "$STAGE/var/log/rover/rover.lcm"
"$STAGE/opt/rover/bin/rover-log-rotate" "$STAGE/var/log/rover/rover.lcm" 10 || fail "rover-log-rotate failed"
[ "$(cat "$STAGE/var/log/rover/rover.lcm.1" 2>/dev/null)" = previous ] || fail "rover-log-rotate did not move rover.lcm to rover.lcm.1"
[ ! -e "$STAGE/var/log/rover/rover.lcm" ] || fail "rover-log-rotate left rover.lcm in place"
if [ "${#units[@]}" -eq 0 ]; then
  echo "SKIP: no process built in $BUILD/bin"
  exit 77
fi

# The command of a unit with its paths in the staging root, one argument per line.
# ${VAR} is expanded from the environment file as systemd does (one word each).
command_of() {
  sed -n 's/^ExecStart=//p' "$STAGE/etc/systemd/system/$1.service" |
    sed "s|/opt/rover/|$STAGE/opt/rover/|g; s|/etc/rover/|$STAGE/etc/rover/|g; s|/var/log/rover/|$STAGE/var/log/rover/|g; s|/var/lib/rover/|$STAGE/var/lib/rover/|g"
}
mkdir -p "$STAGE/var/log/rover" "$STAGE/var/lib/rover"

# The environment file in the systemd syntax used here (KEY=VALUE, # comments) — read it
# without a shell: the URL holds '&' and '?'.
envs=()
while IFS= read -r line; do
  case "$line" in ''|'#'*) continue ;; *=*) envs+=("$line") ;; esac
done < "$STAGE/etc/rover/rover.env"
[ "${#envs[@]}" -gt 0 ] || fail "rover.env sets nothing"

# The runner inside the namespace: starts everything, waits, checks, stops.
cat > "$STAGE/run.sh" <<'EOF'
set -u -f
stage="$1"; settle="$2"; shift 2
ip link set lo up && ip route add 224.0.0.0/4 dev lo || { echo "FAIL: no route on lo"; exit 1; }
declare -A pid
status=0
start() {  # name, then the command line with ${VAR}s
  local name="$1"; shift
  local argv=()
  for a in "$@"; do argv+=("$(eval "printf '%s' \"$a\"")"); done
  "${argv[@]}" > "$stage/$name.out" 2>&1 &
  pid[$name]=$!
}
while IFS=$'\t' read -r name cmd; do
  # shellcheck disable=SC2086
  start "$name" $cmd
done < "$stage/commands.tsv"
sleep "$settle"
for name in "${!pid[@]}"; do
  if ! kill -0 "${pid[$name]}" 2>/dev/null; then
    wait "${pid[$name]}"; rc=$?
    echo "FAIL: $name exited (status $rc) within ${settle} s: $(tail -n 3 "$stage/$name.out" | tr '\n' ' ')"
    status=1; unset "pid[$name]"
  fi
done
for name in "${!pid[@]}"; do [ "$name" = rover-logger ] || kill -TERM "${pid[$name]}"; done
for name in "${!pid[@]}"; do
  [ "$name" = rover-logger ] && continue
  wait "${pid[$name]}"; rc=$?
  if [ $rc -ne 0 ]; then
    echo "FAIL: $name exited with status $rc on SIGTERM: $(tail -n 3 "$stage/$name.out" | tr '\n' ' ')"
    status=1
  else
    echo "ok: $name ran ${settle} s and exited 0 on SIGTERM"
  fi
done
if [ -n "${pid[rover-logger]:-}" ]; then
  kill -TERM "${pid[rover-logger]}"; wait "${pid[rover-logger]}"; rc=$?
  if [ $rc -ne 0 ]; then
    echo "FAIL: rover-logger exited with status $rc on SIGTERM: $(tail -n 3 "$stage/rover-logger.out" | tr '\n' ' ')"
    status=1
  else
    echo "ok: rover-logger (rover_recorder) exited 0 on SIGTERM"
  fi
fi
exit $status
EOF

: > "$STAGE/commands.tsv"
for name in "${units[@]}" rover-logger; do
  printf '%s\t%s\n' "$name" "$(command_of "$name")" >> "$STAGE/commands.tsv"
done
echo "running on a private bus: ${units[*]} rover-logger"
env "${envs[@]}" unshare -rn bash "$STAGE/run.sh" "$STAGE" "$SETTLE_S"
status=$?

# Heartbeats (channel HEARTBEAT, name of the process in the message) in the logger's file.
log="$STAGE/var/log/rover/rover.lcm"
[ -n "$log" ] && [ -s "$log" ] || fail "the logger wrote nothing under /var/log/rover ($(cat "$STAGE/rover-logger.out"))"
for name in "${units[@]}"; do
  bin="$(command_of "$name" | sed 's|^[^ ]*/bin/\([^ ]*\).*|\1|')"
  if grep -aq "$bin" "$log" && grep -aq HEARTBEAT "$log"; then
    echo "ok: heartbeat of $bin in the log"
  else
    echo "FAIL: no heartbeat of $bin in $(basename "$log")" >&2
    status=1
  fi
done
[ $status -eq 0 ] || exit 1
echo "every built process ran from its unit's command line (${#units[@]})"
