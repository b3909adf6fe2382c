#!/usr/bin/env python3
"""Which tests `make test` runs, as (crate, feature set, test name) triples, so a change to how
the suite is built can show that no test was dropped.

    scripts/test-inventory.py list > after.txt      # builds the test binaries (no test runs)
    scripts/test-inventory.py compare before.txt after.txt

`list` reads the cargo commands of `make -n test` (so it follows the Makefile of the checkout it
runs in), builds each command's test binaries with `--no-run`, and asks every binary (and the
doctests) for the tests it would run under that command's filters and environment, one line per
test: `crate<TAB>feature set<TAB>test`. The feature set is the cargo feature flags and the
environment variables the command sets. An integration-test binary's file is folded into the
test name (`tests/cli_render.rs`'s `renders` and `tests/suite/main.rs`'s module `cli_render`'s
`renders` both read `tests::cli_render::renders`), so one binary per file and one binary with a
module per file give the same lines.

`compare` prints the triples only one side has and exits 1 when the second file lacks any,
except those matched by a line of `--dropped FILE` (a regular expression per line, `#` comments),
the runs left out on purpose."""

import json
import os
import re
import shlex
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def make_commands():
    """The `cargo test` commands of `make -n test`, each as (env, argv)."""
    out = subprocess.run(["make", "-n", "--no-print-directory", "test"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    commands = []
    for line in out.splitlines():
        words = shlex.split(line)
        env = {}
        while words and re.match(r"^[A-Z_][A-Z0-9_]*=", words[0]):
            key, value = words.pop(0).split("=", 1)
            env[key] = value
        if len(words) >= 2 and words[0].endswith("cargo") and words[1] == "test":
            commands.append((env, words[1:]))
    return commands


def split_harness_args(args):
    """cargo's own arguments and the test harness's (a TESTNAME filter and what follows `--`)."""
    cargo, harness, i = [], [], 0
    takes_value = {"-p", "--package", "--test", "--bench", "--features", "-F", "--target-dir",
                   "--exclude", "--profile", "-j", "--jobs", "--bin", "--example"}
    while i < len(args):
        a = args[i]
        if a == "--":
            harness += args[i + 1:]
            break
        if a in takes_value:
            cargo += [a, args[i + 1]]
            i += 2
            continue
        if a.startswith("-"):
            cargo.append(a)
        else:
            harness.append(a)  # cargo test's TESTNAME: a filter the harness applies
        i += 1
    return cargo, harness


def feature_set(cargo, env):
    flags = [a for a in cargo if a in ("--no-default-features", "--all-features")]
    for i, a in enumerate(cargo):
        if a in ("--features", "-F"):
            flags.append(f"--features={cargo[i + 1]}")
    flags += [f"{k}={v}" for k, v in sorted(env.items())]
    return " ".join(flags) or "default"


def test_name(target, name):
    """A test's name with its integration-test file folded in (see the module doc)."""
    if "test" in target["kind"]:
        if target["name"] == "suite":
            return f"tests::{name}"
        return f"tests::{target['name']}::{name}"
    kind = "lib" if "lib" in target["kind"] else "+".join(target["kind"])
    return f"{kind}::{name}"


def package_name(package_id):
    """`path+file:///x/ffi#embree4-sys@0.1.0` or `path+file:///x/crates/dormant#0.1.0`."""
    where, _, fragment = package_id.partition("#")
    if "@" in fragment:
        return fragment.split("@")[0]
    return where.rstrip("/").split("/")[-1]


def list_command(env, argv):
    cargo, harness = split_harness_args(argv[1:])
    run_env = dict(os.environ, **env)
    build = subprocess.run(["cargo", "test", "--no-run", "--message-format=json"] + cargo,
                           cwd=ROOT, env=run_env, capture_output=True, text=True)
    if build.returncode != 0:
        sys.exit(f"test-inventory: {' '.join(argv)} did not build:\n{build.stderr[-3000:]}")
    features = feature_set(cargo, env)
    lines = []
    for msg in map(json.loads, build.stdout.splitlines()):
        if msg.get("reason") != "compiler-artifact" or not msg.get("executable"):
            continue
        if not msg["profile"]["test"]:
            continue
        crate = package_name(msg["package_id"])
        listing = subprocess.run([msg["executable"], "--list", "--format", "terse"] + harness,
                                 cwd=ROOT, env=run_env, capture_output=True, text=True,
                                 check=True).stdout
        for line in listing.splitlines():
            if line.endswith(": test"):
                lines.append(f"{crate}\t{features}\t{test_name(msg['target'], line[:-6])}")
    if not any(a in cargo for a in ("--lib", "--test", "--bins", "--bin", "--tests")):
        doc = subprocess.run(["cargo", "test", "--doc"] + cargo + ["--", "--list", "--format",
                             "terse"] + harness, cwd=ROOT, env=run_env, capture_output=True,
                             text=True, check=True)
        for line in doc.stdout.splitlines():
            if line.endswith(": test"):
                lines.append(f"doctest\t{features}\t{line[:-6]}")
    return lines


def normalise(line):
    """Doctest names carry a line number, which moves with unrelated edits."""
    return re.sub(r" \(line \d+\)$", "", line)


def compare(before_path, after_path, dropped_path):
    before = {normalise(l.rstrip("\n")) for l in open(before_path) if l.strip()}
    after = {normalise(l.rstrip("\n")) for l in open(after_path) if l.strip()}
    dropped = []
    if dropped_path:
        for l in open(dropped_path):
            l = l.split("#", 1)[0].strip()
            if l:
                dropped.append(re.compile(l))
    missing = sorted(before - after)
    on_purpose = [l for l in missing if any(d.search(l) for d in dropped)]
    lost = [l for l in missing if l not in on_purpose]
    added = sorted(after - before)
    print(f"before {len(before)}, after {len(after)}; dropped on purpose {len(on_purpose)}, "
          f"lost {len(lost)}, added {len(added)}")
    for title, rows in (("lost", lost), ("added", added)):
        for r in rows:
            print(f"{title}\t{r}")
    return 1 if lost else 0


def main():
    if len(sys.argv) >= 2 and sys.argv[1] == "list":
        for env, argv in make_commands():
            for line in list_command(env, argv):
                print(line)
        return 0
    if len(sys.argv) >= 4 and sys.argv[1] == "compare":
        dropped = None
        if "--dropped" in sys.argv:
            dropped = sys.argv[sys.argv.index("--dropped") + 1]
        return compare(sys.argv[2], sys.argv[3], dropped)
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
