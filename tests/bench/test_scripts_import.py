#!/usr/bin/env python3
"""Every script of bench/ and bench/lib/ compiles and imports with the standard library alone, as the studies and the
device check (scripts/device-check.sh: bench/official_step.py, which imports vs_official) are run: a syntax error, a
broken import between studies or a module-level failure fails this (CTest `bench: every bench script imports`).
The heavy dependencies (JAX, numpy) are imported inside the functions that need them, never at module level.

Usage: test_scripts_import.py BENCH_DIR"""

import glob
import importlib
import os
import sys

bench = os.path.abspath(sys.argv[1])
sys.path.insert(0, bench)
sys.dont_write_bytecode = True  # nothing written into the source tree
names = sorted(os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(bench, "*.py")))
names += sorted("lib." + os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(bench, "lib", "*.py"))
                if not p.endswith("__init__.py"))
failed = []
for name in names:
    try:
        importlib.import_module(name)
    except BaseException as e:  # SystemExit too: a study must not exit on import
        failed.append(f"{name}: {type(e).__name__}: {e}")
for line in failed:
    print("FAIL " + line)
print(f"{len(names) - len(failed)} of {len(names)} bench modules import")
sys.exit(1 if failed or len(names) < 20 else 0)
