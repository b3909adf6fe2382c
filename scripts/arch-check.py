#!/usr/bin/env python3
"""The architecture check (`make arch-check`): fails on an import cycle between modules, an
import against the layer order, or a breach of the house rules below. Cargo enforces the arrows
between the workspace's crates; this checks the arrows inside each crate.

- Layers: each crate's top-level modules have a layer (LAYERS below). A module may import
  modules of lower layers only; two modules of one layer may not import each other (render and
  residency, for instance, do not know each other).
- Cycles: at every level of the module tree, the sibling modules under one parent (a file, or
  a folder taken as a whole) must not import each other in a circle. A module may use what its
  parent declares; a name its parent re-exports counts as an import of the module that
  defines it.
- The core crate's API (crates/dormant/src), counted from the source: at most
  MAX_PUB_USE_NAMES `pub use` names and MAX_PUBLIC_ITEMS public items (see their comment);
  no glob re-export (`pub use a::*`) and no `#[doc(hidden)]`, which would hide names from
  the count and from the documentation. No dependency CORE_FORBIDDEN_DEPENDENCIES names (clap).
- No `clippy::too_many_arguments` allowed anywhere in the workspace (a parameter struct or a
  method on the value the arguments describe instead), nor its threshold raised.
- No function over LONG_FUNCTION_LINES lines in any crate's src/ (test modules aside),
  counted as ../shared/tools/long-functions counts.
- Every docs/ link in the Rust sources names a file and heading that exist.
- A comment in a crate's src/ that quotes a measured ratio (`1.3x`) links the docs/lab entry
  holding the measurement, and at most MAX_RATIO_COMMENTS do (ratios only: see there).

Imports are read from the source text: `use` trees and `crate::`/`super::`/`self::` paths in
code (comments and string literals stripped), and paths through child modules a file declares.
No build and no nightly toolchain: pure Python over the source, in well under a second.
Usage: scripts/arch-check.py [--graph]  (--graph prints every module edge found)."""

import os
import re
import sys
from collections import defaultdict

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Per crate: its source folder, root file, and the layer of each top-level module (lowest
# first). A top-level module missing here is an error, so a new domain gets a place on purpose.
CRATES = {
    "dormant": ("crates/dormant/src", "lib.rs", {
        "atomic_file": 0, "rng": 0, "geometry": 0, "names": 0,
        "scene": 1,
        "physics": 2,
        "accel": 3,
        "render": 4, "residency": 4,
        "sequence": 5,
        "prelude": 6,
    }),
    "dormant-embree": ("crates/dormant-embree/src", "lib.rs", {
        "error": 0, "quality": 0, "motion": 0,
        "device": 1,
        "filter": 2, "geometry": 2,
        "view": 3,
        "frozen": 4, "packet": 4,
        "instance_array": 5,
        "scene": 6,
    }),
    "dormant-lab": ("crates/dormant-lab/src", "lib.rs", {
        "report": 0, "crosscheck": 0,
        "bench": 1,
        "paper": 2, "regimes": 2,
    }),
    "dormant-cli": ("src", "main.rs", {
        "report": 0,
        "cli": 1,
    }),
}


# The core crate's API caps, counted from the source (scripts/api-size.py counts the same API
# with rustdoc JSON, which needs a nightly toolchain and a build). Re-baselined at commit
# 25660ea ("A curated API within the house's limits"), where api-size.py counted 120 `pub use`
# names and 439 public items by rustdoc; this script's counts of that commit's source are the
# caps: 120 names (api-size.py's own `pub_use_names`, the same count) and 459 items (the source
# count also takes public items in private modules and of private types, which rustdoc does not
# reach, so it is higher than rustdoc's). Raise a cap only on purpose, with its new provenance.
API_CRATE = "dormant"
MAX_PUB_USE_NAMES = 120
MAX_PUBLIC_ITEMS = 459
# Declarations with plain `pub` (not `pub(crate)`, `pub(super)`, ...): functions (inherent
# methods included; trait methods have no `pub`), types, traits, constants (associated ones
# included), statics, type aliases and modules. Fields and enum variants are parts of their type.
PUBLIC_ITEM = re.compile(
    r"(?<![\w:])pub\s+(?:(?:const|async|unsafe|extern)\s+)*(fn|struct|enum|union|trait|const|static|type|mod)\b")

# Dependencies the core crate must not take: what the CLI owns stays in the CLI (the core's
# enums get their names through names.rs's `named_enum!`; the CLI parses them).
CORE_FORBIDDEN_DEPENDENCIES = {"clap": "argument parsing belongs to dormant-cli"}

# The longest function allowed in any crate's src/, in lines (../shared/tools/long-functions).
LONG_FUNCTION_LINES = 80
# Folders the workspace-wide rules do not look into (build outputs, dependencies, VCS).
NOT_SOURCES = {"target", ".git", ".deps", "out", "node_modules"}

def strip_comments_and_strings(text):
    """Source without comments, string and char literals (replaced by spaces)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 8]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            end = text.find('"' + hashes, i + 2 + len(hashes))
            i = n if end < 0 else end + 1 + len(hashes)
            out.append(" ")
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            i += 1
            out.append(" ")
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", text[i:i + 4] + "    "):
            m = re.match(r"'(\\x..|\\u\{[0-9a-fA-F]+\}|\\.|[^\\'])'", text[i:])
            i += len(m.group(0)) if m else 1
            out.append(" ")
        else:
            out.append(c)
            i += 1
    return "".join(out)


class Crate:
    def __init__(self, name, src, root_file, layers):
        self.name, self.src, self.layers = name, os.path.join(ROOT, src), layers
        self.files = {}  # module path tuple -> file
        self.children = defaultdict(set)  # module -> declared child names
        self.text = {}
        self._collect(os.path.join(self.src, root_file), ())
        self.reexports = {m: self._reexports(m) for m in self.files}

    def _collect(self, path, module):
        self.files[module] = path
        text = without_test_blocks(strip_comments_and_strings(open(path, encoding="utf-8").read()))
        self.text[module] = text
        here = os.path.dirname(path)
        is_dir_module = os.path.basename(path) in ("mod.rs", "lib.rs", "main.rs")
        for m in re.finditer(r"(?m)^\s*((?:#\[[^\]]*\]\s*)*)(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;", text):
            if "cfg(test)" in m.group(1):
                continue  # test-only modules are not part of the architecture
            child = m.group(2)
            base = here if is_dir_module else os.path.join(here, os.path.splitext(os.path.basename(path))[0])
            for candidate in (os.path.join(base, child + ".rs"), os.path.join(base, child, "mod.rs")):
                if os.path.isfile(candidate):
                    self.children[module].add(child)
                    self._collect(candidate, module + (child,))
                    break
            else:
                raise SystemExit(f"arch-check: {path}: `mod {child};` has no file")

    def use_paths(self, module):
        """Every path the module's `use` items name, as segment lists (leaf names included)."""
        paths = []
        for m in re.finditer(r"\buse\s+([^;]+);", self.text[module]):
            paths.extend(expand_use_tree(m.group(1).strip()))
        return paths

    def _reexports(self, module):
        """Names the module re-exports (`pub use` / `pub(...) use`) -> the path they come from."""
        out = {}
        for m in re.finditer(r"\bpub(?:\([^)]*\))?\s+use\s+([^;]+);", self.text[module]):
            for path in expand_use_tree(m.group(1).strip()):
                alias = path[-1]
                if " as " in alias:
                    path[-1], alias = [s.strip() for s in alias.split(" as ")]
                if alias != "*":
                    out[alias] = path
        return out

    def resolve(self, module, path, depth=0):
        """The module a path used in `module` refers to (following re-exports), or None when it
        leaves the crate (another crate, the standard library) or names the module itself."""
        segs = list(path)
        if not segs:
            return None
        if segs[0] == "crate":
            base, segs = (), segs[1:]
        elif segs[0] in ("super", "self"):
            base = module
            while segs and segs[0] in ("super", "self"):
                if segs[0] == "super":
                    base = base[:-1]
                segs = segs[1:]
        elif segs[0] in self.children[module]:
            base = module
        else:
            return None
        target = base
        for i, s in enumerate(segs):
            if s in self.children[target]:
                target = target + (s,)
                continue
            # An item of `target`: if `target` re-exports it, the defining module counts.
            if depth < 8 and s in self.reexports.get(target, {}):
                resolved = self.resolve(target, self.reexports[target][s] + segs[i + 1:], depth + 1)
                if resolved is not None:
                    return resolved
            break
        return target

    def edges(self):
        """(from module, to module) for every import inside the crate."""
        found = set()
        for module, text in self.text.items():
            paths = self.use_paths(module)
            code = re.sub(r"\buse\s+[^;]+;", " ", text)
            for m in re.finditer(r"\b((?:crate|super|self)(?:\s*::\s*\w+)+)", code):
                paths.append([s.strip() for s in m.group(1).split("::")])
            for child in self.children[module]:
                for m in re.finditer(r"(?<![\w:])" + child + r"((?:\s*::\s*\w+)+)", code):
                    paths.append([child] + [s.strip() for s in m.group(1).split("::")[1:]])
            for path in paths:
                target = self.resolve(module, path)
                if target is not None and target != module:
                    found.add((module, target))
        return found


def without_test_blocks(text):
    """`text` without its `#[cfg(test)]` inline modules and items (tests are not part of the
    architecture)."""
    while True:
        m = re.search(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?(?:mod|fn|impl|use)\b[^{;]*([{;])", text)
        if not m:
            return text
        end = m.end()
        if m.group(1) == "{":
            depth = 1
            while end < len(text) and depth:
                depth += (text[end] == "{") - (text[end] == "}")
                end += 1
        text = text[:m.start()] + text[end:]


def expand_use_tree(tree):
    """`a::{b, c::{d, e as f}}` -> [[a, b], [a, c, d], [a, c, e as f]]."""
    tree = re.sub(r"\s+", " ", tree).strip()
    if tree.startswith("::"):
        tree = tree[2:]
    brace = tree.find("{")
    if brace < 0:
        return [[s.strip() for s in tree.split("::")]]
    prefix = [s.strip() for s in tree[:brace].rstrip(":").split("::") if s.strip()]
    inner, depth, parts, start = tree[brace + 1:tree.rfind("}")], 0, [], 0
    for i, c in enumerate(inner):
        depth += (c == "{") - (c == "}")
        if c == "," and depth == 0:
            parts.append(inner[start:i])
            start = i + 1
    parts.append(inner[start:])
    out = []
    for p in parts:
        p = p.strip()
        if not p:
            continue
        if p == "self":
            out.append(prefix[:])
        else:
            out.extend(prefix + sub for sub in expand_use_tree(p))
    return out


def sccs(nodes, adjacency):
    """Strongly connected components (Tarjan), iteratively."""
    index, low, on_stack, stack, result, counter = {}, {}, set(), [], [], [0]
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(adjacency.get(root, ()))))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, it = work[-1]
            advanced = False
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter[0]
                    counter[0] += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(adjacency.get(nxt, ())))))
                    advanced = True
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    component.append(w)
                    if w == node:
                        break
                result.append(component)
    return result


def name(module):
    return "::".join(module) or "(root)"


def check(crate, show_graph):
    problems = []
    edges = crate.edges()
    for top in crate.children[()]:
        if top not in crate.layers:
            problems.append(f"{crate.name}: top-level module `{top}` has no layer in scripts/arch-check.py")
    for a, b in sorted(edges):
        if show_graph:
            print(f"{crate.name}: {name(a)} -> {name(b)}")
        if not a or not b or a[0] == b[0]:
            continue
        la, lb = crate.layers.get(a[0]), crate.layers.get(b[0])
        if la is not None and lb is not None and lb >= la:
            what = "an upward arrow" if lb > la else "an arrow within one layer"
            problems.append(f"{crate.name}: {name(a)} imports {name(b)}: {what} ({a[0]} is layer {la}, {b[0]} layer {lb})")
    # Cycles among siblings, at every parent.
    for parent in list(crate.files):
        kids = sorted(crate.children[parent])
        if len(kids) < 2:
            continue
        depth = len(parent)
        adjacency = defaultdict(set)
        for a, b in edges:
            if len(a) > depth and len(b) > depth and a[:depth] == parent and b[:depth] == parent and a[depth] != b[depth]:
                adjacency[a[depth]].add(b[depth])
        for component in sccs(kids, adjacency):
            if len(component) > 1:
                where = name(parent)
                ties = [f"{name(a)} -> {name(b)}" for a, b in sorted(edges)
                        if len(a) > depth and len(b) > depth and a[:depth] == parent and b[:depth] == parent
                        and a[depth] in component and b[depth] in component and a[depth] != b[depth]]
                problems.append(f"{crate.name}: import cycle among the modules of {where}: "
                                f"{', '.join(sorted(component))} ({'; '.join(ties)})")
    return problems, len(edges), len(crate.files)


def load_api_size():
    """scripts/api-size.py as a module: the owner of the `pub use` name count."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("api_size", os.path.join(ROOT, "scripts", "api-size.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def api_counts(crate):
    """(`pub use` names, public items by kind) of `crate`, from its source."""
    import pathlib
    names = load_api_size().pub_use_names(pathlib.Path(crate.src))
    kinds = defaultdict(int)
    for text in crate.text.values():
        for m in PUBLIC_ITEM.finditer(text):
            kinds[m.group(1)] += 1
    return names, kinds


def api_problems(crate):
    """The core crate's API against its caps, glob re-exports and `#[doc(hidden)]`."""
    problems = []
    names, kinds = api_counts(crate)
    items = sum(kinds.values())
    detail = ", ".join(f"{k} {n}" for k, n in sorted(kinds.items()))
    over = []
    if names > MAX_PUB_USE_NAMES:
        over.append(f"{names} `pub use` names, cap {MAX_PUB_USE_NAMES} (+{names - MAX_PUB_USE_NAMES})")
    if items > MAX_PUBLIC_ITEMS:
        over.append(f"{items} public items, cap {MAX_PUBLIC_ITEMS} (+{items - MAX_PUBLIC_ITEMS}; {detail})")
    if over:
        problems.append(f"{crate.name}: the public API is over its cap: {'; '.join(over)}. Give the new "
                        f"names a home that does not widen the API (a method of the type they serve, "
                        f"`pub(crate)`, one re-export fewer) rather than raising the caps "
                        f"(MAX_PUB_USE_NAMES, MAX_PUBLIC_ITEMS in scripts/arch-check.py)")
    for module, text in sorted(crate.text.items()):
        where = os.path.relpath(crate.files[module], ROOT)
        for m in re.finditer(r"\bpub\s+use\s+([^;]+);", text):
            for path in expand_use_tree(m.group(1).strip()):
                if path[-1] == "*":
                    problems.append(f"{crate.name}: {where}: glob re-export `pub use {'::'.join(path)}` "
                                    f"(name each item: the API count and the reader see only named ones)")
        if not re.search(r"\bdoc\s*\(\s*hidden\b", text):
            continue
        raw = open(crate.files[module], encoding="utf-8").read().split("\n")
        for line in (i for i, l in enumerate(raw, 1)
                     if re.search(r"\bdoc\s*\(\s*hidden\b", l) and not l.lstrip().startswith("//")):
            problems.append(f"{crate.name}: {where}:{line}: `#[doc(hidden)]` hides an item from the API "
                            f"count and the documentation (make it `pub(crate)` or document it)")
    return problems, names, items


def workspace_files(suffixes):
    """Every file of the checkout ending in one of `suffixes`, outside NOT_SOURCES, sorted."""
    found = []
    for root, dirs, files in os.walk(ROOT):
        dirs[:] = sorted(d for d in dirs if d not in NOT_SOURCES)
        found.extend(os.path.join(root, f) for f in files if f.endswith(suffixes))
    return sorted(found)


def too_many_arguments_problems():
    """`clippy::too_many_arguments` allowed (or expected) in any Rust source of the workspace,
    or its threshold raised in a clippy.toml or a Cargo.toml `[lints]` table."""
    problems = []
    for path in workspace_files((".rs",)):
        code = strip_comments_and_strings(open(path, encoding="utf-8", errors="replace").read())
        for m in re.finditer(r"\btoo_many_arguments\b", code):
            line = code.count("\n", 0, m.start()) + 1
            problems.append(f"{os.path.relpath(path, ROOT)}:{line}: `clippy::too_many_arguments` allowed: "
                            f"pass a parameter struct, or make the function a method of what its "
                            f"arguments describe")
    for path in workspace_files(("clippy.toml", "Cargo.toml")):
        for i, line in enumerate(open(path, encoding="utf-8", errors="replace"), 1):
            if re.search(r"too[-_]many[-_]arguments", line.split("#")[0]):
                problems.append(f"{os.path.relpath(path, ROOT)}:{i}: clippy's too_many_arguments "
                                f"configured (the default threshold holds everywhere)")
    return problems


def markdown_anchors(path):
    """The anchors of a Markdown file's headings, as GitHub makes them."""
    anchors, seen = set(), defaultdict(int)
    in_code = False
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"):
            in_code = not in_code
        m = None if in_code else re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            slug = re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-")
            anchors.add(slug if not seen[slug] else f"{slug}-{seen[slug]}")
            seen[slug] += 1
    return anchors


def doc_link_problems():
    """Links from the Rust sources' comments into docs/ (`docs/lab/<file>.md#<anchor>`: where a
    comment's measurement lives) whose file or heading does not exist. String literals are
    left alone (a test may build links that point nowhere on purpose)."""
    problems, anchors = [], {}
    for path in workspace_files((".rs",)):
        text = open(path, encoding="utf-8", errors="replace").read()
        for m in re.finditer(r"\bdocs/([\w./-]+?\.md)(?:#([\w-]+))?", text):
            line_start = text.rfind("\n", 0, m.start()) + 1
            if "//" not in text[line_start:m.start()]:
                continue
            doc = os.path.join(ROOT, "docs", m.group(1))
            where = f"{os.path.relpath(path, ROOT)}:{text.count(chr(10), 0, m.start()) + 1}"
            if not os.path.isfile(doc):
                problems.append(f"{where}: links docs/{m.group(1)}, which does not exist")
            elif m.group(2):
                if doc not in anchors:
                    anchors[doc] = markdown_anchors(doc)
                if m.group(2) not in anchors[doc]:
                    problems.append(f"{where}: links docs/{m.group(1)}#{m.group(2)}, a heading that does not exist")
    return problems


# A comment that quotes a measured speed ratio (`1.3x`, `0.72-0.78x`) must link the docs/lab
# entry that holds the measurement, and few may quote one at all: the history lives in the lab
# notebook, a comment says why in a line. Only ratios are checked: percentages and times also
# state thresholds, definitions and sizes, which a pattern cannot tell from measurements.
MAX_RATIO_COMMENTS = 10
RATIO = re.compile(r"(?<![\w.])\d+(?:\.\d+)?(?:-\d+(?:\.\d+)?)?x\b")


def comment_blocks(path):
    """(first line, text) of each run of comment lines of one kind (`//!`, `///`, `//`) in a Rust
    file, outside test modules (`#[cfg(test)]` then `mod NAME {`)."""
    lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
    blocks, i = [], 0
    while i < len(lines):
        m = re.match(r"^(\s*)#\[cfg\(test\)\]\s*$", lines[i])
        if m and i + 1 < len(lines) and re.match(r"^\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{", lines[i + 1]):
            i += 2
            while i < len(lines) and not lines[i].startswith(m.group(1) + "}"):
                i += 1
            i += 1
            continue
        kind = re.match(r"^\s*(//[/!]?)", lines[i])
        if not kind:
            i += 1
            continue
        j = i
        while j < len(lines) and re.match(r"^\s*(//[/!]?)", lines[j]) and \
                re.match(r"^\s*(//[/!]?)", lines[j]).group(1) == kind.group(1):
            j += 1
        blocks.append((i + 1, "\n".join(lines[i:j])))
        i = j
    return blocks


def ratio_comment_problems():
    """Comment blocks in the crates' src/ that quote a ratio without a docs/lab link, and more
    than MAX_RATIO_COMMENTS of them."""
    problems, quoting = [], []
    for path in workspace_files((".rs",)):
        rel = os.path.relpath(path, ROOT)
        if "/src/" not in "/" + rel:
            continue
        for line, text in comment_blocks(path):
            if RATIO.search(text):
                quoting.append(f"{rel}:{line}")
                if "docs/lab/" not in text:
                    problems.append(f"{rel}:{line}: a comment quotes a measured ratio "
                                    f"({RATIO.search(text).group(0)}) without the docs/lab entry that holds "
                                    f"the measurement: link it, or say why in a line and move the figures there")
    if len(quoting) > MAX_RATIO_COMMENTS:
        problems.append(f"{len(quoting)} comments quote measured ratios, more than {MAX_RATIO_COMMENTS}: "
                        f"leave the figures to docs/lab ({', '.join(quoting)})")
    return problems, len(quoting)


def long_functions(limit=LONG_FUNCTION_LINES):
    """(lines, path, line, name) of each function longer than `limit` lines in any src/ folder
    of the workspace, counted as ../shared/tools/long-functions counts: a function runs from its
    `fn` line to the first later line at its own indentation that starts with `}`; test modules
    (`#[cfg(test)]` then `mod NAME {`) are skipped, and a `#[cfg(test)]` on another item skips
    only that item's function."""
    fn_re = re.compile(r'^(\s*)(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?(extern\s+"C"\s+)?fn\s+(\w+)')
    mod_re = re.compile(r'^(\s*)(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{')
    skip = {"target", ".git", ".deps", "fuzz", "tests", "benches", "out", "node_modules"}

    def block_end(lines, i, indent):
        for j in range(i + 1, len(lines)):
            if lines[j].startswith(indent + "}"):
                return j
        return len(lines) - 1

    found = []
    for root, dirs, files in os.walk(ROOT):
        dirs[:] = sorted(d for d in dirs if d not in skip)
        rel = "./" + os.path.relpath(root, ROOT)
        if "/src" not in rel + "/" and not rel.endswith("/src"):
            continue
        for f in sorted(files):
            if not f.endswith(".rs"):
                continue
            path = os.path.join(root, f)
            lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
            i, test_attr = 0, False
            while i < len(lines):
                line = lines[i]
                if re.match(r"^\s*#\[cfg\(test\)\]", line):
                    test_attr = True
                    i += 1
                    continue
                m = mod_re.match(line)
                if m and test_attr:
                    i = block_end(lines, i, m.group(1)) + 1
                    test_attr = False
                    continue
                m = fn_re.match(line)
                if m and not line.rstrip().endswith(";"):
                    n = block_end(lines, i, m.group(1)) - i + 1
                    if n > limit and not test_attr:
                        found.append((n, os.path.relpath(path, ROOT), i + 1, m.group(8)))
                if line.strip() and not line.strip().startswith("#["):
                    test_attr = False
                i += 1
    return found


def core_dependency_problems():
    """Dependencies of the core crate's [dependencies] table that CORE_FORBIDDEN_DEPENDENCIES names."""
    import tomllib
    with open(os.path.join(ROOT, "crates", API_CRATE, "Cargo.toml"), "rb") as f:
        manifest = tomllib.load(f)
    deps = manifest.get("dependencies", {})
    return [f"crates/{API_CRATE}/Cargo.toml: [dependencies] has `{name}`: {why}"
            for name, why in sorted(CORE_FORBIDDEN_DEPENDENCIES.items()) if name in deps]


def main():
    show_graph = "--graph" in sys.argv[1:]
    problems, summary = [], []
    for crate_name, (src, root_file, layers) in CRATES.items():
        crate = Crate(crate_name, src, root_file, layers)
        found, edge_count, modules = check(crate, show_graph)
        problems.extend(found)
        summary.append(f"{crate_name}: {modules} modules, {edge_count} arrows")
        if crate_name == API_CRATE:
            found, names, items = api_problems(crate)
            problems.extend(found)
            api = (f"{crate_name} API: {names}/{MAX_PUB_USE_NAMES} `pub use` names, "
                   f"{items}/{MAX_PUBLIC_ITEMS} public items")
    problems.extend(core_dependency_problems())
    problems.extend(too_many_arguments_problems())
    problems.extend(doc_link_problems())
    found, ratio_comments = ratio_comment_problems()
    problems.extend(found)
    for lines, path, line, fn in long_functions():
        problems.append(f"{path}:{line}: `fn {fn}` is {lines} lines, over {LONG_FUNCTION_LINES}: split it "
                        f"into steps with names")
    for p in problems:
        print("arch-check:", p)
    ratios = f"{ratio_comments}/{MAX_RATIO_COMMENTS} comments quoting a ratio"
    print("arch-check:", "; ".join(summary + [api, ratios]), f"; {len(problems)} problem(s)")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
