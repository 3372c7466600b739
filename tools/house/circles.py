#!/usr/bin/env python3
"""Import circles between a workspace's source files.

Reads every `src/**/*.rs` of the crates given (default: `crates/*` and `backends/wgpu`), maps each
file to its module path, and draws an edge from a file to every module file its `use` lines and
`crate::`/`super::`/`self::` paths name. A module's edges to its own descendants are left out:
a parent declaring and re-exporting its children is the hierarchy, not an import. Prints each
strongly connected set of more than one file (an import circle), and their count last.

Run from the repository root: `python3 tools/house/circles.py [crate dirs...]`.
"""
import os
import re
import sys
from pathlib import Path


def module_files(src: Path):
    """Module path (a tuple) of every .rs file under `src`, the crate root being ()."""
    files = {}
    for path in src.rglob("*.rs"):
        parts = list(path.relative_to(src).with_suffix("").parts)
        if parts in (["lib"], ["main"]):
            parts = []
        elif parts[-1] == "mod":
            parts = parts[:-1]
        if "bin" in path.relative_to(src).parts[:1]:
            continue
        files.setdefault(tuple(parts), path)
    return files


PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
USE_GROUP = re.compile(r"\buse\s+(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)*)::\{([^;]*)\};", re.S)


def strip_comments(text: str) -> str:
    text = re.sub(r"//[^\n]*", "", text)
    return re.sub(r"/\*.*?\*/", "", text, flags=re.S)


def test_module_start(text: str) -> str:
    """The text before a `#[cfg(test)] mod tests {` block: tests may import anything."""
    at = re.search(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{", text)
    return text[: at.start()] if at else text


def targets(module, text, files):
    """The module files that `module`'s text names."""
    named = []
    for root, rest in PATH.findall(text):
        named.append((root, [p for p in rest.split("::") if p]))
    for root, prefix, group in USE_GROUP.findall(text):
        base = [p for p in prefix.split("::") if p]
        for item in re.split(r",", re.sub(r"\{[^}]*\}", "", group)):
            item = item.strip().split(" as ")[0]
            if item and item != "self":
                named.append((root, base + [p for p in item.split("::") if p]))
    found = set()
    for root, parts in named:
        if root == "crate":
            base = []
        elif root == "self":
            base = list(module)
        else:
            base = list(module[:-1])
            while parts and parts[0] == "super":
                base, parts = base[:-1], parts[1:]
        path = base + parts
        # The longest prefix that is a module file.
        while path and tuple(path) not in files:
            path = path[:-1]
        target = tuple(path)
        if target in files and target != module and target[: len(module)] != module:
            found.add(target)
    return found


def circles(crate: Path):
    src = crate / "src"
    files = module_files(src)
    graph = {}
    for module, path in files.items():
        text = test_module_start(strip_comments(path.read_text()))
        graph[module] = targets(module, text, files)
    # Tarjan's strongly connected components.
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(group)

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return [[os.path.relpath(files[m]) for m in sorted(g)] for g in out]


def main():
    crates = [Path(p) for p in sys.argv[1:]] or sorted(Path("crates").iterdir()) + [Path("backends/wgpu")]
    total = 0
    for crate in crates:
        for group in circles(crate):
            total += 1
            print("circle: " + " <-> ".join(group))
    print(f"{total} import circles")


if __name__ == "__main__":
    main()
