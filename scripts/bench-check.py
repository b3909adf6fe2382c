#!/usr/bin/env python3
"""Reruns the headline benchmarks of docs/performance.md and prints each figure beside the
documented one (`make bench-check`; docs/performance.md#how-to-measure).

The figures, their commands and their documented spread are docs/performance.json. Each
selected command runs --runs times (its `setup`, e.g. simulating the trajectory, once before);
each figure is read from the command's --json report. A figure is flagged when it falls
outside its tolerance band: the documented spread [min, max] widened by --margin of the
documented value on each side. A flag on the worse side (`better` says which way is better)
is a regression and fails the check; one on the better side means the documentation is stale
and is printed, not failed. Figures documented from fewer than three runs are marked: their
band is narrower than the machine's noise.

Usage: scripts/bench-check.py [--runs N] [--margin F] [--areas A,B] [--only ID_PREFIX...]
                              [--bin PATH] [--json FILE]
"""
import argparse
import json
import os
import pathlib
import shlex
import statistics
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
FIGURES = ROOT / "docs" / "performance.json"
# What `make bench-check` reruns by default: about 6 minutes on the quiet 2-core machine.
DEFAULT_AREAS = ("accelerators", "rendering", "integration")
DEFAULT_MARGIN = 0.10


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=1, help="runs of each command (default 1)")
    p.add_argument("--margin", type=float, default=DEFAULT_MARGIN,
                   help="band widening, a share of the documented value (default 0.10)")
    p.add_argument("--areas", default=",".join(DEFAULT_AREAS), help="areas of performance.json to run")
    p.add_argument("--only", nargs="*", default=[], help="figure ids (or their prefixes) to run")
    p.add_argument("--bin", default=str(ROOT / "target" / "release" / "dormant"), help="the dormant binary")
    p.add_argument("--json", help="write every measured figure here")
    return p.parse_args()


def selected(figures, args):
    areas = set(args.areas.split(","))
    for f in figures:
        if args.only:
            if any(f["id"].startswith(prefix) for prefix in args.only):
                yield f
        elif f["area"] in areas:
            yield f


def metric(report, path):
    """The value at `path` in a --json report: `a.b` a key, `a[2]` an array's element."""
    value = report
    for part in path.split("."):
        name, _, index = part.partition("[")
        if name:
            value = value[name]
        if index:
            value = value[int(index.rstrip("]"))]
    return value


def command_argv(command, binary):
    """A documented command as argv, with `dormant` the binary under test."""
    argv = shlex.split(command)
    if argv[0] == "dormant":
        argv[0] = binary
    return argv


def json_output(argv):
    return ROOT / argv[argv.index("--json") + 1]


def missing_inputs(argv):
    """The files a command names that do not exist (the shared assets, on a machine without
    them)."""
    return [a for a in argv[1:] if a.startswith("../") and not (ROOT / a).exists()]


def run_command(command, setup, runs, binary):
    """The --json reports of `runs` runs of `command`, after `setup` once; None when its
    inputs are absent."""
    argv = command_argv(command, binary)
    if missing_inputs(argv):
        print(f"bench-check: skipped (missing {', '.join(missing_inputs(argv))}): {command}", flush=True)
        return None
    if setup:
        setup_argv = command_argv(setup, binary)
        output = setup_argv[setup_argv.index("--out") + 1] if "--out" in setup_argv else None
        if output is None or not (ROOT / output).exists():
            print(f"bench-check: setup: {setup}", flush=True)
            subprocess.run(setup_argv, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
    (ROOT / "out").mkdir(exist_ok=True)
    reports = []
    for run in range(runs):
        start = time.monotonic()
        subprocess.run(argv, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        print(f"bench-check: run {run + 1}/{runs} in {time.monotonic() - start:.0f} s: {command}", flush=True)
        reports.append(json.loads(json_output(argv).read_text()))
    return reports


def verdict(figure, measured, margin):
    """'ok', 'WORSE' or 'better' for `measured` against the figure's band."""
    slack = margin * abs(figure["value"])
    low, high = figure["min"] - slack, figure["max"] + slack
    if low <= measured <= high:
        return "ok"
    worse = measured > high if figure["better"] == "lower" else measured < low
    return "WORSE" if worse else "better"


def print_table(rows, margin):
    print(f"\nfigure | documented median [min, max] (runs) | measured | measured / documented | "
          f"band +-{margin:.0%} of the median")
    for r in rows:
        f = r["figure"]
        few = " (fewer than 3 runs)" if f["runs"] < 3 else ""
        values = ", ".join(f"{v:.4g}" for v in r["values"])
        ratio = r["median"] / f["value"] if f["value"] else float("nan")
        print(f"{f['id']} | {f['value']:.4g} [{f['min']:.4g}, {f['max']:.4g}] ({f['runs']}{few}) | "
              f"{values} | {ratio:.3f} | {r['verdict']}")


def main():
    args = parse_args()
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"bench-check: {args.bin} is not built (make build)")
    figures = list(selected(json.loads(FIGURES.read_text()), args))
    if not figures:
        sys.exit("bench-check: no figure selected")
    reports = {}
    for command in dict.fromkeys(f["command"] for f in figures):
        setup = next(f.get("setup") for f in figures if f["command"] == command)
        reports[command] = run_command(command, setup, args.runs, args.bin)
    rows = []
    for f in figures:
        if reports[f["command"]] is None:
            continue
        values = [float(metric(r, f["metric"])) for r in reports[f["command"]]]
        median = statistics.median(values)
        rows.append({"figure": f, "values": values, "median": median, "verdict": verdict(f, median, args.margin)})
    print_table(rows, args.margin)
    if args.json:
        out = [{"id": r["figure"]["id"], "values": r["values"], "documented": r["figure"]["value"],
                "verdict": r["verdict"]} for r in rows]
        pathlib.Path(args.json).write_text(json.dumps(out, indent=2) + "\n")
    worse = [r["figure"]["id"] for r in rows if r["verdict"] == "WORSE"]
    stale = [r["figure"]["id"] for r in rows if r["verdict"] == "better"]
    if stale:
        print(f"bench-check: better than documented (update docs/performance.md and .json): {', '.join(stale)}")
    if worse:
        print(f"bench-check: FAILED, worse than the documented band: {', '.join(worse)}")
        sys.exit(1)
    print(f"bench-check: {len(rows)} figure(s) within their bands")


if __name__ == "__main__":
    main()
