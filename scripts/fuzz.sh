#!/usr/bin/env bash
# Runs every cargo-fuzz target (or those named) over a temporary copy of its committed corpus
# (fuzz/corpus/TARGET), so that nothing new is written into the repository. Two modes:
#   - timed (default, `make fuzz`): FUZZ_SECONDS seconds a target (default 60), random seed;
#   - fixed (FUZZ_RUNS set, `make fuzz-check`, run by CI): the corpus, then FUZZ_RUNS
#     mutations from seed 1 on one process: the same amount of fuzzing every run, from the
#     same inputs (the mutations drift a little between runs: coverage is not fully
#     repeatable, probably through random hash seeds), so a failure is replayed from the
#     input it prints.
# Installs cargo-fuzz when missing; builds with RUSTC_BOOTSTRAP=1 because cargo-fuzz passes
# -Z flags (the sanitizer) to a stable rustc. A crash, hang or out-of-memory stops the run:
# the script prints the input in base64 (to add under tests/data/fuzz/TARGET/, see
# docs/fuzzing.md), keeps it in out/fuzz/TARGET/ and fails.
#
#   scripts/fuzz.sh [TARGET...]    env: FUZZ_SECONDS (60), FUZZ_RUNS, FUZZ_ARGS (extra flags)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
cargo_fuzz_version=0.13.2
seconds=${FUZZ_SECONDS:-60}
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene_toml gltf_glb gltf_json trajectory cli_values stats_json)
export RUSTC_BOOTSTRAP=1

say() { printf 'fuzz: %s\n' "$*"; }

if [ -n "${FUZZ_RUNS:-}" ]; then
    mode=(-seed=1 -runs="$FUZZ_RUNS")
    what="$FUZZ_RUNS runs from seed 1"
else
    mode=(-max_total_time="$seconds")
    what="${seconds} s"
fi

if ! cargo fuzz --version >/dev/null 2>&1; then
    say "installing cargo-fuzz $cargo_fuzz_version"
    cargo install --locked cargo-fuzz --version "$cargo_fuzz_version"
fi
cargo fuzz build

# The inputs libFuzzer kept for a failure, printed in base64 and copied to out/fuzz/TARGET/.
report_failure() {
    local target=$1 artifacts=$2 log=$3
    tail -n 40 "$log" >&2
    mkdir -p "out/fuzz/$target"
    for input in "$artifacts"*; do
        [ -f "$input" ] || continue
        say "$target: $(basename "$input") in base64:"
        base64 -w 0 "$input"
        echo
        cp "$input" "out/fuzz/$target/"
    done
    say "$target FAILED; its input is in out/fuzz/$target/ (see docs/fuzzing.md)"
}

work=$(mktemp -d "${TMPDIR:-/tmp}/dormant-fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT
for target in "${targets[@]}"; do
    corpus="$work/$target/corpus"
    artifacts="$work/$target/artifacts/"
    mkdir -p "$corpus" "$artifacts"
    cp -r "fuzz/corpus/$target/." "$corpus/"
    say "$target: $what over $(find "$corpus" -type f | wc -l) input(s)"
    log="$work/$target/log"
    # shellcheck disable=SC2086 # FUZZ_ARGS is a list of flags
    if ! cargo fuzz run "$target" "$corpus" -- "${mode[@]}" -rss_limit_mb=2048 -timeout=10 \
        -print_final_stats=1 -artifact_prefix="$artifacts" ${FUZZ_ARGS:-} >"$log" 2>&1; then
        report_failure "$target" "$artifacts" "$log"
        exit 1
    fi
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    last=$(grep -E '^#[0-9]+' "$log" | tail -n 1)
    say "$target: ok, $runs runs; last: $last"
done
