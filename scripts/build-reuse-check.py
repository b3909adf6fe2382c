#!/usr/bin/env python3
"""Checks that the release build and the test build share their compiled crates: run after
`cargo test --release --workspace` (the end of `make test` runs it), it builds the release
workspace and fails if anything had to be compiled, naming what. A test build compiles the
dev-dependencies, and their features unify with the normal dependencies'; where they differ
(serde's `alloc`, say), every crate above the one that differs is compiled twice, once per
feature set, and `make test` after `make build` spends minutes on it. The pins in
crates/dormant/Cargo.toml and the root Cargo.toml make the sets equal; a new dependency can
make them differ again, and this says which crate to pin.

Usage: scripts/build-reuse-check.py  (from any directory; uses the checkout's target/)"""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    build = subprocess.run(
        ["cargo", "build", "--release", "--workspace", "--message-format=json"],
        cwd=ROOT, capture_output=True, text=True)
    if build.returncode != 0:
        sys.exit(f"build-reuse-check: the release build failed:\n{build.stderr[-3000:]}")
    compiled = []
    for line in build.stdout.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and not msg.get("fresh", True):
            kinds = "+".join(msg["target"]["kind"])
            compiled.append(f"{msg['package_id'].split('#')[-1]} ({kinds} {msg['target']['name']})")
    if compiled:
        print("build-reuse-check: the release build after the test build compiled again:")
        for c in compiled:
            print(f"  {c}")
        print("The test build's dev-dependencies turn on features of these crates (or of one "
              "they depend on) that the release build does not: pin them in "
              "crates/dormant/Cargo.toml (see its comment); `cargo tree -e features -i CRATE` "
              "shows who turns what on.")
        return 1
    print("build-reuse-check: the release build reuses the test build's crates")
    return 0


if __name__ == "__main__":
    sys.exit(main())
