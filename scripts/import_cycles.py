#!/usr/bin/env python3
"""Finds import circles between the source files of each crate (crates/*/src).

A file imports another when it names an item of that file's module through `crate::`,
`super::` or a re-export of the crate root (`crate::Name` where lib.rs has
`pub use module::Name`). Child modules declared inside a file count as part of it, and a
file's own `#[cfg(test)]` module is left out (tests may use anything). Prints each circle
(a strongly connected set of files) and exits 1 if there is one.
"""
import re
import sys
from pathlib import Path

USE_GROUP = re.compile(r"\buse\s+((?:crate|super)(?:::\w+)*)::\{", re.S)
PATH = re.compile(r"\b(crate|super)((?:::\w+)+)")


def expand(prefix: str, body: str) -> list:
    """`prefix::{a::B, c::{D, E}}` → the full paths (`body` without the outer braces)."""
    out, depth, item = [], 0, ""
    for ch in body + ",":
        if ch == "," and depth == 0:
            item = item.strip()
            if "{" in item:
                head, inner = item.split("{", 1)
                out += expand(prefix + "::" + head.rstrip(":").strip(), inner.rsplit("}", 1)[0])
            elif item and item != "self":
                out.append(prefix + "::" + item.split(" as ")[0].strip())
            item = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        item += ch
    return out


def grouped_uses(text: str) -> str:
    """Rewrites every `use crate::{…};` / `use super::{…};` as one path per line."""
    out, pos = [], 0
    for m in USE_GROUP.finditer(text):
        if m.start() < pos:
            continue
        depth, i = 1, m.end()
        while depth and i < len(text):
            depth += text[i] == "{"
            depth -= text[i] == "}"
            i += 1
        out.append(text[pos : m.start()])
        out.append("\n".join(expand(m.group(1), text[m.end() : i - 1])) + "\n")
        pos = i
    out.append(text[pos:])
    return "".join(out)


def module_of(src: Path, file: Path) -> tuple:
    rel = file.relative_to(src).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] in ("lib", "main", "mod"):
        parts = parts[:-1]
    return tuple(parts)


def strip_tests(text: str) -> str:
    """The file without its `#[cfg(test)]` module and without comments (doc links are not
    imports)."""
    m = re.search(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{", text)
    text = text[: m.start()] if m else text
    return re.sub(r"//[^\n]*", "", text)


def root_reexports(lib_text: str) -> dict:
    out = {}
    for m in re.finditer(r"pub\s+use\s+(\w+)(?:::(\w+))*::\{([^}]*)\}\s*;", lib_text, re.S):
        for name in re.split(r"[,\s]+", m.group(3)):
            name = name.split(" as ")[-1].strip()
            if name and name != "self":
                out[name] = (m.group(1),)
    for m in re.finditer(r"pub\s+use\s+(\w+)((?:::\w+)*)::(\w+)\s*;", lib_text):
        out[m.group(3)] = (m.group(1),)
    return out


def crate_cycles(crate: Path) -> list:
    src = crate / "src"
    files = {module_of(src, f): f for f in src.rglob("*.rs")}
    root = files.get(())
    reexports = root_reexports(root.read_text()) if root else {}
    edges = {m: set() for m in files}
    for mod, f in files.items():
        text = grouped_uses(strip_tests(f.read_text()))
        for m in PATH.finditer(text):
            head, rest = m.group(1), [p for p in m.group(2).split("::") if p]
            base = [] if head == "crate" else list(mod[:-1] if f.name != "mod.rs" else mod)
            if head == "super" and f.name == "mod.rs":
                base = list(mod[:-1])
            while rest and rest[0] == "super":
                base = base[:-1]
                rest = rest[1:]
            path = tuple(base + rest)
            target = None
            for n in range(len(path), 0, -1):
                if path[:n] in files:
                    target = path[:n]
                    break
            if target is None and head == "crate" and rest and rest[0] in reexports:
                target = reexports[rest[0]]
                if target not in files:  # a re-export of another crate's item
                    target = None
            if target is not None and target != mod and target != ():
                edges[mod].add(target)
    # Tarjan's strongly connected components.
    index, low, stack, on, comps, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                comps.append(comp)

    sys.setrecursionlimit(10000)
    for v in edges:
        if v not in index:
            visit(v)
    return [sorted("/".join(c) or "lib" for c in comp) for comp in comps]


def main() -> int:
    top = Path(__file__).resolve().parent.parent
    found = False
    for crate in sorted((top / "crates").iterdir()):
        if not (crate / "src").is_dir():
            continue
        for comp in crate_cycles(crate):
            found = True
            print(f"{crate.name}: import circle between " + ", ".join(comp))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
