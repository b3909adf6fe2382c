#!/usr/bin/env python3
"""Counts the instructions of a few small fixed workloads under cachegrind and compares them
with the committed baselines (docs/instruction-counts.json): `make instruction-check`, run by
CI. Timed benchmarks cannot run in CI (the machines are shared and noisy); instruction counts
of one thread are deterministic, so a change that makes the renderer or an accelerator do
more work fails here. A workload more than `tolerance` (5%) above its baseline fails the
check; one more than that below it is printed (update the baseline to keep the guard tight).

Updating a baseline is a reviewed commit that says why the count moved:
    scripts/instruction-check.py --update
Usage: scripts/instruction-check.py [--update] [--only NAME...] [--bin PATH]
"""
import argparse
import datetime
import json
import os
import pathlib
import re
import shlex
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
BASELINES = ROOT / "docs" / "instruction-counts.json"
OUT = ROOT / "out" / "instruction-check"
# The trajectory the render workloads replay, simulated natively (not under valgrind): the
# atrium with 800 objects, all of them asleep from frame 680 to 800.
SETUP = "dormant simulate scenes/atrium.toml --count 800 --out out/instruction-check/atrium800.traj -q"
RENDER = ("dormant render --trajectory out/instruction-check/atrium800.traj --frames 700..704 "
          "--size 320x180 --mode shaded --spp 4 --reuse off --threads 1 -q --out out/instruction-check/frames")
WORKLOADS = {
    "atrium-settled-never-embree": RENDER + " --integration never --backend embree",
    "atrium-settled-resting-embree": RENDER + " --integration always --integrate-as resting --backend embree",
    "atrium-settled-resting-bvh": RENDER + " --integration always --integrate-as resting --backend bvh",
    "accel-default-scene": "dormant bench accel --size 320x180 --runs 1 --threads 1 -q --json out/instruction-check/accel.json",
    # The BVH's build of `bench accel`'s scene (monastery + 8,000 ducks), builds only: loading the
    # glTF files once, then three builds, so that the builds are most of the count.
    "bvh-build-monastery-ducks": "dormant bench accel --env ../shared/assets/monastery.glb "
    "--object ../shared/assets/duck.glb --count 8000 --builds-only --backend bvh --runs 3 --threads 1 -q "
    "--json out/instruction-check/accel-build.json",
}
# Workloads that read the shared assets beside the checkout: skipped (with a message) without them.
NEEDS = {
    "bvh-build-monastery-ducks": ["../shared/assets/monastery.glb", "../shared/assets/duck.glb"],
}


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--update", action="store_true", help="write the counts as the new baselines")
    p.add_argument("--only", nargs="*", default=[], help="workloads to run")
    p.add_argument("--bin", default=str(ROOT / "target" / "release" / "dormant"), help="the dormant binary")
    return p.parse_args()


def argv_of(command, binary):
    argv = shlex.split(command)
    argv[0] = binary
    return argv


def count_instructions(command, binary):
    """The instructions (cachegrind's `I refs`) of one run of `command`."""
    cmd = ["valgrind", "--tool=cachegrind", "--cache-sim=no", "--cachegrind-out-file=/dev/null"]
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    run = subprocess.run(cmd + argv_of(command, binary), cwd=ROOT, env=env, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"instruction-check: failed ({run.returncode}): {command}\n{run.stderr[-2000:]}")
    found = re.search(r"I\s+refs:\s+([\d,]+)", run.stderr)
    if not found:
        sys.exit(f"instruction-check: no count in valgrind's output for: {command}\n{run.stderr[-2000:]}")
    return int(found.group(1).replace(",", ""))


def valgrind_version():
    return subprocess.run(["valgrind", "--version"], capture_output=True, text=True).stdout.strip()


def main():
    args = parse_args()
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"instruction-check: {args.bin} is not built (make build)")
    names = args.only or list(WORKLOADS)
    OUT.mkdir(parents=True, exist_ok=True)
    subprocess.run(argv_of(SETUP, args.bin), cwd=ROOT, check=True)
    baselines = json.loads(BASELINES.read_text()) if BASELINES.exists() else {"workloads": {}}
    tolerance = baselines.get("tolerance", 0.05)
    counts, failed = {}, []
    for name in names:
        missing = [f for f in NEEDS.get(name, []) if not (ROOT / f).is_file()]
        if missing:
            print(f"instruction-check: {name}: skipped ({', '.join(missing)} absent)", flush=True)
            continue
        counts[name] = count_instructions(WORKLOADS[name], args.bin)
        base = baselines["workloads"].get(name, {}).get("instructions")
        if base is None:
            print(f"instruction-check: {name}: {counts[name]:,} (no baseline)")
            continue
        ratio = counts[name] / base
        verdict = "ok"
        if ratio > 1 + tolerance:
            verdict = "FAILED"
            failed.append(name)
        elif ratio < 1 - tolerance:
            verdict = "below the baseline: update it (--update) to keep the guard tight"
        print(f"instruction-check: {name}: {counts[name]:,} against {base:,} ({ratio:.4f}): {verdict}", flush=True)
    if args.update:
        for name, count in counts.items():
            baselines["workloads"][name] = {"command": WORKLOADS[name], "instructions": count}
        baselines.update(tolerance=tolerance, setup=SETUP, valgrind=valgrind_version(),
                         date=datetime.date.today().isoformat())
        BASELINES.write_text(json.dumps(baselines, indent=2) + "\n")
        print(f"instruction-check: wrote {BASELINES.relative_to(ROOT)}")
    elif failed:
        sys.exit(f"instruction-check: {', '.join(failed)} more than {tolerance:.0%} above the baseline")


if __name__ == "__main__":
    main()
