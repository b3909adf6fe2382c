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
#   4. submits one task over every frame, warns it mid-render with SIGUSR1 (what a time limit's
#      `--signal=B:USR1@...` sends): it must stop, requeue itself and resume to the whole
#      run's frames, byte for byte;
#   5. stops the daemons and removes the directory, also on failure or Ctrl-C.
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

# Waits until job $1 has left the queue and requires its $2 tasks to have COMPLETED with exit
# code 0. No accounting database here (sacct has nothing), but slurmctld keeps finished jobs
# for MinJobAge (300 s).
await_job() {
    local job=$1 tasks=$2 deadline states
    deadline=$(( $(date +%s) + timeout_s ))
    while [ -n "$(squeue -h -j "$job" 2>/dev/null)" ]; do
        [ "$(date +%s)" -lt "$deadline" ] || die "job $job still queued or running after $timeout_s s: $(squeue -h -j "$job" -o '%i %T %R' | head -n 3 | tr '\n' ';')"
        kill -0 "$slurmctld_pid" 2>/dev/null || die "slurmctld died while job $job ran"
        sleep 1
    done
    states=$(scontrol -o show job "$job" | sed -E 's/.*ArrayTaskId=([0-9]+).* JobState=([A-Z_]+).* ExitCode=([0-9:]+).*/\1 \2 \3/' | sort -n)
    [ "$(echo "$states" | grep -c ' COMPLETED 0:0$')" -eq "$tasks" ] \
        || die "job $job: not every task completed with exit code 0 (task state exit): $(echo "$states" | grep -v ' COMPLETED 0:0$' | head -n 5 | tr '\n' ';') (task logs above)"
}

# Requires every frame file of the whole run in directory $1, byte for byte, and no other.
same_frames_as_whole() {
    local dir=$1 whole_files other_files n=0
    whole_files=$(cd whole && find . -maxdepth 1 -type f -name 'frame_*' -printf '%f\n' | sort)
    other_files=$(cd "$dir" && find . -maxdepth 1 -type f -name 'frame_*' -printf '%f\n' | sort)
    [ -n "$whole_files" ] || die "the whole run wrote no frames"
    if [ "$whole_files" != "$other_files" ]; then
        die "$dir's frame files differ from the whole run's: $(diff <(echo "$whole_files") <(echo "$other_files") | grep '^[<>]' | head -n 5 | tr '\n' ' ')"
    fi
    for f in $whole_files; do
        cmp -s "whole/$f" "$dir/$f" || die "$dir/$f differs from the whole run's (byte comparison)"
        n=$((n + 1))
    done
    say "frames: $n files in $dir, byte-identical to the whole run"
}

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
await_job "$job" "$tasks"
say "job $job finished: $tasks tasks completed in $(( ($(date +%s%N) - submitted) / 1000000 )) ms"

"$root/scripts/slurm-gather.sh" out/tiny

# --- compare ---------------------------------------------------------------------------------
same_frames_as_whole out/tiny

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
# may differ there, and in the slice's later frames (a blocked shadow ray's horizon follows the
# blocker the tracer meets first, which depends on when and in which build it was traced); `reused`
# only where the whole run reused the frame. The first slice starts where the whole run does.
starts = sorted(int(read(p)[1][0]) for p in parts if len(read(p)) > 1)
traced_may_differ = {w[0] for w in whole[1:] if any(s <= int(w[0]) for s in starts[1:])} | {str(s) for s in starts}
first_frame_columns = {"rays", "neighbour_rays", "samples_traced", "samples_reused", "traced_share", "pixels_traced",
                       "full_frame"}
compared = [c for c in header if c not in timing | integration]
differ, informational = [], {}
for w, j in zip(whole[1:], joined[1:]):
    for i, c in enumerate(header):
        if w[i] == j[i]:
            continue
        if c in integration:
            informational[c] = informational.get(c, 0) + 1
        elif c in compared and not (w[0] in traced_may_differ and (c in first_frame_columns
                                        or (c == "reused" and w[header.index("reused")] == "true"))):
            differ.append(f"frame {w[0]} {c}: whole {w[i]}, joined {j[i]}")
if differ:
    fail(f"stats.csv differs from the whole run's in {len(differ)} cells, e.g.\n  " + "\n  ".join(differ[:10]))
print(f"slurm-check: stats.csv: {len(whole) - 1} rows equal in {', '.join(compared)}")
print(f"slurm-check: not compared: timing ({', '.join(sorted(timing))}) and the slices' own integration "
      f"columns; of these {sum(informational.values())} cells differed: "
      + (", ".join(f"{c} {n}" for c, n in sorted(informational.items())) or "none"))
PY

# --- a task stopped before its time limit and requeued ---------------------------------------
# One task over every frame. Once it has written a tenth of them, its batch shell gets SIGUSR1,
# the warning `#SBATCH --signal=B:USR1@120` asks for before a time limit: the script passes it
# to dormant, which stops after the frame in flight (exit 138); the task requeues itself and,
# run again, its --resume renders the rest. The result must be the whole run's frames.
say "submitting one task over all $frames frames, to be warned (SIGUSR1) mid-render"
job=$(DORMANT="$bin" TRAJECTORY=out/tiny.traj FRAMES=$frames PER_TASK=$frames OUT=out/requeued \
      RENDER_ARGS="$render_args" \
      sbatch --parsable --array=0 --cpus-per-task=1 --job-name=dormant-requeue \
      --chdir="$work" --open-mode=append --output="$tmp/log/requeued-%a.out" "$root/scripts/slurm-array.sh")
job=${job%%;*}
part=out/requeued/part_0000
# Frame 48, the 25th of 240: the frame files appear as frames finish (stats.json at intervals).
warn_at=$(printf '%s/frame_%04d.png' "$part" 48)
deadline=$(( $(date +%s) + timeout_s ))
until [ -f "$warn_at" ]; do
    [ "$(date +%s)" -lt "$deadline" ] || die "job $job did not write $warn_at in $timeout_s s"
    [ -n "$(squeue -h -j "$job" 2>/dev/null)" ] || die "job $job ended before it was warned"
    sleep 0.01
done
scancel --batch --signal=USR1 "${job}_0"
say "warned job $job once it wrote $warn_at; waiting"
# Slurm holds a requeued job for about two minutes (its BeginTime); start it at once.
for _ in $(seq 200); do
    if [ "$(squeue -h -j "$job" -o %T 2>/dev/null)" = PENDING ]; then
        scontrol update JobId="${job}_0" StartTime=now 2>/dev/null || true
        break
    fi
    [ -n "$(squeue -h -j "$job" 2>/dev/null)" ] || break
    sleep 0.05
done
await_job "$job" 1
restarts=$(scontrol -o show job "$job" | sed -E 's/.* Restarts=([0-9]+).*/\1/')
[ "$restarts" -ge 1 ] || die "job $job was not requeued (Restarts=$restarts): $(tail -n 5 "$tmp/log/requeued-0.out" | tr '\n' ';')"
grep -q "stopped by SIGUSR1 after frame" "$tmp/log/requeued-0.out" \
    || die "job $job's log does not say dormant stopped on SIGUSR1: $(tail -n 5 "$tmp/log/requeued-0.out" | tr '\n' ';')"
same_frames_as_whole "$part"
say "the warned task stopped after frame $(grep -o 'after frame [0-9]*' "$tmp/log/requeued-0.out" | head -n 1 | cut -d' ' -f3), was requeued ($restarts restart) and resumed to the whole run's frames"

say "PASSED in $(( $(date +%s) - started )) s: $tasks slices through Slurm equal one run, and a warned task requeued and resumed to it"
