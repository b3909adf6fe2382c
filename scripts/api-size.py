#!/usr/bin/env python3
"""The size of the core crate's public API: its public items (rustdoc JSON) and its `pub use`
names (source).

Usage: scripts/api-size.py            (builds the JSON with `cargo +nightly rustdoc`)
       scripts/api-size.py FILE.json  (counts a JSON built before)

Items are the crate's own public functions, structs, enums, traits, constants, associated
constants and modules reachable by the JSON (fields and enum variants are not counted: they are
parts of their type). Needs a nightly toolchain for the JSON: `rustup toolchain install nightly`.
"""
import collections
import json
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
KINDS = ("function", "struct", "enum", "trait", "constant", "assoc_const", "module")


def rustdoc_json() -> pathlib.Path:
    subprocess.run(
        ["cargo", "+nightly", "rustdoc", "-q", "-p", "dormant", "--lib", "--",
         "-Z", "unstable-options", "--output-format", "json"],
        cwd=ROOT, check=True, stderr=subprocess.DEVNULL)
    return ROOT / "target" / "doc" / "dormant.json"


def public_items(path: pathlib.Path) -> collections.Counter:
    index = json.loads(path.read_text())["index"]
    kinds = collections.Counter()
    for item in index.values():
        inner = item.get("inner") or {}
        kind = next(iter(inner), None)
        if item.get("crate_id") == 0 and kind in KINDS and item.get("visibility") == "public":
            kinds[kind] += 1
    return kinds


def pub_use_names(src: pathlib.Path) -> int:
    count = 0
    for file in src.rglob("*.rs"):
        for m in re.finditer(r"(?m)^\s*pub use ([^;]+);", file.read_text()):
            body = m.group(1)
            if "{" in body:
                body = body[body.index("{") + 1:body.rindex("}")]
            count += sum(1 for n in re.split(r"[,{}]", body) if n.strip() and not n.strip().endswith("::"))
    return count


def main() -> None:
    path = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else rustdoc_json()
    kinds = public_items(path)
    detail = ", ".join(f"{k} {kinds[k]}" for k in KINDS)
    print(f"public items: {sum(kinds.values())} ({detail})")
    print(f"pub use names: {pub_use_names(ROOT / 'crates' / 'dormant' / 'src')}")


if __name__ == "__main__":
    main()
