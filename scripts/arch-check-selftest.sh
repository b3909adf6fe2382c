#!/usr/bin/env bash
# Shows that each rule of scripts/arch-check.py fails when broken: copies the tracked sources
# into a scratch folder, makes one scratch change per rule, and requires arch-check to exit
# non-zero naming the problem (and to pass on the unchanged copy). `make arch-check` runs it.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
git -C "$root" ls-files -z --cached --others --exclude-standard -- . ":!fuzz/corpus" | (cd "$root" && xargs -0 cp --parents -t "$scratch" 2>/dev/null) || true
pristine="$scratch/pristine"
mkdir "$pristine" && (cd "$scratch" && find . -mindepth 1 -maxdepth 1 ! -name pristine -exec mv -t "$pristine" {} +)
geometry=crates/dormant/src/geometry/mod.rs

# expect_failure NAME MESSAGE-PATTERN CHANGE: CHANGE (shell code, run in a fresh copy) must
# make arch-check exit non-zero with a line matching MESSAGE-PATTERN.
expect_failure() {
    local name=$1 pattern=$2 change=$3 work="$scratch/work" out
    rm -rf "$work" && cp -a "$pristine" "$work"
    (cd "$work" && eval "$change")
    if out=$(cd "$work" && python3 scripts/arch-check.py 2>&1); then
        echo "arch-check-selftest: '$name' was not caught:"; echo "$out"; exit 1
    fi
    if ! grep -q -- "$pattern" <<<"$out"; then
        echo "arch-check-selftest: '$name' failed without naming it ($pattern):"; echo "$out"; exit 1
    fi
    echo "arch-check-selftest: caught $name: $(grep -m1 -- "$pattern" <<<"$out" | cut -c1-140)"
}

(cd "$pristine" && python3 scripts/arch-check.py >/dev/null) || { echo "arch-check-selftest: arch-check fails on the unchanged tree"; exit 1; }
expect_failure "pub use names over the cap" "pub use\` names, cap" \
    'for i in $(seq 1 20); do echo "pub use crate::geometry::Aabb as Extra$i;" >> '$geometry'; done'
expect_failure "public items over the cap" "public items, cap" \
    'for i in $(seq 1 80); do echo "pub fn extra_$i() {}" >> '$geometry'; done'
expect_failure "a glob re-export" "glob re-export" \
    'echo "pub use crate::geometry::*;" >> crates/dormant/src/render/mod.rs'
expect_failure "#[doc(hidden)]" "doc(hidden)" \
    'printf "#[doc(hidden)]\npub fn hidden_helper() {}\n" >> '$geometry
expect_failure "a too_many_arguments allow" "too_many_arguments" \
    'printf "#[allow(clippy::too_many_arguments)]\npub(crate) fn many(a: u8, b: u8, c: u8, d: u8, e: u8, f: u8, g: u8, h: u8) {}\n" >> '$geometry
expect_failure "a function over 80 lines" "over 80" \
    '{ echo "pub(crate) fn long_one() -> u32 {"; echo "    let mut x = 0;"; for i in $(seq 1 85); do echo "    x += $i;"; done; echo "    x"; echo "}"; } >> '$geometry
expect_failure "clap in the core" "has \`clap\`" \
    'sed -i "s/^\[dependencies\]/[dependencies]\nclap = \"4\"/" crates/dormant/Cargo.toml'
expect_failure "an import against the layers" "geometry" \
    'echo "use crate::render::Film;" >> '$geometry
echo "arch-check-selftest: every rule caught its scratch change"
