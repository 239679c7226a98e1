#!/usr/bin/env bash
# Installs the rover process set on a rover computer (configs/systemd/README.md):
#   binaries  build/bin/<process>            -> /opt/rover/bin/
#   configs   configs/rover.yaml, vo.yaml, rover.env, worlds/, cameras/ -> /etc/rover/ (never overwritten)
#   units     configs/systemd/*.service, *.target -> /etc/systemd/system/ (always overwritten)
#   account   rover.sysusers -> /etc/sysusers.d/rover.conf; sysctl 90-rover-lcm.conf -> /etc/sysctl.d/
#   key       /etc/rover/rover.key, the deployment's key for signed commands: made when absent
#             (32 random bytes as hex, mode 0640, group rover), never replaced
# then enables the process units into their targets and runs daemon-reload. It does not
# start anything, nor enable rover.target at boot.
#
# --prefix DIR installs into a staging root (tests, images): no systemctl calls on the
# running system; units are enabled offline with `systemctl --root=DIR`.
#
# --deployment FILE --host NAME: one computer of a rover split over several (README,
# "Several hosts"): every unit is installed, but only the process units of NAME's share
# of FILE (its processes with `host: NAME`, as `./rover launch FILE --host NAME` starts
# them) are enabled, with the route and logger units. Every computer needs the same
# /etc/rover/rover.env bus (ttl=1, same group and port) and the same key.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
BUILD="$ROOT/build"
PREFIX=""
ENABLE=1
DEPLOYMENT=""
HOST=""

die() { echo "install.sh: error: $*" >&2; exit 1; }
note() { echo "install.sh: $*"; }

usage() {
  cat <<'EOF'
usage: configs/systemd/install.sh [--prefix DIR] [--build-dir DIR] [--no-enable]
  --prefix DIR     install under DIR (a staging root) instead of /; no systemctl on the running system
  --build-dir DIR  build tree holding bin/ (default: build/ at the repository root)
  --no-enable      copy files only; do not enable the units into rover.target / rover-sim.target
  --deployment FILE --host NAME
                   enable only the process units of host NAME's share of FILE (configs/deploy/*.yaml
                   with `host:` per process); the rest are installed but not enabled
EOF
}

while [ $# -gt 0 ]; do
  case "$1" in
    --prefix) [ $# -ge 2 ] || die "--prefix needs a directory"; PREFIX="$2"; shift 2 ;;
    --build-dir) [ $# -ge 2 ] || die "--build-dir needs a directory"; BUILD="$2"; shift 2 ;;
    --no-enable) ENABLE=0; shift ;;
    --deployment) [ $# -ge 2 ] || die "--deployment needs a file (configs/deploy/*.yaml)"; DEPLOYMENT="$2"; shift 2 ;;
    --host) [ $# -ge 2 ] || die "--host needs a host name (from the deployment file)"; HOST="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done

BIN="$BUILD/bin"
[ -d "$BIN" ] || die "no build output at $BIN: build first (./rover build) or pass --build-dir"
if [ -n "$DEPLOYMENT" ] || [ -n "$HOST" ]; then
  [ -n "$DEPLOYMENT" ] && [ -n "$HOST" ] || die "--deployment FILE and --host NAME go together"
  [ -x "$BIN/launcher" ] || die "$BIN/launcher not built: it reads the deployment file (./rover build)"
  # The programs of this host's share, one a line (the launcher reads the file: one parser).
  host_programs="$("$BIN/launcher" "$DEPLOYMENT" --host "$HOST" --list 2>&1)" || die "$host_programs"
  host_programs="$(echo "$host_programs" | awk '{ n = split($2, p, "/"); print p[n] }')"
fi
if [ -n "$PREFIX" ]; then
  mkdir -p "$PREFIX" || die "cannot create prefix $PREFIX"
  PREFIX="$(cd "$PREFIX" && pwd)"
  [ "$PREFIX" != "/" ] || die "--prefix / is the live system: run without --prefix instead"
else
  [ "$(id -u)" -eq 0 ] || die "installing to / needs root (run with sudo, or use --prefix DIR)"
fi

# The binary a unit runs from /opt/rover/bin, or nothing for a unit that runs none.
unit_binary() { sed -n 's|^ExecStart=/opt/rover/bin/\([^ ]*\).*|\1|p' "$1"; }

# Copies a config file unless the target exists; a differing new version goes next to it
# as .new, as dpkg does, so an operator's edits are never lost.
install_config() {
  local src="$1" dst="$2"
  if [ -e "$dst" ]; then
    if ! cmp -s "$src" "$dst"; then
      install -m 0644 "$src" "$dst.new"
      note "kept ${dst#"$PREFIX"} (edited?); the shipped version is ${dst#"$PREFIX"}.new"
    fi
  else
    install -D -m 0644 "$src" "$dst"
  fi
}

OPT="$PREFIX/opt/rover/bin"
ETC="$PREFIX/etc/rover"
UNITS="$PREFIX/etc/systemd/system"
mkdir -p "$OPT" "$ETC" "$UNITS" "$PREFIX/etc/sysusers.d" "$PREFIX/etc/sysctl.d"

installed_units=()
shopt -s nullglob
for unit in "$HERE"/*.service "$HERE"/*.target; do
  name="$(basename "$unit")"
  bin="$(unit_binary "$unit")"
  if [ -n "$bin" ]; then
    if [ ! -x "$BIN/$bin" ]; then
      note "warning: $BIN/$bin not built: skipping it and $name"
      continue
    fi
    install -m 0755 "$BIN/$bin" "$OPT/$bin"
  fi
  install -m 0644 "$unit" "$UNITS/$name"
  installed_units+=("$name")
done
[ "${#installed_units[@]}" -gt 0 ] || die "no unit files found in $HERE"
# rover-lcm-route.service's check of the bus settings and rover-logger.service's rotation
# of its logs (shell scripts).
install -m 0755 "$HERE/rover-bus-check" "$OPT/rover-bus-check"
install -m 0755 "$HERE/rover-log-rotate" "$OPT/rover-log-rotate"

install_config "$ROOT/configs/rover.yaml" "$ETC/rover.yaml"
install_config "$ROOT/configs/vo.yaml" "$ETC/vo.yaml"
install_config "$HERE/rover.env" "$ETC/rover.env"
for dir in worlds cameras; do
  for f in "$ROOT/configs/$dir"/*.yaml; do
    install_config "$f" "$ETC/$dir/$(basename "$f")"
  done
done
install -m 0644 "$HERE/rover.sysusers" "$PREFIX/etc/sysusers.d/rover.conf"
install -m 0644 "$HERE/90-rover-lcm.conf" "$PREFIX/etc/sysctl.d/90-rover-lcm.conf"

# The deployment's key (README.md, "Bus security"): every process unit signs and checks
# commands with it (--key). Made from the kernel's random source when absent, never
# readable by others (the processes refuse a key that is); never replaced, because every
# computer and operator of the rover must hold the same one.
KEY="$ETC/rover.key"
if [ -e "$KEY" ]; then
  [ -f "$KEY" ] || die "${KEY#"$PREFIX"} exists but is not a regular file (expected the deployment's key)"
  note "kept ${KEY#"$PREFIX"} (the deployment's key)"
else
  ( umask 077 && od -An -v -tx1 -N32 /dev/urandom | tr -d ' \n' > "$KEY.tmp" && echo >> "$KEY.tmp" ) ||
    die "cannot write ${KEY#"$PREFIX"}.tmp"
  [ "$(wc -c < "$KEY.tmp")" -eq 65 ] || { rm -f "$KEY.tmp"; die "could not read 32 random bytes from /dev/urandom"; }
  chmod 0640 "$KEY.tmp" && mv "$KEY.tmp" "$KEY"
  note "made a new key ${KEY#"$PREFIX"}: copy it (mode 0640 or stricter) to every other computer and operator of this rover"
fi

if [ -z "$PREFIX" ]; then
  for tool in /usr/sbin/ip; do
    [ -x "$tool" ] || note "warning: $tool not found: the units need it (apt-get install iproute2)"
  done
fi

# Units that have an [Install] section: the process units, the route, rover.target.
# rover.target's own WantedBy=multi-user.target (start at boot) is left to the operator.
enable_units=()
for name in "${installed_units[@]}"; do
  [ "$name" = rover.target ] && continue
  grep -q '^WantedBy=' "$UNITS/$name" || continue
  bin="$(unit_binary "$UNITS/$name")"
  # Every computer records the bus (the logger is in no deployment's process list).
  if [ -n "$HOST" ] && [ -n "$bin" ] && [ "$name" != rover-logger.service ] &&
     ! echo "$host_programs" | grep -qx "$bin"; then
    note "$name not enabled: $bin is not in host $HOST's share of $DEPLOYMENT"
    continue
  fi
  enable_units+=("$name")
done
[ -z "$HOST" ] || note "host $HOST of $DEPLOYMENT: enabling ${enable_units[*]}"

if [ -n "$PREFIX" ]; then
  if [ "$ENABLE" -eq 1 ] && [ "${#enable_units[@]}" -gt 0 ]; then
    command -v systemctl >/dev/null || die "systemctl not found: cannot enable units under $PREFIX (use --no-enable)"
    out="$(systemctl --root="$PREFIX" --quiet enable "${enable_units[@]}" 2>&1)" ||
      die "systemctl --root=$PREFIX enable failed: $(echo "$out" | head -n 1)"
  fi
  note "installed ${#installed_units[@]} units under $PREFIX"
  exit 0
fi

command -v systemd-sysusers >/dev/null && systemd-sysusers /etc/sysusers.d/rover.conf
# The units run as group rover: it reads the key; others get nothing.
if getent group rover >/dev/null; then
  chgrp rover "$KEY" && chmod g+r,g-wx,o-rwx "$KEY"
else
  note "warning: no group rover here: the units cannot read ${KEY} until it is group rover, mode 0640"
fi
command -v sysctl >/dev/null && sysctl -q -p /etc/sysctl.d/90-rover-lcm.conf
if [ ! -d /run/systemd/system ]; then
  note "warning: systemd is not running here: files installed, daemon-reload and enable skipped"
  exit 0
fi
systemctl daemon-reload
if [ "$ENABLE" -eq 1 ] && [ "${#enable_units[@]}" -gt 0 ]; then
  systemctl --quiet enable "${enable_units[@]}"
fi
note "installed ${#installed_units[@]} units. Edit /etc/rover/rover.env (ROVER_LCM_IFACE), then:"
note "  systemctl start rover.target        (rover-sim.target on a bench)"
note "  systemctl enable rover.target       (start at boot)"
note "  journalctl -f -u 'rover-*'"
