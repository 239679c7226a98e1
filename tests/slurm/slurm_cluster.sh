#!/bin/bash
# A one-node Slurm cluster of Debian's own daemons (slurmctld, slurmd, munged), for as long as
# CMD runs:   tests/slurm/slurm_cluster.sh DIR CMD [ARG...]
# Everything it makes is in DIR: the munge key, socket, pid and log; slurm.conf; the daemons'
# state, spool, pids and logs. CMD runs with SLURM_CONF set, so sbatch, squeue and scancel
# (and ./rover campaign --slurm) use the cluster. On the way out, also on failure or a signal,
# it cancels every job left and stops every daemon it started.
# Exit status: CMD's; 77, with the reason on stderr, when the cluster cannot be made here.
#
# The cluster lives in namespaces of its own, which works as root, as a user allowed user
# namespaces, and inside ./rover private (where ./rover test runs ctest):
#  - a network namespace: its loopback has the cluster to itself, so the fixed ports below are
#    free, and no Slurm traffic leaves it. Loopback gets a second address, 10.254.254.1,
#    because Slurm resolves 127.0.0.1 with getaddrinfo(AF_INET, AI_ADDRCONFIG), which glibc
#    answers "Name or service not known" on a host whose only IPv4 address is 127.0.0.1.
#  - a user namespace in which this user is "nobody" (65534): slurmd and slurmctld, started as
#    root, drop supplementary groups with setgroups(), which a user namespace made by an
#    unprivileged user refuses (/proc/self/setgroups is "deny"; ./rover private's is). Started
#    as another user they skip that, and slurmd then runs the jobs of that same user, as
#    SlurmUser=SlurmdUser=nobody. munged runs as that user as well (--force: its directories
#    are not root's), with its key, socket, pid, log and seed files in DIR.
set -u
dir="${1:?usage: slurm_cluster.sh DIR CMD [ARG...]}"
shift
[ "$#" -gt 0 ] || { echo "usage: slurm_cluster.sh DIR CMD [ARG...]" >&2; exit 2; }
self="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/$(basename "${BASH_SOURCE[0]}")"
skip() { echo "slurm_cluster: cannot make a Slurm cluster here: $*" >&2; exit 77; }

case "${ROVER_SLURM_STAGE:-}" in
  "")  # here: the tools, then a network namespace of the cluster's own
    for tool in munged munge slurmctld slurmd sbatch squeue scancel sinfo unshare ip; do
      command -v "$tool" >/dev/null || skip "$tool is not installed (Debian: slurmctld slurmd slurm-client munge)"
    done
    mkdir -p "$dir" || exit 1
    dir="$(cd "$dir" && pwd)"
    net=(unshare -n)
    [ "$(id -u)" -eq 0 ] || net=(unshare -rn)
    "${net[@]}" true 2>/dev/null || skip "'${net[*]}' failed: no network namespace for the cluster"
    exec env ROVER_SLURM_STAGE=net "${net[@]}" "$self" "$dir" "$@" ;;
  net)  # in the cluster's network namespace: loopback's addresses, then the user namespace
    ip link set lo up && ip addr add 10.254.254.1/32 dev lo \
      || skip "cannot configure loopback in the cluster's network namespace"
    unshare -U --map-user=65534 --map-group=65534 true 2>/dev/null \
      || skip "unshare -U --map-user=65534 failed: no user namespace for the daemons"
    exec env ROVER_SLURM_STAGE=cluster unshare -U --map-user=65534 --map-group=65534 "$self" "$dir" "$@" ;;
  cluster) ;;
  *) echo "slurm_cluster: unknown ROVER_SLURM_STAGE '$ROVER_SLURM_STAGE'" >&2; exit 2 ;;
esac

# In the cluster's namespaces, as "nobody".
user="$(id -un)"
pids=()
watchdog=""
stop() {
  local code=$? p
  trap - EXIT INT TERM
  [ -z "$watchdog" ] || kill "$watchdog" 2>/dev/null
  if [ -n "${SLURM_CONF:-}" ] && squeue -h -o %i 2>/dev/null | grep -q .; then
    scancel -u "$user" 2>/dev/null
    for _ in $(seq 100); do squeue -h -o %i 2>/dev/null | grep -q . || break; sleep 0.2; done
  fi
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  for _ in $(seq 50); do
    local alive=0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ "$alive" -eq 0 ] && break
    sleep 0.1
  done
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null
  exit "$code"
}
trap stop EXIT
trap 'exit 143' INT TERM

rm -rf "$dir/munge" "$dir/state" "$dir/spool"
mkdir -p "$dir/munge" "$dir/state" "$dir/spool"
chmod 700 "$dir/munge"
head -c 1024 /dev/urandom >"$dir/munge/munge.key" && chmod 400 "$dir/munge/munge.key"
socket="$dir/munge/munge.socket"
munged -F --force --key-file="$dir/munge/munge.key" --socket="$socket" --pid-file="$dir/munge/munged.pid" \
  --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/munged.seed" >"$dir/munge/munged.out" 2>&1 &
pids+=("$!")
for _ in $(seq 100); do [ -S "$socket" ] && break; sleep 0.05; done
munge -n -S "$socket" | unmunge -S "$socket" >/dev/null 2>&1 \
  || skip "munged did not start ($(tail -n 1 "$dir/munge/munged.out" "$dir/munge/munged.log" 2>/dev/null | grep -v '^==' | grep . | tail -n 1))"

# The node as slurmd sees this machine (CPUs, sockets, cores, threads, memory).
node="$(slurmd -C 2>/dev/null | head -n 1 | sed -e 's/^NodeName=[^ ]* *//' -e 's/ *UpTime=.*//')"
[[ "$node" == CPUs=* ]] || skip "slurmd -C did not describe this machine: '$node'"
cat >"$dir/slurm.conf" <<EOF
# A one-node cluster for the Slurm test (tests/slurm/slurm_cluster.sh): no cgroups, no accounting.
ClusterName=rovertest
SlurmctldHost=localhost(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
SlurmctldPort=6817
SlurmdPort=6818
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
NodeName=localhost NodeAddr=127.0.0.1 $node State=UNKNOWN
PartitionName=rover Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$dir/slurm.conf"
rm -f "$dir/slurmctld.log" "$dir/slurmd.log"
slurmctld -D -i -f "$SLURM_CONF" >"$dir/slurmctld.out" 2>&1 &
pids+=("$!")
slurmd -D -f "$SLURM_CONF" -N localhost >"$dir/slurmd.out" 2>&1 &
pids+=("$!")
# Should this script be killed outright (no trap runs on SIGKILL), the daemons follow it.
( while kill -0 $$ 2>/dev/null; do sleep 1; done; kill -TERM "${pids[@]}" 2>/dev/null ) &
watchdog="$!"
# The node is up when sinfo says idle; a daemon that exits before is one that cannot run here.
state=""
for _ in $(seq 300); do
  state="$(sinfo -h -o %T 2>/dev/null)"
  [ "$state" = idle ] && break
  for name in slurmctld slurmd; do
    pid="${pids[1]}"; [ "$name" = slurmd ] && pid="${pids[2]}"
    kill -0 "$pid" 2>/dev/null \
      || skip "$name exited at start: $(grep . "$dir/$name.out" "$dir/$name.log" 2>/dev/null | tail -n 1)"
  done
  sleep 0.2
done
[ "$state" = idle ] || { echo "slurm_cluster: the node is '$state', not idle, after 60 s (see $dir/slurmctld.log, $dir/slurmd.log)" >&2; exit 1; }
echo "slurm_cluster: one-node cluster up in $dir ($node)" >&2

"$@"
