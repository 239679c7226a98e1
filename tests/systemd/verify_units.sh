#!/usr/bin/env bash
# Installs the rover units into a staging root with configs/systemd/install.sh --prefix,
# then runs `systemd-analyze verify --root=STAGE` on every unit. Fails on a non-zero
# exit AND on any message: systemd-analyze 252 only warns (exit 0) about an unknown key
# or a value it cannot parse ("Restat=", "Restart=sometimes"), and those are the likely
# mistakes. Exit 77 (CTest SKIP_RETURN_CODE) when systemd-analyze is not available.
#
# usage: verify_units.sh SOURCE_DIR BUILD_DIR [UNIT_DIR]
#   UNIT_DIR defaults to SOURCE_DIR/configs/systemd (another directory: prove the test
#   fails on a broken copy).
set -uo pipefail

SRC="${1:?usage: verify_units.sh SOURCE_DIR BUILD_DIR [UNIT_DIR]}"
BUILD="${2:?usage: verify_units.sh SOURCE_DIR BUILD_DIR [UNIT_DIR]}"
UNIT_DIR="${3:-$SRC/configs/systemd}"

fail() { echo "FAIL: $*" >&2; exit 1; }

if ! command -v systemd-analyze >/dev/null; then
  echo "SKIP: systemd-analyze not found (install systemd to verify the rover units)"
  exit 77
fi
# Units depend on sysinit.target, network-online.target...: the host's own unit files
# stand in for the rover computer's inside the staging root.
HOST_UNITS=""
for d in /usr/lib/systemd/system /lib/systemd/system; do
  [ -f "$d/sysinit.target" ] && { HOST_UNITS="$d"; break; }
done
if [ -z "$HOST_UNITS" ]; then
  echo "SKIP: no systemd unit files on this host (sysinit.target), nothing to verify against"
  exit 77
fi

STAGE="$(mktemp -d "${TMPDIR:-/tmp}/rover-systemd-stage.XXXXXX")" || fail "mktemp"
trap 'rm -rf "$STAGE"' EXIT

# A build tree for install.sh: the real binaries where built; a placeholder executable
# for a process whose target is not built here (verify needs ExecStart to exist).
FAKE_BUILD="$STAGE.build"
mkdir -p "$FAKE_BUILD/bin"
trap 'rm -rf "$STAGE" "$FAKE_BUILD"' EXIT
for unit in "$UNIT_DIR"/*.service; do
  bin="$(sed -n 's|^ExecStart=/opt/rover/bin/\([^ ]*\).*|\1|p' "$unit")"
  [ -n "$bin" ] || continue
  if [ -x "$BUILD/bin/$bin" ]; then
    ln -s "$BUILD/bin/$bin" "$FAKE_BUILD/bin/$bin"
  else
    echo "note: $bin is not built in $BUILD: $(basename "$unit") is verified against a placeholder binary"
    printf '#!/bin/sh\nexit 0\n' > "$FAKE_BUILD/bin/$bin"
    chmod +x "$FAKE_BUILD/bin/$bin"
  fi
done

# The system tools units run, from the host (iproute2 and liblcm-bin are project packages).
mkdir -p "$STAGE/usr/lib/systemd" "$STAGE/usr/bin" "$STAGE/usr/sbin"
cp -a "$HOST_UNITS" "$STAGE/usr/lib/systemd/system"
for tool in $(sed -n 's|^-\{0,1\}ExecStart=\(/usr/[^ ]*\).*|\1|p' "$UNIT_DIR"/*.service | sort -u); do
  [ -x "$tool" ] || fail "$tool (run by a unit) is not installed on this host"
  cp -L "$tool" "$STAGE$tool"
done

out="$(bash "$SRC/configs/systemd/install.sh" --prefix "$STAGE" --build-dir "$FAKE_BUILD" 2>&1)" ||
  fail "install.sh --prefix: $out"
if echo "$out" | grep -q "warning"; then fail "install.sh warned: $out"; fi
# Another unit directory (a deliberately broken copy): its units replace the installed ones.
if [ "$UNIT_DIR" != "$SRC/configs/systemd" ]; then
  cp "$UNIT_DIR"/*.service "$UNIT_DIR"/*.target "$STAGE/etc/systemd/system/"
fi

units=()
for unit in "$UNIT_DIR"/*.service "$UNIT_DIR"/*.target; do
  name="$(basename "$unit")"
  [ -f "$STAGE/etc/systemd/system/$name" ] || fail "install.sh did not install $name"
  units+=("$name")
done
[ "${#units[@]}" -gt 0 ] || fail "no units in $UNIT_DIR"

# Enabled into their targets: what `systemctl start rover.target` will start.
for name in "${units[@]}"; do
  target="$(sed -n 's/^WantedBy=//p' "$STAGE/etc/systemd/system/$name")"
  [ -z "$target" ] || [ "$name" = rover.target ] && continue
  [ -L "$STAGE/etc/systemd/system/$target.wants/$name" ] || fail "$name is not enabled into $target"
done

# One call: systemd-analyze loads every unit in the root anyway, so a broken unit shows
# once, named by file and line.
msg="$(systemd-analyze verify --root="$STAGE" --man=no --generators=no "${units[@]}" 2>&1)"
rc=$?
if [ $rc -ne 0 ] || [ -n "$msg" ]; then
  echo "FAIL: systemd-analyze verify (exit $rc; any message counts as a failure):" >&2
  echo "$msg" | sed "s|$STAGE||; s/^/  /" >&2
  exit 1
fi
echo "verified ${#units[@]} units (${units[*]}) with $(systemd-analyze --version | head -n 1)"
