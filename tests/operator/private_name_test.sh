#!/usr/bin/env bash
# ./rover private --name NAME: separate commands, each started on its own, share one
# private bus. A recorder started by one call is heard by a console started by another
# call with the same name; a name that is not there is not joined (one line naming the
# buses there are, exit 2), unless --make makes it; the namespace is not the caller's;
# --stop ends it and whatever still runs on it, and a second --stop says there is none.
# usage: private_name_test.sh ROOT BUILD
set -u
root="$1"
build="$2"
export ROVER_BUILD_DIR="$build" XDG_RUNTIME_DIR="$build/test-out/private_name"
rm -rf "$XDG_RUNTIME_DIR"
mkdir -p "$XDG_RUNTIME_DIR"
rover="$root/rover"
name="t$$"
url="udpm://239.255.76.67:7667?ttl=0"
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
cleanup() {
  [ -n "${rec:-}" ] && kill "$rec" 2>/dev/null
  "$rover" private --name "$name" --stop >/dev/null 2>&1
  "$rover" private --name "${name}b" --stop >/dev/null 2>&1
}
trap cleanup EXIT

mine="$(readlink /proc/self/ns/net)"
first="$("$rover" private --name "$name" --make readlink /proc/self/ns/net 2>"$XDG_RUNTIME_DIR/made.txt")"
second="$("$rover" private --name "$name" readlink /proc/self/ns/net)"
check "the first call made it and said so" "grep -q \"private bus '$name' made\" '$XDG_RUNTIME_DIR/made.txt'"
check "two calls, one namespace ($first, $second)" '[ -n "$first" ] && [ "$first" = "$second" ]'
check "not the caller's namespace ($mine)" '[ "$first" != "$mine" ]'
check "multicast routed to loopback" '"$rover" private --name "$name" ip route | grep -q "224.0.0.0/4 dev lo"'

# A recorder (heartbeats once a second) in one call; consoles in others.
"$rover" private --name "$name" "$build/bin/rover_recorder" --lcm-url "$url" "$XDG_RUNTIME_DIR/bus.lcm" \
  >"$XDG_RUNTIME_DIR/recorder.txt" 2>&1 &
rec=$!
"$rover" private --name "$name" "$build/bin/rover_console" --once --wait 3 --lcm-url "$url" >"$XDG_RUNTIME_DIR/same.txt" 2>&1
same=$?
"$rover" private --name "${name}b" "$build/bin/rover_console" --once --wait 3 --lcm-url "$url" >"$XDG_RUNTIME_DIR/typo.txt" 2>&1
typo=$?
"$rover" private --name "${name}b" --make "$build/bin/rover_console" --once --wait 3 --lcm-url "$url" >"$XDG_RUNTIME_DIR/other.txt" 2>&1
other=$?
check "a console in the same named bus hears the recorder" '[ "$same" -eq 0 ] && grep -q "rover_recorder" "$XDG_RUNTIME_DIR/same.txt"'
check "a name that is not there: exit 2, one line naming the buses there are" \
  '[ "$typo" -eq 2 ] && [ "$(wc -l <"$XDG_RUNTIME_DIR/typo.txt")" -eq 1 ] && grep -q "there are: $name" "$XDG_RUNTIME_DIR/typo.txt"'
check "a console in another named bus (--make) hears nothing (exit 3)" '[ "$other" -eq 3 ]'
kill "$rec"
wait "$rec"
rec=""
check "the recorder stopped cleanly" 'grep -q "rover_recorder: wrote" "$XDG_RUNTIME_DIR/recorder.txt"'

# A process still on the bus ends with it (SIGTERM: the recorder writes its log and exits).
"$rover" private --name "$name" "$build/bin/rover_recorder" --lcm-url "$url" "$XDG_RUNTIME_DIR/left.lcm" \
  >"$XDG_RUNTIME_DIR/left.txt" 2>&1 &
left=$!
for _ in $(seq 50); do grep -q "recording" "$XDG_RUNTIME_DIR/left.txt" 2>/dev/null && break; sleep 0.1; done
check "--stop ends it" '"$rover" private --name "$name" --stop | grep -q "stopped (1 processes on it ended)"'
check "the process left on the bus was stopped, and cleanly" '! kill -0 "$left" 2>/dev/null && grep -q "rover_recorder: wrote" "$XDG_RUNTIME_DIR/left.txt"'
"$rover" private --name "$name" --stop >"$XDG_RUNTIME_DIR/again.txt" 2>&1
rc=$?
check "a second --stop: exit 2, one line" '[ "$rc" -eq 2 ] && [ "$(wc -l <"$XDG_RUNTIME_DIR/again.txt")" -eq 1 ]'
"$rover" private --name "bad/name" true >"$XDG_RUNTIME_DIR/bad.txt" 2>&1
rc=$?
check "a bad name: exit 2, one line" '[ "$rc" -eq 2 ] && grep -q "expected a name of letters" "$XDG_RUNTIME_DIR/bad.txt"'
exit "$fail"
