#!/usr/bin/env bash
# ./rover console --web --private NAME: the guide's way to watch a named private bus in a
# browser. The console runs inside the named namespace; this script, outside it, fetches
# the page and the state from 127.0.0.1:PORT as a browser on the desktop would, and finds
# the named bus's simulated stack in it (configs/deploy/sim_vo.yaml, launched as the guide
# says) with nothing dropped: the console, started by hand outside the stack's virtual-time
# barrier, follows its clock. Inside the namespace nothing
# listens on that port (its loopback is its own); the socket is the user's alone; another
# site's Host is refused; Ctrl-C ends the console and the forwarder and removes the socket.
# usage: web_private_test.sh ROOT BUILD
set -u
root="$1"
build="$2"
export ROVER_BUILD_DIR="$build" XDG_RUNTIME_DIR="$build/test-out/web_private"
rm -rf "$XDG_RUNTIME_DIR"
mkdir -p "$XDG_RUNTIME_DIR"
out="$XDG_RUNTIME_DIR"
command -v socat >/dev/null || { echo "[  SKIPPED ] socat is not installed (apt-get install socat, or ./rover setup)"; exit 77; }
command -v curl >/dev/null || { echo "[  SKIPPED ] curl is not installed"; exit 77; }
rover="$root/rover"
name="w$$"
port=$((20000 + $$ % 20000))
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
cleanup() {
  [ -n "${stack:-}" ] && kill "$stack" 2>/dev/null && wait "$stack" 2>/dev/null
  [ -n "${web:-}" ] && kill "$web" 2>/dev/null
  "$rover" private --name "$name" --stop >/dev/null 2>&1
}
trap cleanup EXIT

# The guide's steps: the stack on the named bus, then its web console.
(cd "$root" && exec "$rover" private --name "$name" "$rover" launch configs/deploy/sim_vo.yaml) >"$out/launch.txt" 2>&1 &
stack=$!
for _ in $(seq 100); do [ -f "$XDG_RUNTIME_DIR/rover-private-$(id -u)/$name.pid" ] && break; sleep 0.05; done
"$rover" console --web --private "$name" --port "$port" >"$out/console.txt" 2>&1 &
web=$!
for _ in $(seq 200); do grep -q "is at http://127.0.0.1:$port/" "$out/console.txt" && break; sleep 0.05; done
check "the console says where it is" "grep -q \"web console of private bus '$name' is at http://127.0.0.1:$port/\" '$out/console.txt'"
sock="$XDG_RUNTIME_DIR/rover-private-$(id -u)/$name.web.sock"
check "its socket is the user's alone (0600)" '[ "$(stat -c %a "$sock" 2>/dev/null)" = 600 ]'

# From here (outside the namespace), as a browser would.
curl -s -o "$out/page.html" -w '%{http_code}' "http://127.0.0.1:$port/" >"$out/page.code"
check "the page, from outside the namespace" 'grep -q 200 "$out/page.code" && grep -q "<canvas id=\"map\"" "$out/page.html"'
for _ in $(seq 150); do
  curl -s "http://127.0.0.1:$port/api/state" >"$out/state.json"
  grep -q '"sequence_executor"' "$out/state.json" && grep -q '"pose":{' "$out/state.json" && break
  sleep 0.2
done
check "the state carries the named bus's stack (heartbeats, a pose)" \
  'grep -q "\"sequence_executor\"" "$out/state.json" && grep -q "\"pose\":{" "$out/state.json"'
sleep 3  # rover time goes on (up to 50 times the wall clock)
curl -s "http://127.0.0.1:$port/api/state" >"$out/state2.json"
check "the console follows the stack's virtual clock: it dropped nothing" \
  'grep -Eq "\"name\":\"rover_web\",\"state\":\"ok\",\"age_s\":[0-9.e+-]+,\"dropped\":0," "$out/state2.json"'
# The events stream (the page's live feed) passes the forwarder.
curl -s -N --max-time 2 "http://127.0.0.1:$port/api/events" >"$out/events.txt"
check "the event stream passes the forwarder" 'grep -q "^data: {\"bus\"" "$out/events.txt"'
code="$(curl -s -o /dev/null -w '%{http_code}' -H "Host: evil.example:$port" "http://127.0.0.1:$port/api/state")"
check "another site's Host is refused (403, got $code)" '[ "$code" = 403 ]'
# Inside the namespace the port is not the console: the forwarder is outside.
inside="$("$rover" private --name "$name" curl -s -o /dev/null -w '%{http_code}' --max-time 3 "http://127.0.0.1:$port/")"
check "inside the namespace nothing listens on $port (got '$inside')" '[ "$inside" = 000 ]'
# rover_web runs in the named namespace, not this one.
web_pid="$(pgrep -n -f -- "--listen unix:$sock" || true)"
check "rover_web is in the named namespace" '[ -n "$web_pid" ] && [ "$(readlink /proc/$web_pid/ns/net)" != "$(readlink /proc/self/ns/net)" ] &&
  [ "$(readlink /proc/$web_pid/ns/net)" = "$("$rover" private --name "$name" readlink /proc/self/ns/net)" ]'

# SIGTERM (what Ctrl-C becomes in the script's trap) ends it all.
kill -TERM "$web"
for _ in $(seq 100); do kill -0 "$web" 2>/dev/null || break; sleep 0.05; done
check "SIGTERM ends the console" '! kill -0 "$web" 2>/dev/null'
web=""
check "the socket is gone" '[ ! -e "$sock" ]'
check "the port is closed" '! curl -s -o /dev/null --max-time 2 "http://127.0.0.1:$port/"'

# A second console on a port in use says so.
socat "TCP-LISTEN:$port,bind=127.0.0.1,reuseaddr" /dev/null &
blocker=$!
sleep 0.3
"$rover" console --web --private "$name" --port "$port" >"$out/busy.txt" 2>&1
rc=$?
kill "$blocker" 2>/dev/null
check "a port in use: exit 2 and why (rc $rc)" '[ "$rc" -eq 2 ] && grep -q "is 127.0.0.1:$port in use" "$out/busy.txt"'
"$rover" console --web --private "bad/name" >"$out/bad.txt" 2>&1
rc=$?
check "a bad name: exit 2, one line" '[ "$rc" -eq 2 ] && [ "$(wc -l <"$out/bad.txt")" -eq 1 ]'
exit "$fail"
