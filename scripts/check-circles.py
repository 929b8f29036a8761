#!/usr/bin/env python3
"""Fails when modules use each other in a circle: inside each crate (`crate::`, `super::`,
`self::` paths and a module's paths to its own children) and among the page's ES modules
(web/*.js imports). A circle is a set of modules that cannot be split apart: each reaches the
others. Known circles are listed below with why they remain; a new one fails the check, and a
listed one that has gone must be taken off the list.
"""
import glob
import os
import re
import sys

# Circles left on purpose, until they are taken apart (each: where, and its modules); none now.
KNOWN = set()


def rust_modules(src):
    modules = {}
    for path in glob.glob(os.path.join(src, "**", "*.rs"), recursive=True):
        parts = os.path.relpath(path, src)[:-3].split(os.sep)
        if parts[-1] in ("lib", "main", "mod"):
            parts = parts[:-1]
        modules["::".join(parts)] = path
    return modules


def rust_edges(src):
    modules = rust_modules(src)
    edges = {m: set() for m in modules}
    for module, path in modules.items():
        with open(path, encoding="utf-8") as f:
            text = f.read()
        # Unit tests may use anything of their module's parent.
        text = text.split("#[cfg(test)]")[0]
        text = re.sub(r"//.*", "", text)
        here = module.split("::") if module else []
        refs = re.findall(r"\b((?:crate|super|self)(?:::\w+)+)", text)
        for base, items in re.findall(r"\b((?:crate|super|self)(?:::\w+)*)::\{([^}]*)\}", text):
            for item in items.split(","):
                item = item.strip().split(" as ")[0].split("::")[0]
                if item:
                    refs.append(base if item == "self" else f"{base}::{item}")
        for ref in refs:
            parts = ref.split("::")
            if parts[0] == "crate":
                base, rest = [], parts[1:]
            else:
                base, rest = list(here), parts
                while rest and rest[0] in ("super", "self"):
                    if rest[0] == "super":
                        base = base[:-1]
                    rest = rest[1:]
            for k in range(len(rest), -1, -1):
                candidate = "::".join(base + rest[:k])
                if candidate in modules:
                    if candidate not in ("", module):
                        edges[module].add(candidate)
                    break
        prefix = f"{module}::" if module else ""
        for child in modules:
            short = child[len(prefix):]
            if child.startswith(prefix) and child != module and "::" not in short:
                if re.search(r"(?<![:\w])" + short + r"::\w", text):
                    edges[module].add(child)
    return edges


def js_edges(folder):
    edges = {}
    for path in glob.glob(os.path.join(folder, "*.js")):
        with open(path, encoding="utf-8") as f:
            text = f.read()
        imported = re.findall(r"from\s+'\./([\w\-]+\.js)'", text)
        imported += re.findall(r"import\(\s*'\./([\w\-]+\.js)'", text)
        edges[os.path.basename(path)] = set(imported)
    return edges


def circles(edges):
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in edges:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(tuple(sorted(component)))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def main():
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    found = set()
    for src in sorted(glob.glob("crates/*/src")):
        found.update((src, c) for c in circles(rust_edges(src)))
    found.update(("web", c) for c in circles(js_edges("web")))
    status = 0
    for where, modules in sorted(found - KNOWN):
        print(f"check-circles: {where}: {', '.join(modules)} use each other in a circle", file=sys.stderr)
        status = 1
    for where, modules in sorted(KNOWN - found):
        print(f"check-circles: {where}: the known circle of {', '.join(modules)} has gone: "
              "take it off scripts/check-circles.py", file=sys.stderr)
        status = 1
    if status == 0:
        print(f"check-circles: no module circle beyond the {len(KNOWN)} known")
    return status


if __name__ == "__main__":
    sys.exit(main())
