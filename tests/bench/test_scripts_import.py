#!/usr/bin/env python3
"""Every study of bench/studies/ and every module of bench/lib/ compiles and imports with the standard library alone, as the studies and the
device check (scripts/device-check.sh runs bench/studies/official_step.py) are run: a syntax error, a broken import between
modules or a module-level failure fails this (CTest `bench: every bench script imports`). The heavy dependencies
(JAX, numpy) are imported inside the functions that need them, never at module level. And the imports between
bench's own modules (at any level, read with ast) form no circle: shared code lives in bench/lib/ (until 2026-11-27,
vs_official.py and vs_official_llff.py imported each other).

Usage: test_scripts_import.py BENCH_DIR"""

import ast
import glob
import importlib
import os
import sys

bench = os.path.abspath(sys.argv[1])
sys.path.insert(0, bench)
sys.path.insert(1, os.path.join(bench, "studies"))  # a study imports as its file name, as when it runs
sys.dont_write_bytecode = True  # nothing written into the source tree
names = sorted(os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(bench, "studies", "*.py")))
names += sorted("lib." + os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(bench, "lib", "*.py"))
                if not p.endswith("__init__.py"))
failed = []


def local_imports(name):
    """The bench modules `name` imports anywhere in its source (lib.x as lib.x)."""
    path = os.path.join(bench, *name.split(".")) + ".py" if name.startswith("lib.") else \
        os.path.join(bench, "studies", name + ".py")
    found = set()
    for node in ast.walk(ast.parse(open(path).read(), path)):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
    return sorted(found & set(names))


graph = {name: local_imports(name) for name in names}


def circle_from(start):
    """A list of modules that import each other round to `start`, or None."""
    stack = [(start, [start])]
    while stack:
        node, path = stack.pop()
        for nxt in graph[node]:
            if nxt == start:
                return path + [start]
            if nxt not in path:
                stack.append((nxt, path + [nxt]))
    return None


for name in names:
    circle = circle_from(name)
    if circle:
        failed.append(f"{name}: an import circle: {' -> '.join(circle)}")
        break
for name in names:
    try:
        importlib.import_module(name)
    except BaseException as e:  # SystemExit too: a study must not exit on import
        failed.append(f"{name}: {type(e).__name__}: {e}")
for line in failed:
    print("FAIL " + line)
print(f"{len(names) - len(failed)} of {len(names)} bench modules import")
sys.exit(1 if failed or len(names) < 20 else 0)
