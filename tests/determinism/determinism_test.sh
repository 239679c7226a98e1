#!/bin/sh
# Determinism in virtual time (README, "Simulated time"): the demo scenario run on a quiet
# machine, beside two CPU burners, and at the unlimited rate must end the same and give
# the same log digest (the log less VO's ms_* wall-time fields). Run by ctest inside the
# private network namespace of `./rover test`.
# usage: determinism_test.sh BUILD_BIN_DIR SOURCE_DIR OUT_DIR
set -u
bin="$1"; src="$2"; out="$3"
rm -rf "$out"; mkdir -p "$out"
cd "$src" || exit 2

run() {  # name [scenario_runner args...]
  name="$1"; shift
  "$bin/scenario_runner" configs/scenarios/demo.yaml --out "$out/$name" --quiet --no-plot "$@" \
    >"$out/$name.txt" 2>&1
  rc=$?
  digest="$(sed -n 's/.*"log_digest": *"\([0-9a-f]*\)".*/\1/p' "$out/$name/summary.json" 2>/dev/null | head -1)"
  outcome="$(sed -n 's/.*"outcome": *"\([a-z_]*\)".*/\1/p' "$out/$name/summary.json" 2>/dev/null | head -1)"
  echo "$name: exit $rc, outcome ${outcome:-none}, digest ${digest:-none}, $(grep -o '[0-9.]* s wall' "$out/$name.txt")"
  eval "digest_$name=\$digest"
  eval "rc_$name=\$rc"
}

run quiet
# Two burners, one per core: the scheduler now decides who runs when.
sh -c 'while :; do :; done' & b1=$!
sh -c 'while :; do :; done' & b2=$!
run busy
kill "$b1" "$b2" 2>/dev/null
wait "$b1" "$b2" 2>/dev/null
run fastest --rate max

fail=0
for n in quiet busy fastest; do
  eval "rc=\$rc_$n; d=\$digest_$n"
  if [ "$rc" -ne 0 ]; then echo "FAIL: the $n run did not end as the demo expects (see $out/$n.txt)"; fail=1; fi
  if [ -z "$d" ]; then echo "FAIL: the $n run has no log digest in $out/$n/summary.json"; fail=1; fi
done
if [ "$digest_quiet" != "$digest_busy" ]; then echo "FAIL: two burners changed the log (digest $digest_quiet vs $digest_busy)"; fail=1; fi
if [ "$digest_quiet" != "$digest_fastest" ]; then echo "FAIL: the unlimited rate changed the log (digest $digest_quiet vs $digest_fastest)"; fail=1; fi
if [ "$fail" -eq 0 ]; then echo "PASS: the same log digest quiet, busy and at the unlimited rate"; fi
exit "$fail"
