#!/usr/bin/env bash
# A full disk must not pass for a good record. On a small tmpfs (a mount namespace of this
# test's own, unshare -rm: no privilege needed):
#   1. rover_recorder writing past the free space: its closing report says
#      "log complete: no (writing the log failed ...)" and it exits 1;
#   2. the scenario runner with --out there: it says THE LOG IS NOT WHOLE with the
#      executor's own last status, never "wrote .../summary.json", and exits 1.
# Exit 77 (skipped) when no user and mount namespace can be made. Run it on a private bus:
#   ./rover private ctest --test-dir build -R OperatorFullDisk
# usage: full_disk_test.sh ROOT BUILD PUBLISHER
set -u
root="$1"
build="$2"
publisher="$3"
out="$build/test-out/full_disk"
rm -rf "$out"
mkdir -p "$out/disk"
unshare -rm true 2>/dev/null || { echo "SKIP: cannot make a user and mount namespace (unshare -rm)"; exit 77; }

cat >"$out/inside.sh" <<'INSIDE'
set -u
root="$1"; build="$2"; publisher="$3"; out="$4"
disk="$out/disk"
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
mount -t tmpfs -o size=192k tmpfs "$disk" || { echo "FAIL: cannot mount a tmpfs"; exit 1; }

# 1. The recorder: 64 KiB free, a publisher sending ~150 KB/s for 2 s.
head -c 131072 /dev/zero >"$disk/filler"
url="udpm://239.255.76.72:$((32000 + $$ % 380 * 2))?ttl=0"
"$build/bin/rover_recorder" --lcm-url "$url" "$disk/log.lcm" 2>"$out/recorder.txt" &
rec=$!
sleep 0.5
"$publisher" --lcm-url "$url" --seconds 2 --period-ms 2 >/dev/null 2>&1
kill "$rec"
wait "$rec"
rc=$?
cat "$out/recorder.txt" | tail -n 5
check "the recorder exits 1 when its writes failed (exit $rc)" '[ "$rc" -eq 1 ]'
check "its closing report says the log is not complete, and why" \
  'grep -q "^log complete: no (.*writing the log failed" "$out/recorder.txt"'
check "it does not say the log is complete" '! grep -q "^log complete: yes" "$out/recorder.txt"'
rm -f "$disk/filler" "$disk/log.lcm"

# 2. The scenario runner, its --out on the same 192 KiB: the log does not fit.
cd "$root"
"$build/bin/scenario_runner" configs/scenarios/keepout_abort.yaml --out "$disk/run" --rate max --no-plot \
  >"$out/runner.txt" 2>&1
rc=$?
tail -n 12 "$out/runner.txt"
check "the runner exits 1 (exit $rc)" '[ "$rc" -eq 1 ]'
check "it says the log is not whole" 'grep -q "THE LOG IS NOT WHOLE" "$out/runner.txt"'
check "it names how the executor said the drive ended" 'grep -q "on the bus the executor reported the sequence aborted (keepout)" "$out/runner.txt"'
check "it does not claim to have written summary.json" '! grep -q "wrote .*summary.json" "$out/runner.txt"'
exit "$fail"
INSIDE
unshare -rm bash "$out/inside.sh" "$root" "$build" "$publisher" "$out"
