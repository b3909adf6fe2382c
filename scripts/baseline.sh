#!/usr/bin/env bash
# Output baseline: records what a dormant binary produces for a fixed set of commands whose
# results do not depend on timings, and compares two such records. Used to show that a change
# which should not alter outputs (a restructuring, a refactor) leaves them byte for byte alike.
#
#   scripts/baseline.sh record DIR [BIN]   # BIN defaults to target/release/dormant
#   scripts/baseline.sh compare A B        # exits 1 on any difference, naming each
#
# Recorded: stills of the built-in scene (path traced with albedo/normal/depth AOVs and EXR,
# shaded, ambient occlusion) and, with ../shared/assets beside the checkout, of an asset pile,
# on both backends; scenes/tiny.toml sequences with
# `--integration always` in both integration forms and with motion blur (decisions that do not
# depend on measured times), on both backends; its trajectory and export; `dormant verify` on
# the default scene and on simulated tiny.toml frames. Compared: every image and trajectory
# byte for byte; JSON and CSV on every field whose name does not say it is a time or a rate
# (report.png plots times, so it is left out).
set -euo pipefail

die() { printf 'baseline: %s\n' "$*" >&2; exit 2; }

record() {
    local dir=$1 bin=${2:-target/release/dormant}
    [ -x "$bin" ] || die "no dormant binary at $bin (run make build)"
    bin=$(realpath "$bin")
    local tiny small=(--size 160x90 --threads 2 --quiet)
    tiny=$(realpath scenes/tiny.toml)
    # Outputs are written by relative paths, so that paths recorded in reports compare equal.
    mkdir -p "$dir"
    cd "$dir"
    for backend in embree bvh; do
        "$bin" render "${small[@]}" --spp 4 --backend "$backend" --aov albedo,normal,depth --exr \
            --out "still-path-$backend"
        "$bin" render "${small[@]}" --spp 2 --backend "$backend" --mode shaded --out "still-shaded-$backend"
        "$bin" render "${small[@]}" --spp 2 --backend "$backend" --mode ao --out "still-ao-$backend"
        for form in resting baked; do
            "$bin" render "$tiny" "${small[@]}" --spp 2 --backend "$backend" --frames 0..160 --frame-step 8 \
                --integration always --integrate-as "$form" --out "tiny-$form-$backend"
        done
        "$bin" render "$tiny" "${small[@]}" --spp 2 --backend "$backend" --frames 0..64 --frame-step 8 \
            --integration always --shutter 0.5 --out "tiny-blur-$backend"
    done
    local assets
    assets=$(cd "$(dirname "$tiny")/../.." && pwd)/shared/assets
    if [ -f "$assets/monastery.glb" ]; then
        # An asset pile (glTF import, materials, the pile's placement) on both backends.
        for backend in embree bvh; do
            "$bin" render "${small[@]}" --spp 2 --backend "$backend" --env "$assets/monastery.glb" \
                --object "$assets/duck.glb" --count 200 --out "pile-$backend"
        done
    fi
    "$bin" simulate "$tiny" --quiet --out "tiny.traj" --json "tiny-simulate.json"
    "$bin" export --quiet --trajectory "tiny.traj" --frames 0..48 --frame-step 8 --out "tiny-export.json"
    "$bin" verify --quiet --threads 2 --json "verify-default.json"
    "$bin" verify "$tiny" --quiet --threads 2 --count 60 --check-frames 3 --json "verify-tiny.json"
    rm -f ./*/report.png
    echo "baseline: recorded $(find . -type f | wc -l) files in $dir"
}

compare() {
    python3 - "$1" "$2" <<'EOF'
import csv, json, os, re, sys

# Fields that are measured times or rates (or derived from them): not compared.
TIMED = re.compile(r"(_ms$|_ms_|_s$|_seconds$|^seconds$|mrays|per_second|estimated|elapsed|^time|"
                   r"_time$|wall|duration|threads|^cost_model$)")

def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if not TIMED.search(k)}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v

def load(path):
    if path.endswith(".json"):
        with open(path) as f:
            return strip(json.load(f))
    if path.endswith(".csv"):
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        return [strip(r) for r in rows]
    with open(path, "rb") as f:
        return f.read()

a, b = sys.argv[1], sys.argv[2]
def files(root):
    return {os.path.relpath(os.path.join(d, n), root) for d, _, ns in os.walk(root) for n in ns}
fa, fb = files(a), files(b)
bad = [f"only in {a}: {p}" for p in sorted(fa - fb)] + [f"only in {b}: {p}" for p in sorted(fb - fa)]
for p in sorted(fa & fb):
    if load(os.path.join(a, p)) != load(os.path.join(b, p)):
        bad.append(f"differs: {p}")
for line in bad:
    print("baseline:", line)
print(f"baseline: {len(fa & fb)} files compared, {len(bad)} differences")
sys.exit(1 if bad else 0)
EOF
}

case "${1:-}" in
    record) [ $# -ge 2 ] || die "usage: $0 record DIR [BIN]"; record "$2" "${3:-}" ;;
    compare) [ $# -eq 3 ] || die "usage: $0 compare A B"; compare "$2" "$3" ;;
    *) die "usage: $0 record DIR [BIN] | compare A B" ;;
esac
