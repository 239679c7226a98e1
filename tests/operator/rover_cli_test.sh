#!/usr/bin/env bash
# ./rover as a user types it, away from the repository root (issue 44's paper cuts):
# relative paths from the folder it is run in (inputs and --out), a path found nowhere named
# with both folders; --help of every subcommand without a build; console --help names the
# web console; private --help; joining a named private bus that is not there; rover_seq's
# exit 2 on a bad bus URL.
# usage: rover_cli_test.sh ROOT BUILD
set -u
root="$1"
build="$2"
rover="$root/rover"
work="$build/test-out/rover_cli"
rm -rf "$work"
mkdir -p "$work/here" "$work/empty_build" "$work/runtime"
export XDG_RUNTIME_DIR="$work/runtime"
fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
lines() { wc -l <"$1"; }

# ---- relative paths, from a folder that is not the root ----
cd "$work/here"
printf 'drive 1 m\nturn 10 deg\n' >my.seq
ROVER_BUILD_DIR="$build" "$rover" seq check my.seq >check.txt 2>&1
check "seq check my.seq from another folder reads ./my.seq (exit 0)" '[ $? -eq 0 ]'
ROVER_BUILD_DIR="$build" "$rover" seq check missing.seq >missing.txt 2>&1
rc=$?
check "a file found nowhere: exit 2, one line naming it, this folder and the root" \
  '[ "$rc" -eq 2 ] && [ "$(lines missing.txt)" -eq 1 ] && grep -q "missing.seq: no such file" missing.txt &&
   grep -qF "$work/here, where ./rover was run" missing.txt && grep -qF "and in $root" missing.txt'
ROVER_BUILD_DIR="$build" "$rover" seq check configs/sequences/demo.seq >root_rel.txt 2>&1
check "a path from the root still works from elsewhere (configs/sequences/demo.seq)" '[ $? -eq 0 ]'
# An OpenCV calibration in millimetres, imported with --t-unit mm to a relative --out.
cat >cal.yaml <<'EOF'
%YAML:1.0
---
image_width: 640
image_height: 480
K1: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]
K2: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]
R: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 1., 0., 0., 0., 1., 0., 0., 0., 1. ]
T: !!opencv-matrix
   rows: 3
   cols: 1
   dt: d
   data: [ -200., 0., 0. ]
EOF
mkdir -p rigs
mount="--left-position 0,0,-1 --left-rpy 0,-20,0"
ROVER_BUILD_DIR="$build" "$rover" calib import --opencv cal.yaml $mount --out rigs/rig.yaml >mm.txt 2>&1
rc=$?
check "calib import of a millimetre file with no --t-unit: exit 2, one line naming 200 m and --t-unit mm" \
  '[ "$rc" -eq 2 ] && [ "$(lines mm.txt)" -eq 1 ] && grep -q "baseline 200 m" mm.txt && grep -q -- "--t-unit mm" mm.txt && [ ! -e rigs/rig.yaml ]'
ROVER_BUILD_DIR="$build" "$rover" calib import --opencv cal.yaml --t-unit mm $mount --out rigs/rig.yaml >import.txt 2>&1
check "--out rigs/rig.yaml lands in the folder ./rover was run in, not the root" \
  '[ $? -eq 0 ] && [ -f "$work/here/rigs/rig.yaml" ] && [ ! -e "$root/rigs/rig.yaml" ] && grep -q "Baseline 0.2 m" rigs/rig.yaml'
ROVER_BUILD_DIR="$build" "$rover" calib import --opencv cal.yaml --t-unit mm $mount --out rigs/rig.yaml >again.txt 2>&1
check "an existing --out is kept: exit 2, one line" '[ $? -eq 2 ] && [ "$(lines again.txt)" -eq 1 ] && grep -q "exists; kept" again.txt'

# ---- --help without a build: the script's own text, no cmake ----
for sub in launch scenario plot "seq submit" "calib import" conformance logcheck; do
  # shellcheck disable=SC2086
  ROVER_BUILD_DIR="$work/empty_build" timeout 20 "$rover" $sub --help >help.txt 2>&1
  rc=$?
  first="${sub%% *}"
  check "./rover $sub --help with nothing built: exit 0, its usage, no build" \
    '[ "$rc" -eq 0 ] && grep -q "^  $first" help.txt && grep -q "not built yet" help.txt && [ ! -e "$work/empty_build/CMakeCache.txt" ]'
done

# ---- console --help names the web console ----
for b in "$build" "$work/empty_build"; do
  ROVER_BUILD_DIR="$b" timeout 20 "$rover" console --help >console.txt 2>&1
  rc=$?
  check "console --help (build $(basename "$b")) names --web, --web --private NAME, --web --log and rover_web --help" \
    '[ "$rc" -eq 0 ] && grep -q -- "console --web \[--port P\]" console.txt && grep -q -- "--web --private NAME" console.txt &&
     grep -q -- "--web --log LOG.lcm" console.txt && grep -q "rover_web --help" console.txt'
done
check "console --help with the console built also prints its own options" 'ROVER_BUILD_DIR="$build" "$rover" console --help | grep -q -- "--once"'

# ---- private --help; joining a bus that is not there ----
"$rover" private --help >private_help.txt 2>&1
check "private --help: exit 0, its usage" '[ $? -eq 0 ] && grep -q "^usage: ./rover private" private_help.txt && grep -q -- "--make" private_help.txt'
"$rover" private --name "cli$$" --help >/dev/null 2>&1
check "private --name N --help: exit 0" '[ $? -eq 0 ]'
"$rover" private >noargs.txt 2>&1
check "private with no CMD: exit 2, one line" '[ $? -eq 2 ] && [ "$(lines noargs.txt)" -eq 1 ]'
name="cli$$"
"$rover" private --name "$name" --make true 2>made.txt
check "--make makes a named bus and says so" '[ $? -eq 0 ] && grep -q "private bus '"'$name'"' made" made.txt'
"$rover" private --name "${name}x" "$build/bin/rover_console" --once --wait 3 >typo.txt 2>&1
rc=$?
check "a mistyped name: exit 2, one line naming the buses there are" \
  '[ "$rc" -eq 2 ] && [ "$(lines typo.txt)" -eq 1 ] && grep -q "no private bus named '"'${name}x'"'" typo.txt && grep -q "there are: .*$name" typo.txt'
check "and no bus was made for it" '! "$rover" private --list | grep -qx "${name}x" && "$rover" private --list | grep -qx "$name"'
"$rover" private --name "$name" --stop >/dev/null
"$rover" private --name "$name" true >gone.txt 2>&1
check "after --stop, joining it fails and names none" '[ $? -eq 2 ] && grep -q "there are: " gone.txt'

# ---- rover_seq: a bad bus URL is a bad argument (exit 2, one line) ----
for url in "udpm://10.1.2.3:7667" "udpm://239.255.76.67:99999" "tcp://x"; do
  "$build/bin/rover_seq" status --lcm-url "$url" >url.txt 2>&1
  rc=$?
  check "rover_seq status --lcm-url $url: exit 2, one line naming it" \
    '[ "$rc" -eq 2 ] && [ "$(lines url.txt)" -eq 1 ] && grep -qF "$url" url.txt'
done
"$build/bin/rover_seq" pause --lcm-url >url.txt 2>&1
check "rover_seq --lcm-url with no value: exit 2" '[ $? -eq 2 ] && [ "$(lines url.txt)" -eq 1 ]'
check "rover_seq --help documents its exit codes" '"$build/bin/rover_seq" --help | grep -q "^Exit codes: 0 done"'
exit "$fail"
