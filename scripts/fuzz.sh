#!/usr/bin/env bash
# Runs every cargo-fuzz target (or those named) for FUZZ_SECONDS seconds each (default 60)
# over a temporary copy of its committed corpus (fuzz/corpus/TARGET), so that nothing new is
# written into the repository. Installs cargo-fuzz when missing; builds with
# RUSTC_BOOTSTRAP=1 because cargo-fuzz passes -Z flags (the sanitizer) to a stable rustc.
# A crash, hang or out-of-memory stops the run: its input is kept in out/fuzz/TARGET/ and
# the script fails. `make fuzz` runs it; docs/fuzzing.md explains the targets.
#
#   scripts/fuzz.sh [TARGET...]    env: FUZZ_SECONDS (60), FUZZ_ARGS (extra libFuzzer flags)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
cargo_fuzz_version=0.13.2
seconds=${FUZZ_SECONDS:-60}
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene_toml gltf_glb gltf_json trajectory cli_values)
export RUSTC_BOOTSTRAP=1

say() { printf 'fuzz: %s\n' "$*"; }

if ! cargo fuzz --version >/dev/null 2>&1; then
    say "installing cargo-fuzz $cargo_fuzz_version"
    cargo install --locked cargo-fuzz --version "$cargo_fuzz_version"
fi
cargo fuzz build

work=$(mktemp -d "${TMPDIR:-/tmp}/dormant-fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT
for target in "${targets[@]}"; do
    corpus="$work/$target/corpus"
    artifacts="$work/$target/artifacts/"
    mkdir -p "$corpus" "$artifacts"
    cp -r "fuzz/corpus/$target/." "$corpus/"
    say "$target: ${seconds} s over $(ls "$corpus" | wc -l) seed(s)"
    log="$work/$target/log"
    # shellcheck disable=SC2086 # FUZZ_ARGS is a list of flags
    if ! cargo fuzz run "$target" "$corpus" -- -max_total_time="$seconds" -rss_limit_mb=2048 \
        -timeout=10 -print_final_stats=1 -artifact_prefix="$artifacts" ${FUZZ_ARGS:-} >"$log" 2>&1; then
        tail -n 40 "$log" >&2
        mkdir -p "out/fuzz/$target"
        cp -r "$artifacts." "out/fuzz/$target/"
        say "$target FAILED; its input is in out/fuzz/$target/ (see docs/fuzzing.md)"
        exit 1
    fi
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    last=$(grep -E '^#[0-9]+' "$log" | tail -n 1)
    say "$target: ok, $runs runs; last: $last"
done
