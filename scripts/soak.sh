#!/usr/bin/env bash
# The soak (`make soak`, not in CI): simulates scenes/soak.toml (10,000 frames of islands
# falling asleep and waking, a bounded number of bodies), renders every frame as a
# low-resolution preview with each backend and each integration form, samples the renderer's
# resident memory every 0.5 s, and checks that it stays flat after warm-up (growth < 5% from
# the end of the first 20% of the frames to the end; the scene needs 2,000 frames, a sweep of
# each plough, to fill up) and that the geometry cache stays within its budget (summary.cache
# in stats.json). Exits non-zero when a check fails. Writes out/soak/: samples.csv,
# summary.json, rss.svg, and each run's frames and stats.json (the frames are deleted after
# the run unless SOAK_KEEP_FRAMES=1).
#
# Runs: baked form (every island integrated as it sleeps, the geometry cache on, with a
# small budget so that it evicts) and resting form (the default), on Embree and on the BVH.
# Environment: SOAK_FRAMES (default: the scene's 10,000), SOAK_SIZE (160x90),
# SOAK_BACKENDS ("embree bvh"), SOAK_FORMS ("baked resting"), SOAK_CACHE_MIB (1),
# SOAK_CACHE_ENTRIES (8), SOAK_OUT (out/soak), SOAK_NICE (5), SOAK_REUSE (off); SOAK_PUBLISH=1
# also copies summary.json and rss.svg to docs/soak/.
#
# Exact reuse is off by default: its change index is rebuilt for each window of frames (up
# to 64 MiB of change boxes; docs/design.md, "Horizons"), and those rebuilds move resident
# memory by tens of MB up and down every few thousand frames, which would hide the slow
# growth this soak looks for. SOAK_REUSE=exact soaks it as users run it (bounded, not flat).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
bin=${DORMANT_BIN:-target/release/dormant}
out=${SOAK_OUT:-out/soak}
frames=${SOAK_FRAMES:-}
size=${SOAK_SIZE:-160x90}
backends=${SOAK_BACKENDS:-embree bvh}
forms=${SOAK_FORMS:-baked resting}
cache_mib=${SOAK_CACHE_MIB:-1}
cache_entries=${SOAK_CACHE_ENTRIES:-8}
niceness=${SOAK_NICE:-5}
reuse=${SOAK_REUSE:-off}

say() { printf 'soak: %s\n' "$*"; }

[ -x "$bin" ] || { echo "soak: $bin not built (run make build)" >&2; exit 2; }
mkdir -p "$out"
rm -f "$out/samples.csv"
start=$(date +%s)

sim_args=(scenes/soak.toml --out "$out/soak.traj" --json "$out/simulate.json" -q)
[ -n "$frames" ] && sim_args+=(--frame-count "$frames")
say "simulating scenes/soak.toml${frames:+ for $frames frames}"
t=$(date +%s)
nice -n "$niceness" "$bin" simulate "${sim_args[@]}"
say "simulated in $(($(date +%s) - t)) s"

runs=()
for backend in $backends; do
    for form in $forms; do
        label="$backend-$form"
        dir="$out/$label"
        rm -rf "$dir"
        mkdir -p "$dir"
        args=(render --trajectory "$out/soak.traj" --backend "$backend" --mode shaded --spp 1
              --size "$size" --integration always --integrate-as "$form" --reuse "$reuse" --out "$dir")
        [ "$form" = baked ] && args+=(--cache-mib "$cache_mib" --cache-entries "$cache_entries")
        say "rendering $label"
        python3 scripts/soak.py run --label "$label" --csv "$out/samples.csv" --wall "$dir/wall.json" \
            -- nice -n "$niceness" "$bin" "${args[@]}"
        say "$label: $(cat "$dir/wall.json")"
        [ "${SOAK_KEEP_FRAMES:-0}" = 1 ] || find "$dir" -name 'frame_*.png' -delete
        runs+=(--run "$label=$dir")
    done
done

min_frames=${frames:-10000}
status=0
python3 scripts/soak.py check --csv "$out/samples.csv" "${runs[@]}" --min-frames "$min_frames" \
    --summary "$out/summary.json" --plot "$out/rss.svg" \
    --title "dormant soak: resident memory over ${min_frames} frames of scenes/soak.toml ($size)" || status=$?
say "wall time $(($(date +%s) - start)) s"
if [ "${SOAK_PUBLISH:-0}" = 1 ]; then
    mkdir -p docs/soak
    cp "$out/summary.json" "$out/rss.svg" docs/soak/
    say "copied summary.json and rss.svg to docs/soak/"
fi
[ "$status" -eq 0 ] && say "passed" || say "FAILED"
exit "$status"
