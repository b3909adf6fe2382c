#!/bin/bash
#SBATCH --job-name=atrium
#SBATCH --array=0-9
#SBATCH --cpus-per-task=16
#SBATCH --time=02:00:00
#SBATCH --signal=B:USR1@120
#SBATCH --requeue
# One slice of a simulated sequence per Slurm array task (README, "Splitting a sequence over
# a job array"). Once, before submitting, from the directory the paths below are relative to:
#
#   dormant simulate scenes/atrium.toml --out out/atrium.traj
#   sbatch scripts/slurm-array.sh                  # then: scripts/slurm-gather.sh out/atrium
#
# Task i renders frames [i*PER_TASK, min((i+1)*PER_TASK, FRAMES)) into OUT/part_NNNN (its own
# directory: stats.json, stats.csv and report.png describe one run). The defaults render the
# atrium's 1,500 frames in 10 slices. Settings come from the environment, which sbatch passes
# to the job (sbatch's own options, e.g. --array or --cpus-per-task, override the lines above):
#
#   DORMANT      the dormant binary (default: `dormant` on the job's PATH); every node must see it
#   TRAJECTORY   trajectory file (default: out/atrium.traj)
#   FRAMES       frames to render, 0..FRAMES (default: 1500, the atrium's whole simulation)
#   PER_TASK     frames per task (default: 150); --array needs 0..ceil(FRAMES/PER_TASK)-1
#   OUT          output directory (default: out/atrium)
#   RENDER_ARGS  further `render` options, split on spaces (e.g. "--size 640x360 --spp 4")
#
# Relative paths resolve against the job's working directory, which is the directory sbatch
# ran in unless `sbatch --chdir=DIR` says otherwise.
#
# Time limits and preemption (docs/slurm.md): two minutes before the limit Slurm sends SIGUSR1
# (--signal above); dormant stops after the frame in flight and the task requeues itself
# (--requeue), to continue where it stopped (--resume) when it runs again. SIGTERM (scancel,
# preemption) stops it the same way; a preempted task is requeued by Slurm.
set -euo pipefail

say() { printf 'slurm-array: task %s: %s\n' "${SLURM_ARRAY_TASK_ID:-?}" "$*" >&2; }
die() { say "error: $*"; exit 1; }

[ -n "${SLURM_ARRAY_TASK_ID:-}" ] || die "not an array task (submit with sbatch; SLURM_ARRAY_TASK_ID is unset)"
dormant=${DORMANT:-dormant}
trajectory=${TRAJECTORY:-out/atrium.traj}
frames=${FRAMES:-1500}
per_task=${PER_TASK:-150}
out=${OUT:-out/atrium}
read -r -a render_args <<< "${RENDER_ARGS:-}"
# Without --cpus-per-task Slurm does not set SLURM_CPUS_PER_TASK; one CPU is what it allocates.
threads=${SLURM_CPUS_PER_TASK:-1}

# A batch job gets the submitting shell's environment, but sites often submit with
# --export=NONE or from a shell without target/release on PATH: name the fix, not just the miss.
command -v "$dormant" >/dev/null 2>&1 \
    || die "'$dormant' is not an executable or on PATH on $(hostname); submit with DORMANT=/path/to/dormant"
[ -f "$trajectory" ] || die "no trajectory $trajectory in $PWD (simulate first, or submit with --chdir / TRAJECTORY=)"

a=$(( SLURM_ARRAY_TASK_ID * per_task ))
b=$(( a + per_task < frames ? a + per_task : frames ))
# An array larger than FRAMES needs has nothing to render in its last tasks; `render` would
# reject the empty range.
if [ "$a" -ge "$frames" ]; then
    say "frames $a.. are past FRAMES=$frames: nothing to render"
    exit 0
fi
part=$(printf '%s/part_%04d' "$out" "$SLURM_ARRAY_TASK_ID")
say "frames $a..$b into $part on $(hostname), $threads threads"
# --resume: a resubmitted or requeued task keeps the frames it finished before it was
# stopped or killed (none on a first run, where its directory holds no stats.json yet).
"$dormant" --quiet --threads "$threads" render --resume --trajectory "$trajectory" --frames "$a..$b" \
    "${render_args[@]}" --out "$part" &
pid=$!
# Slurm signals this batch shell (B: above), not its children: pass the signal on. dormant
# exits 138 (SIGUSR1) or 143 (SIGTERM) once the frame in flight is written; a second signal
# stops it at once.
forwarded=
trap 'forwarded=USR1; kill -s USR1 "$pid" 2>/dev/null || true' USR1
trap 'forwarded=TERM; kill -s TERM "$pid" 2>/dev/null || true' TERM INT
status=0
wait "$pid" || status=$?
# A trapped signal ends `wait` early (status above 128): wait on until dormant itself exits.
while [ "$status" -gt 128 ] && kill -0 "$pid" 2>/dev/null; do
    status=0
    wait "$pid" || status=$?
done
if [ "$forwarded" = USR1 ] && [ "$status" -eq 138 ]; then
    say "stopped before the time limit; requeueing to resume"
    scontrol requeue "$SLURM_JOB_ID" || say "could not requeue; resubmit the array task to resume it"
fi
exit "$status"
