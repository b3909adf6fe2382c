# dormant: build, demo and test entry points. Every target installs what it needs through
# scripts/setup.sh first (idempotent; needs root on a fresh Debian 12/13 machine).

# Where scripts/setup.sh installs Rust with rustup when the machine has no new enough one.
export PATH := $(HOME)/.cargo/bin:$(PATH)
CARGO ?= cargo
RELEASE_BIN := target/release/dormant

.PHONY: setup build demo test test-no-embree lint arch-check fmt bench-check instruction-check soak slurm-check fuzz fuzz-check compare-cycles blender-roundtrip clean

setup:
	bash scripts/setup.sh

build: setup
	$(CARGO) build --release --workspace

# Renders the built-in default scene into out/demo/.
demo: build
	$(RELEASE_BIN) render --out out/demo

# The whole workspace's tests in release mode: each crate's unit tests and the integration
# suite (tests/main.rs, one binary), the BVH on the fastest SIMD path this CPU runs (the
# library's accel/tests/bvh_props.rs checks every path); then the accelerator property tests
# and `dormant verify` again on the portable path (DORMANT_SIMD,
# docs/performance.md#simd-paths); then the tests that differ without Embree and OIDN; last,
# that the release build reuses what the tests compiled (scripts/build-reuse-check.py).
test: setup
	$(CARGO) test --release --workspace
	DORMANT_SIMD=portable $(CARGO) test --release --workspace --lib -- accel::tests
	DORMANT_SIMD=portable $(CARGO) test --release --workspace --test suite -- cli_verify_bench:: --skip bench_
	$(MAKE) test-no-embree
	python3 scripts/build-reuse-check.py

# The pure-Rust build (no Embree, no OIDN): the tests whose code or outcome depends on those
# features. Each of them picks its backend by what the build compiled (the default backend,
# `info`, the paper's backends, the in-process renders of render_images and render_materials)
# or exists only without a feature (render_denoise). Every other test runs the same code with
# and without Embree, so it runs once, above (scripts/test-inventory.py lists both sets;
# docs/testing.md says why each module is or is not here).
NO_EMBREE_TESTS := cli_render:: render_denoise:: bench_paper:: render_images:: render_materials::
test-no-embree:
	$(CARGO) test --release -p dormant-cli --no-default-features --test suite -- $(NO_EMBREE_TESTS)

# The README's job array on a real single-node Slurm started on this machine (root; installs
# slurm-wlm and munge), checked against one uninterrupted run. See docs/slurm.md.
slurm-check: build
	bash scripts/slurm-check.sh

# The soak (not in CI; about 7 minutes after the build): 10,000 frames per backend and form
# with resident memory sampled; fails if it grows 5% or more after warm-up or the geometry
# cache exceeds its budget. See scripts/soak.sh and docs/performance.md#soak-make-soak.
soak: build
	bash scripts/soak.sh

# dormant against Blender Cycles (`setup.sh --bpy` installs Blender 5.0 as a Python module,
# PyPI's bpy, a wheel of some 400 MB, into the git-ignored venv .deps/bpy-venv). Correctness
# at 1,024 spp and the speed of monastery-rain and the demolition at 960x540 (three runs each,
# hours in all; not in CI), on COMPARE_THREADS threads; results in
# out/compare-cycles/report.json. CI runs COMPARE_ARGS=--quick, the image checks on a small
# frame (about a minute). See scripts/compare-cycles.py and
# docs/performance.md#against-blender-cycles.
BPY_VENV := .deps/bpy-venv
BPY_VERSION ?= 5.0.1
COMPARE_THREADS ?= 2
COMPARE_ARGS ?=
compare-cycles: build
	BPY_VENV=$(BPY_VENV) BPY_VERSION=$(BPY_VERSION) bash scripts/setup.sh --bpy
	$(BPY_VENV)/bin/python scripts/compare-cycles.py --threads $(COMPARE_THREADS) $(COMPARE_ARGS)

# A Blender rigid-body bake rendered by dormant and Cycles, and dormant's glTF export imported
# into Blender (scripts/blender-roundtrip.py; not in CI). Uses the bpy venv of compare-cycles.
blender-roundtrip: build
	BPY_VENV=$(BPY_VENV) BPY_VERSION=$(BPY_VERSION) bash scripts/setup.sh --bpy
	$(BPY_VENV)/bin/python scripts/blender-roundtrip.py --threads $(COMPARE_THREADS)

# The module arrows inside each crate: no import cycle, nothing imported against the layer order
# (geometry < scene < physics < accel < {render, residency} < sequence; Cargo enforces the crates'
# own arrows: dormant < dormant-lab < dormant-cli); and the house rules: the core crate's public
# API within its caps (`pub use` names, public items; no glob re-exports or #[doc(hidden)]), no
# clippy::too_many_arguments allowed, no function over 80 lines in a crate's src/, every docs/
# link in the sources resolving, and few comments quoting a measured ratio, each linking its
# docs/lab entry; no clap in the core's dependencies. Pure Python, no build. See
# scripts/arch-check.py. Then scripts/arch-check-selftest.sh breaks each rule once in a scratch
# copy and requires arch-check to catch it (about 15 s).
arch-check:
	python3 scripts/arch-check.py
	bash scripts/arch-check-selftest.sh

lint: arch-check
	$(CARGO) fmt --all --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings
	$(CARGO) clippy -p dormant -p dormant-lab -p dormant-cli --no-default-features --all-targets -- -D warnings

# The headline benchmarks of docs/performance.json run again and printed beside the
# documented figures, flagging any outside its band (timed, so not in CI; about 6 minutes
# on a quiet machine, the trajectories simulated first).
# BENCH_CHECK_ARGS: e.g. --runs 3, --only integration.atrium. See docs/performance.md.
BENCH_CHECK_ARGS ?=
bench-check: build
	python3 scripts/bench-check.py $(BENCH_CHECK_ARGS)

# CI's guard against work creeping into the hot paths: instruction counts (cachegrind, one
# thread) of a few small fixed workloads against docs/instruction-counts.json, failing at +5%.
instruction-check: build
	python3 scripts/instruction-check.py

# Every cargo-fuzz target for FUZZ_SECONDS seconds (default 60) over a temporary copy of its
# committed corpus; installs cargo-fuzz when missing (docs/fuzzing.md). Not part of `test`.
FUZZ_SECONDS ?= 60
fuzz:
	FUZZ_SECONDS=$(FUZZ_SECONDS) bash scripts/fuzz.sh

# CI's fuzzing: every target over its committed corpus, then FUZZ_RUNS mutations from a fixed
# seed, the same amount of fuzzing every time; a crash prints its input in base64 and fails.
FUZZ_RUNS ?= 20000
fuzz-check:
	FUZZ_RUNS=$(FUZZ_RUNS) bash scripts/fuzz.sh

fmt:
	$(CARGO) fmt --all

clean:
	$(CARGO) clean
	rm -rf out
