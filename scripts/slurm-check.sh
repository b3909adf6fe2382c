#!/usr/bin/env bash
# Runs the README's job array (scripts/slurm-array.sh, gathered by scripts/slurm-gather.sh) on
# a real Slurm and checks that the gathered sequence equals one uninterrupted run:
#
#   1. installs Debian's slurm-wlm and munge (idempotent, like scripts/setup.sh);
#   2. starts munged, slurmctld and one slurmd on this machine as root, on loopback, with
#      their configuration, key, state and logs in a temporary directory (no systemd, no
#      cgroups: proctrack/linuxproc, task/none);
#   3. simulates scenes/tiny.toml, renders it whole, submits the array over it in slices,
#      waits, gathers, and compares: the same frame files, byte for byte, and stats.csv rows
#      equal in every column but the timing and the per-slice integration columns (below);
#   4. stops the daemons and removes the directory, also on failure or Ctrl-C.
#
# Needs root and target/release/dormant (`make slurm-check` builds it first). Exits 0 when
# everything matched, 1 with a message naming the mismatch otherwise.
# SLURM_CHECK_KEEP=1 keeps the temporary directory (logs, frames) for a look afterwards.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin="$root/target/release/dormant"

# The check's sequence: tiny's whole 480-frame simulation, every 2nd frame at 80x45 with EXR
# files beside the PNGs, in 11 slices of 45 frames: more than 10 slices (the gather's order),
# slices starting off the step grid (45, 135, ...) and a short last slice (450..480).
frames=480
per_task=45
tasks=$(( (frames + per_task - 1) / per_task ))
render_args="--size 80x45 --spp 2 --frame-step 2 --exr"
timeout_s=${SLURM_CHECK_TIMEOUT:-600}

# stats.csv columns that may differ between the joined slices and the whole run:
#   timing: wall-clock times of the stages and of the horizon queries, and rays per second;
#   integration: each slice starts a fresh scene manager and cost model, which decides for
#   every island already asleep at its first frame and cannot see the sequence past its last
#   one, so the integration decisions and what follows from them (the scene's make-up, the
#   cache, commits, the estimates) are the slice's own. They do not change the images.
timing_columns="physics_ms update_ms integrate_ms reactivate_ms commit_ms trace_ms frame_ms mrays_per_second
horizon_ms"
integration_columns="committed instances integrated_islands baked_bodies resting_bodies rest_rebuilt
islands_integrated islands_reactivated cache_full cache_partial cache_miss decisions
decisions_integrate decisions_decline estimated_net_ms"

say() { printf 'slurm-check: %s\n' "$*"; }
die() { printf 'slurm-check: FAILED: %s\n' "$*" >&2; exit 1; }

[ "$(id -u)" -eq 0 ] || die "run as root: it installs packages and starts Slurm's daemons as root"
[ -x "$bin" ] || die "no $bin: build it first (make build, or make slurm-check)"
started=$(date +%s)

# --- packages ------------------------------------------------------------------------------
packages=(slurm-wlm munge)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
    say "apt packages present: ${packages[*]}"
else
    say "installing apt packages: ${missing[*]}"
    apt-get update -qq >/dev/null
    # The packages' own services are not started: Debian's policy-rc.d denies it in a
    # container, and elsewhere they would find no configuration; this script runs its own.
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
for c in munged mungekey munge unmunge slurmctld slurmd sbatch scontrol sinfo squeue scancel; do
    command -v "$c" >/dev/null 2>&1 || die "$c not found after installing ${packages[*]}"
done

# --- a private Slurm -------------------------------------------------------------------------
tmp=$(mktemp -d "${TMPDIR:-/tmp}/dormant-slurm.XXXXXX")
chmod 700 "$tmp"   # munged refuses a key or socket in a directory others can write to
mkdir -p "$tmp"/{munge,etc,state,spool,run,log,work}
munged_pid="" slurmctld_pid="" slurmd_pid="" job=""

stop() {   # stop PID NAME: TERM, up to 10 s, then KILL
    local pid=$1 name=$2
    [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null || return 0
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    if kill -0 "$pid" 2>/dev/null; then
        say "$name ($pid) ignored SIGTERM; killing it"
        kill -9 "$pid" 2>/dev/null || true
    fi
    wait "$pid" 2>/dev/null || true
}
cleanup() {
    local rc=$?
    set +e
    trap - EXIT INT TERM
    if [ -n "$job" ] && [ -n "$slurmctld_pid" ] && kill -0 "$slurmctld_pid" 2>/dev/null; then
        scancel "$job" 2>/dev/null
        # Let slurmd kill the tasks before it goes itself, so no slurmstepd outlives the check.
        for _ in $(seq 50); do [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break; sleep 0.2; done
    fi
    stop "$slurmd_pid" slurmd
    stop "$slurmctld_pid" slurmctld
    stop "$munged_pid" munged
    if [ "$rc" -ne 0 ]; then
        for f in "$tmp"/log/*; do
            [ -s "$f" ] || continue
            printf '\n--- last lines of %s ---\n' "${f#"$tmp"/}" >&2
            tail -n 15 "$f" >&2
        done
    fi
    if [ "${SLURM_CHECK_KEEP:-0}" = 1 ]; then
        say "kept $tmp"
    else
        rm -rf "$tmp"
    fi
    say "stopped Slurm and munge$([ "$rc" -eq 0 ] || echo " after the failure above")"
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# munge: a generated key, our own socket; Slurm's daemons and commands all use that socket.
mungekey --create --keyfile="$tmp/munge/munge.key" >/dev/null 2>&1 \
    || dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
socket="$tmp/munge/munge.socket"
munged --foreground --force --key-file="$tmp/munge/munge.key" --socket="$socket" \
    --pid-file="$tmp/run/munged.pid" --log-file="$tmp/log/munged.log" \
    --seed-file="$tmp/munge/munged.seed" >>"$tmp/log/munged.log" 2>&1 &
munged_pid=$!
for _ in $(seq 50); do [ -S "$socket" ] && break; kill -0 "$munged_pid" 2>/dev/null || break; sleep 0.1; done
munge -n -S "$socket" | unmunge -S "$socket" >/dev/null 2>&1 \
    || die "munged does not answer on $socket (see munged.log above)"

# Two free TCP ports on loopback, so that a Slurm already on this machine is not disturbed.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*(x.getsockname()[1] for x in s))')
node=$(hostname -s)
cpus=$(nproc)
export SLURM_CONF="$tmp/etc/slurm.conf"
cat > "$SLURM_CONF" <<EOF
# Written by scripts/slurm-check.sh: one controller and one node, this machine, loopback only.
ClusterName=dormantcheck
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/run/slurmctld.pid
SlurmdPidFile=$tmp/run/slurmd.pid
PlugStackConfig=$tmp/etc/plugstack.conf
# No systemd and no cgroups needed: processes tracked by parent pid, no task binding.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldDebug=info
SlurmdDebug=info
NodeName=$node NodeHostname=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=check Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
: > "$tmp/etc/plugstack.conf"   # not Debian's /etc/slurm/plugstack.conf: nothing outside $tmp

# In the foreground (-D) as this script's children, so that it knows their pids; they log to
# stderr.
slurmctld -D -f "$SLURM_CONF" >>"$tmp/log/slurmctld.log" 2>&1 &
slurmctld_pid=$!
slurmd -D -f "$SLURM_CONF" -N "$node" >>"$tmp/log/slurmd.log" 2>&1 &
slurmd_pid=$!
state=""
for _ in $(seq 120); do
    kill -0 "$slurmctld_pid" 2>/dev/null || die "slurmctld exited while starting (see its log above)"
    kill -0 "$slurmd_pid" 2>/dev/null || die "slurmd exited while starting (see its log above)"
    state=$(sinfo -h -N -n "$node" -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.5
done
[ "$state" = idle ] || die "node $node is not idle after 60 s (state: '${state:-no answer}')"
say "Slurm up in $(( $(date +%s) - started )) s: slurmctld on 127.0.0.1:$ctld_port, node $node with $cpus CPUs ($(sinfo --version))"

# --- the sequence, whole and as a job array ------------------------------------------------
# Relative paths, as in the README: the job runs in the directory it is submitted from.
work="$tmp/work"
cd "$work"
"$bin" --quiet simulate "$root/scenes/tiny.toml" --out out/tiny.traj
read -r -a args <<< "$render_args"
t0=$(date +%s%N)
"$bin" --quiet render --trajectory out/tiny.traj --frames "0..$frames" "${args[@]}" --out whole
say "whole run: frames 0..$frames ($render_args) in $(( ($(date +%s%N) - t0) / 1000000 )) ms"

# The README's script as it is, its settings through the environment and sbatch's options
# (which override its #SBATCH lines); DORMANT because the job's PATH has no target/release.
say "submitting scripts/slurm-array.sh: $tasks tasks of $per_task frames, 1 CPU each"
job=$(DORMANT="$bin" TRAJECTORY=out/tiny.traj FRAMES=$frames PER_TASK=$per_task OUT=out/tiny \
      RENDER_ARGS="$render_args" \
      sbatch --parsable --array="0-$((tasks - 1))" --cpus-per-task=1 --job-name=dormant-check \
      --chdir="$work" --output="$tmp/log/task-%a.out" "$root/scripts/slurm-array.sh")
job=${job%%;*}
say "job $job submitted; waiting"
submitted=$(date +%s%N)
deadline=$(( $(date +%s) + timeout_s ))
while [ -n "$(squeue -h -j "$job" 2>/dev/null)" ]; do
    [ "$(date +%s)" -lt "$deadline" ] || die "job $job still queued or running after $timeout_s s: $(squeue -h -j "$job" -o '%i %T %R' | head -n 3 | tr '\n' ';')"
    kill -0 "$slurmctld_pid" 2>/dev/null || die "slurmctld died while job $job ran"
    sleep 1
done
# No accounting database here (sacct has nothing), but slurmctld keeps finished jobs for
# MinJobAge (300 s): every task must have COMPLETED with exit code 0.
states=$(scontrol -o show job "$job" | sed -E 's/.*ArrayTaskId=([0-9]+).* JobState=([A-Z_]+).* ExitCode=([0-9:]+).*/\1 \2 \3/' | sort -n)
[ "$(echo "$states" | grep -c ' COMPLETED 0:0$')" -eq "$tasks" ] \
    || die "job $job: not every task completed with exit code 0 (task state exit): $(echo "$states" | grep -v ' COMPLETED 0:0$' | head -n 5 | tr '\n' ';') (task logs above)"
say "job $job finished: $tasks tasks completed in $(( ($(date +%s%N) - submitted) / 1000000 )) ms"

"$root/scripts/slurm-gather.sh" out/tiny

# --- compare ---------------------------------------------------------------------------------
whole_files=$(cd whole && find . -maxdepth 1 -type f -name 'frame_*' -printf '%f\n' | sort)
array_files=$(cd out/tiny && find . -maxdepth 1 -type f -name 'frame_*' -printf '%f\n' | sort)
[ -n "$whole_files" ] || die "the whole run wrote no frames"
if [ "$whole_files" != "$array_files" ]; then
    die "the array's frame files differ from the whole run's: $(diff <(echo "$whole_files") <(echo "$array_files") | grep '^[<>]' | head -n 5 | tr '\n' ' ')"
fi
n=0
for f in $whole_files; do
    cmp -s "whole/$f" "out/tiny/$f" || die "out/tiny/$f differs from the whole run's (byte comparison)"
    n=$((n + 1))
done
say "frames: $n files, byte-identical to the whole run"

python3 - whole/stats.csv out/tiny/stats.csv "$timing_columns" "$integration_columns" out/tiny/part_*/stats.csv <<'PY'
import csv, sys
whole_path, joined_path, timing, integration, *parts = sys.argv[1:]
timing, integration = set(timing.split()), set(integration.split())
read = lambda p: list(csv.reader(open(p)))
whole, joined = read(whole_path), read(joined_path)
fail = lambda msg: sys.exit(f"slurm-check: FAILED: {msg}")
if whole[0] != joined[0]:
    fail(f"stats.csv headers differ:\n  whole:  {','.join(whole[0])}\n  joined: {','.join(joined[0])}")
header = whole[0]
unknown = (timing | integration) - set(header)
if unknown:
    fail(f"slurm-check.sh names columns stats.csv does not have: {sorted(unknown)}")
frames = lambda t: [r[0] for r in t[1:]]
if frames(whole) != frames(joined):
    fail(f"stats.csv rows: whole run has frames {frames(whole)[:3]}..{frames(whole)[-1:]} ({len(whole) - 1}), "
         f"joined {frames(joined)[:3]}..{frames(joined)[-1:]} ({len(joined) - 1})")
# A slice's first frame has no previous image to copy and no stored samples, so it traces in
# full what the whole run reused there (same image, fixed seed): what was traced and reused
# may differ there only; `reused` only where the whole run reused the frame.
firsts = {read(p)[1][0] for p in parts if len(read(p)) > 1}
first_frame_columns = {"rays", "samples_traced", "samples_reused", "traced_share", "pixels_traced", "full_frame"}
compared = [c for c in header if c not in timing | integration]
differ, informational = [], {}
for w, j in zip(whole[1:], joined[1:]):
    for i, c in enumerate(header):
        if w[i] == j[i]:
            continue
        if c in integration:
            informational[c] = informational.get(c, 0) + 1
        elif c in compared and not (w[0] in firsts and (c in first_frame_columns
                                        or (c == "reused" and w[header.index("reused")] == "true"))):
            differ.append(f"frame {w[0]} {c}: whole {w[i]}, joined {j[i]}")
if differ:
    fail(f"stats.csv differs from the whole run's in {len(differ)} cells, e.g.\n  " + "\n  ".join(differ[:10]))
print(f"slurm-check: stats.csv: {len(whole) - 1} rows equal in {', '.join(compared)}")
print(f"slurm-check: not compared: timing ({', '.join(sorted(timing))}) and the slices' own integration "
      f"columns; of these {sum(informational.values())} cells differed: "
      + (", ".join(f"{c} {n}" for c, n in sorted(informational.items())) or "none"))
PY

say "PASSED in $(( $(date +%s) - started )) s: $tasks slices through Slurm equal one run"
