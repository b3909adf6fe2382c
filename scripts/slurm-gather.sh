#!/usr/bin/env bash
# Gathers what the tasks of scripts/slurm-array.sh wrote into OUT/part_*: every frame file
# (PNG, and EXR and AOV passes when rendered) into OUT, and the slices' stats.csv into one
# OUT/stats.csv: one header, then every row in frame order. Run it after the whole array has
# finished:
#
#   scripts/slurm-gather.sh out/atrium         # OUT; default: $OUT, else out/atrium
#
# The joined table's rows are the whole sequence's; see the README for which columns equal a
# single run's. stats.json and report.png stay per slice.
set -euo pipefail

say() { printf 'slurm-gather: %s\n' "$*"; }
die() { printf 'slurm-gather: error: %s\n' "$*" >&2; exit 1; }

out=${1:-${OUT:-out/atrium}}
[ -d "$out" ] || die "no output directory $out"
shopt -s nullglob
parts=("$out"/part_*/)
[ ${#parts[@]} -gt 0 ] || die "no $out/part_*/ directories: did the array run with OUT=$out?"

# Each finished task wrote its stats.csv last; a slice without one failed or is still running.
header=""
for part in "${parts[@]}"; do
    [ -f "$part/stats.csv" ] || die "${part%/} has no stats.csv: its task failed or has not finished"
    h=$(head -n 1 "$part/stats.csv")
    [ -z "$header" ] || [ "$h" = "$header" ] || die "${part%/}/stats.csv has another header than ${parts[0]%/}/stats.csv"
    header=$h
done

# Frame files: frame_NNNN.png, .exr and .KIND.{png,exr}. find + cp -t instead of a glob on
# the command line: a long sequence has more frames than one argument list holds. Two slices
# with the same frame (overlapping ranges) would overwrite each other silently, so refuse.
dups=$(find "${parts[@]}" -maxdepth 1 -type f -name 'frame_*' -printf '%f\n' | sort | uniq -d | head -n 3)
[ -z "$dups" ] || die "frames rendered by more than one slice (overlapping ranges?): $(tr '\n' ' ' <<< "$dups")"
find "${parts[@]}" -maxdepth 1 -type f -name 'frame_*' -exec cp -t "$out" {} +

# Rows sorted by their frame number, not by the order of the part directories: a glob sorts
# part_10 before part_2 when the names are not zero-padded to one width.
tmp=$(mktemp "$out/.stats.csv.XXXXXX")
trap 'rm -f "$tmp"' EXIT
{ printf '%s\n' "$header"
  for part in "${parts[@]}"; do tail -n +2 "$part/stats.csv"; done | sort -t, -k1,1n; } > "$tmp"
repeated=$(tail -n +2 "$tmp" | cut -d, -f1 | uniq -d | head -n 3)
[ -z "$repeated" ] || die "frames in more than one slice's stats.csv: $(tr '\n' ' ' <<< "$repeated")"
chmod 644 "$tmp"             # mktemp makes it private; the slices' tables are not
mv "$tmp" "$out/stats.csv"   # atomically, like dormant's own files
rows=$(( $(wc -l < "$out/stats.csv") - 1 ))
say "gathered ${#parts[@]} slices into $out: $rows rows in stats.csv, frames $(sed -n 2p "$out/stats.csv" | cut -d, -f1)..$(tail -n 1 "$out/stats.csv" | cut -d, -f1)"
