#!/bin/bash
# The Slurm test's cluster side (slurm_test.cpp), run by slurm_cluster.sh on its one-node
# cluster, as a user types it: a 4-variant demo campaign and a 4-run navbench submitted as
# job arrays (./rover campaign|navbench --slurm); campaign task 2 cancelled while it runs
# (scancel JOB_2); the campaign merged (task 2 named missing), resumed (task 2 alone
# submitted again) and merged again; the navbench merged.
#   slurm_flow.sh ROOT OUT SEED 'NAVBENCH ARGS'
# Writes OUT/slurm_campaign and OUT/slurm_navbench (the runs), and each step's output and
# exit status as OUT/STEP.txt and OUT/STEP.code. Exit 1 when a step could not be taken.
set -u
root="$1" out="$2" seed="$3" navbench_args="$4"
camp="$out/slurm_campaign" nb="$out/slurm_navbench"
cd "$root" || exit 1
rm -rf "$camp" "$nb"
fail() { echo "slurm_flow: $*" >&2; exit 1; }

# step NAME CMD...: CMD's output to OUT/NAME.txt, its exit status to OUT/NAME.code.
step() {
  local name="$1"
  shift
  "$@" >"$out/$name.txt" 2>&1
  echo "$?" >"$out/$name.code"
  echo "slurm_flow: $name: exit $(cat "$out/$name.code")" >&2
}

# Waits until Slurm's queue is empty (every task ended), up to $1 s.
drain() {
  local i
  for ((i = 0; i < $1 * 2; i++)); do
    squeue -h -o %i | grep -q . || return 0
    sleep 0.5
  done
  squeue >&2
  fail "tasks still queued or running after $1 s"
}

step submit_campaign ./rover campaign configs/scenarios/demo.yaml --variants 4 --seed "$seed" --no-plot \
  --out "$camp" --slurm --cpus-per-task 1
[ "$(cat "$out/submit_campaign.code")" = 0 ] || fail "campaign --slurm: $(tail -n 1 "$out/submit_campaign.txt")"
# shellcheck disable=SC2086  # the navbench's arguments are words
step submit_navbench ./rover navbench $navbench_args --out "$nb" --slurm --sbatch-arg=--cpus-per-task=1
[ "$(cat "$out/submit_navbench.code")" = 0 ] || fail "navbench --slurm: $(tail -n 1 "$out/submit_navbench.txt")"

# Task 2 of the campaign, cancelled once its run is recording (mid-run).
job="$(awk 'NR == 1 { print $1 }' "$camp/slurm/jobs.txt")"
for ((i = 0; i < 1200; i++)); do
  [ -f "$camp/v2/log.lcm" ] && [ -f "$camp/slurm/status/2.start" ] && break
  sleep 0.5
done
[ -f "$camp/v2/log.lcm" ] || fail "campaign task 2 did not start its run in 600 s"
[ -f "$camp/slurm/status/2.exit" ] && fail "campaign task 2 ended before it could be cancelled"
squeue -h -r -o "%i %T" -j "$job" >"$out/queue_at_cancel.txt"
scancel "${job}_2" || fail "scancel ${job}_2 failed"
drain 1200

step merge_cancelled ./rover campaign --merge "$camp"
cp "$camp/campaign.json" "$out/campaign_cancelled.json"
step resume ./rover campaign --resume "$camp"
drain 600
step merge_campaign ./rover campaign --merge "$camp"
step merge_navbench ./rover navbench --merge "$nb"
exit 0
