#!/usr/bin/env python3
"""The soak's sampler, checker and plot (`make soak`); standard library only.

`run`: renders a trajectory with one backend while sampling the process's resident memory
(VmRSS in /proc/PID/status) every --interval seconds, with the frame it had reached (read
from the "rendered .../frame_NNNN.png" lines `dormant render` prints), and appends the
samples to a CSV. `check`: reads that CSV and each run's stats.json, prints the figures,
writes them as JSON and the RSS plot as SVG, and exits 1 when a run's resident memory grew
by 5% or more from the end of warm-up to the end, or its geometry cache exceeded its budget.
"""

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import threading
import time

FRAME_LINE = re.compile(r"frame_(\d+)\.png")
CSV_FIELDS = ["run", "elapsed_s", "frame", "rss_kb"]


def rss_kb(pid):
    """VmRSS of `pid` in kB, or None once it is gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except (FileNotFoundError, ProcessLookupError):
        return None
    return None


def run(args):
    """Runs the render command, sampling it; returns its exit code."""
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, bufsize=1)
    last = {"frame": -1}

    def follow():
        for line in proc.stdout:
            m = FRAME_LINE.search(line)
            if m:
                last["frame"] = int(m.group(1))

    reader = threading.Thread(target=follow, daemon=True)
    reader.start()
    start = time.monotonic()
    new = not os.path.exists(args.csv)
    with open(args.csv, "a", newline="") as f:
        out = csv.writer(f)
        if new:
            out.writerow(CSV_FIELDS)
        while proc.poll() is None:
            kb = rss_kb(proc.pid)
            if kb is not None:
                out.writerow([args.label, f"{time.monotonic() - start:.2f}", last["frame"], kb])
                f.flush()
            time.sleep(args.interval)
    reader.join(timeout=5)
    wall = time.monotonic() - start
    with open(args.wall, "w") as f:
        json.dump({"run": args.label, "wall_s": round(wall, 1), "exit": proc.returncode}, f)
    return proc.returncode


def load_samples(path):
    runs = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            runs.setdefault(row["run"], []).append(
                (float(row["elapsed_s"]), int(row["frame"]), int(row["rss_kb"]))
            )
    return runs


def mean(values):
    return sum(values) / len(values) if values else float("nan")


def rss_before(samples, frame, count=5):
    """Mean RSS (kB) of the last `count` samples taken at or before `frame` (at 0.5 s a
    sample, up to a hundred frames apart: several samples rather than one)."""
    before = [kb for _, f, kb in samples if f <= frame][-count:]
    return mean(before)


def figures(label, samples, stats, wall, warmup_fraction):
    """The run's figures: frames, wall time, RSS at the end of warm-up and at the end, growth,
    the cache's peak against its budget and what the cache and the manager did."""
    summary = stats["summary"]
    frames = summary["frames"]
    last_frame = summary["last_frame"]
    warmup_frame = int(last_frame * warmup_fraction)
    # Samples at the last frame are the finish: stats.json, stats.csv and report.png written
    # from every frame's record. The end of the run is the last samples before that.
    rendering = [s for s in samples if 0 <= s[1] < last_frame]
    finish = [kb for _, f, kb in samples if f == last_frame]
    warm = rss_before(rendering, warmup_frame)
    end = rss_before(rendering, last_frame)
    after = [(f, kb) for _, f, kb in rendering if f >= warmup_frame]
    cache, totals = summary["cache"], summary["totals"]
    return {
        "run": label,
        "backend": stats["run"]["backend"],
        "integration": stats["run"]["integration"],
        "integrate_as": stats["run"]["integrate_as"],
        "size": f'{stats["run"]["width"]}x{stats["run"]["height"]}',
        "spp": stats["run"]["spp"],
        "mode": stats["run"]["mode"],
        "frames": frames,
        "wall_s": wall["wall_s"],
        "samples": len(samples),
        "warmup_frame": warmup_frame,
        "rss_warmup_mb": round(warm / 1024, 1),
        "rss_end_mb": round(end / 1024, 1),
        "rss_peak_mb": round(max(kb for _, _, kb in samples) / 1024, 1),
        "rss_finish_mb": round(max(finish) / 1024, 1) if finish else None,
        "growth_pct": round(100.0 * (end - warm) / warm, 2),
        "slope_kb_per_kframe": round(slope(after) * 1000, 1),
        "cache_peak_bytes": cache.get("peak_bytes"),
        "cache_peak_entries": cache.get("peak_entries"),
        "cache_budget_bytes": cache.get("budget_bytes"),
        "cache_budget_entries": cache.get("budget_entries"),
        "cache": {k: cache[k] for k in ("requests", "full", "partial", "miss", "recorded", "evicted", "invalidated")},
        "islands": {k: totals[k] for k in ("islands_slept", "islands_woke", "islands_integrated", "islands_reactivated")},
        "reused_frames": totals["reused_frames"],
    }


def slope(points):
    """Least-squares slope of kB over frames."""
    if len(points) < 2:
        return 0.0
    mx, my = mean([p[0] for p in points]), mean([p[1] for p in points])
    sxx = sum((x - mx) ** 2 for x, _ in points)
    return sum((x - mx) * (y - my) for x, y in points) / sxx if sxx else 0.0


def problems(fig, min_frames, max_growth):
    found = []
    if fig["frames"] < min_frames:
        found.append(f'{fig["frames"]} frames rendered, fewer than {min_frames}')
    if not fig["growth_pct"] < max_growth:
        found.append(f'resident memory grew {fig["growth_pct"]}% after warm-up (limit {max_growth}%)')
    peak_b, peak_n = fig["cache_peak_bytes"], fig["cache_peak_entries"]
    budget_b, budget_n = fig["cache_budget_bytes"], fig["cache_budget_entries"]
    if None in (peak_b, peak_n, budget_b, budget_n):
        found.append("stats.json reports no cache peak and budget")
    elif peak_b > budget_b or peak_n > budget_n:
        found.append(f"geometry cache peaked at {peak_b} bytes / {peak_n} entries, over its budget "
                     f"of {budget_b} bytes / {budget_n} entries")
    return found


COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"]


def svg_panel(points, figs, box, xmax, yrange, ylabel):
    """One panel of the plot: axes, grid, a line per run, the warm-up ends dashed."""
    left, top, pw, ph = box
    ymin, ymax = yrange
    ystep = nice_step((ymax - ymin) / 5)
    ymin, ymax = ystep * int(ymin / ystep), ystep * (int(ymax / ystep) + 1)
    sx = lambda f: left + pw * f / xmax
    sy = lambda mb: top + ph - ph * (mb - ymin) / (ymax - ymin)
    out = []
    y = ymin
    while y <= ymax + ystep / 2:
        out.append(f'<line x1="{left}" y1="{sy(y):.1f}" x2="{left + pw}" y2="{sy(y):.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{left - 6}" y="{sy(y) + 4:.1f}" text-anchor="end">{y:g}</text>')
        y += ystep
    xstep = nice_step(xmax / 5)
    x = 0
    while x <= xmax:
        out.append(f'<text x="{sx(x):.1f}" y="{top + ph + 16}" text-anchor="middle">{x:g}</text>')
        x += xstep
    out.append(f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#444"/>')
    out.append(f'<text transform="translate({left - 48} {top + ph / 2}) rotate(-90)" '
               f'text-anchor="middle">{ylabel}</text>')
    for warm in sorted({fig["warmup_frame"] for fig in figs.values()}):
        out.append(f'<line x1="{sx(warm):.1f}" y1="{top}" x2="{sx(warm):.1f}" y2="{top + ph}" '
                   f'stroke="#888" stroke-dasharray="4 4"/>')
    for i, pts in enumerate(points.values()):
        step = max(1, len(pts) // 600)
        line = " ".join(f"{sx(f):.1f},{sy(mb):.1f}" for f, mb in pts[::step] + pts[-1:])
        out.append(f'<polyline fill="none" stroke="{COLORS[i % len(COLORS)]}" stroke-width="1.5" '
                   f'points="{line}"/>')
    return out


def svg_plot(runs, figs, path, title):
    """RSS (MB) over rendered frames, one line per run: from zero above, zoomed in below;
    the end of warm-up dashed, each run's growth in the legend."""
    w, left, pw = 880, 70, 790
    points = {label: [(f, kb / 1024) for _, f, kb in s if f >= 0] for label, s in runs.items()}
    values = [mb for p in points.values() for _, mb in p] or [1.0]
    xmax = nice_step(max((f for p in points.values() for f, _ in p), default=1) / 10) * 10
    legend_rows = (len(points) + 1) // 2
    h = 40 + 260 + 40 + 200 + 60 + 18 * legend_rows
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="DejaVu Sans, sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<text x="{w / 2}" y="22" text-anchor="middle" font-size="15">{title}</text>']
    out += svg_panel(points, figs, (left, 40, pw, 260), xmax, (0, max(values)), "resident memory (MB)")
    out += svg_panel(points, figs, (left, 340, pw, 200), xmax, (min(values) - 0.5, max(values)),
                     "zoomed (MB)")
    out.append(f'<text x="{left + pw / 2}" y="{340 + 200 + 32}" text-anchor="middle">rendered frame '
               f'(dashed: end of warm-up; the spike at the end: statistics being written)</text>')
    for i, label in enumerate(points):
        color, fig = COLORS[i % len(COLORS)], figs.get(label)
        ly, lx = 340 + 200 + 56 + 18 * (i // 2), left + (i % 2) * pw / 2
        text = label if not fig else (f'{label}: {fig["rss_warmup_mb"]} → {fig["rss_end_mb"]} MB '
                                      f'({fig["growth_pct"]:+.2f}%)')
        out.append(f'<line x1="{lx}" y1="{ly - 4}" x2="{lx + 24}" y2="{ly - 4}" stroke="{color}" '
                   f'stroke-width="3"/><text x="{lx + 30}" y="{ly}">{text}</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def nice_step(raw):
    """1, 2 or 5 times a power of ten, at least `raw`."""
    if raw <= 0:
        return 1
    power = 10 ** int(f"{raw:e}".split("e")[1])
    for m in (1, 2, 5, 10):
        if m * power >= raw:
            return m * power
    return 10 * power


def check(args):
    runs = load_samples(args.csv)
    figs, failed = {}, False
    for spec in args.run:
        label, outdir = spec.split("=", 1)
        with open(os.path.join(outdir, "stats.json")) as f:
            stats = json.load(f)
        with open(os.path.join(outdir, "wall.json")) as f:
            wall = json.load(f)
        fig = figures(label, runs.get(label, []), stats, wall, args.warmup)
        figs[label] = fig
        found = problems(fig, args.min_frames, args.max_growth)
        fig["problems"] = found
        failed |= bool(found)
        print(f'{label}: {fig["frames"]} frames in {fig["wall_s"]} s; RSS {fig["rss_warmup_mb"]} MB at '
              f'frame {fig["warmup_frame"]} -> {fig["rss_end_mb"]} MB at the end ({fig["growth_pct"]:+.2f}%, '
              f'{fig["slope_kb_per_kframe"]:+.1f} kB per 1000 frames), peak {fig["rss_peak_mb"]} MB '
              f'(writing the statistics: {fig["rss_finish_mb"]} MB); '
              f'cache peak {fig["cache_peak_bytes"]} B / {fig["cache_peak_entries"]} entries of '
              f'{fig["cache_budget_bytes"]} B / {fig["cache_budget_entries"]}; cache {fig["cache"]}; '
              f'islands {fig["islands"]}')
        for p in found:
            print(f"{label}: FAIL: {p}")
    with open(args.summary, "w") as f:
        json.dump({"warmup_fraction": args.warmup, "max_growth_pct": args.max_growth,
                   "runs": list(figs.values())}, f, indent=2)
        f.write("\n")
    svg_plot(runs, figs, args.plot, args.title)
    print(f"wrote {args.summary} and {args.plot}")
    return 1 if failed else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run a render command, sampling its resident memory")
    r.add_argument("--label", required=True)
    r.add_argument("--csv", required=True, help="samples CSV to append to")
    r.add_argument("--wall", required=True, help="JSON file for the wall time and exit code")
    r.add_argument("--interval", type=float, default=0.5)
    r.add_argument("command", nargs=argparse.REMAINDER)
    c = sub.add_parser("check", help="figures, criteria and the plot from the samples")
    c.add_argument("--csv", required=True)
    c.add_argument("--run", action="append", required=True, metavar="LABEL=OUTDIR")
    c.add_argument("--warmup", type=float, default=0.2, help="warm-up as a fraction of the frames")
    c.add_argument("--max-growth", type=float, default=5.0, help="percent")
    c.add_argument("--min-frames", type=int, default=10000)
    c.add_argument("--summary", required=True)
    c.add_argument("--plot", required=True)
    c.add_argument("--title", default="dormant soak: resident memory")
    args = parser.parse_args()
    sys.exit(run(args) if args.cmd == "run" else check(args))


if __name__ == "__main__":
    main()
