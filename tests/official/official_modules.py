"""What the vector generators share: the official code's modules loaded by file, and the generators' arguments.

The official repositories' `internal/__init__.py` imports every module (flax, gin and more); a generator needs a few
modules that import only their siblings. `internal_module` gives them a bare package object whose path is that
folder, named as the siblings import it, so `from internal import math` (multinerf) or a relative import
(camp_zipnerf) resolves there and nothing else is imported."""
import argparse
import importlib
import os
import sys
import types


def internal_module(folder, package, name):
    """Module `name` of the official `folder`, imported as `package.name` through a bare package `package`."""
    if package not in sys.modules:
        bare = types.ModuleType(package)
        bare.__path__ = [folder]
        sys.modules[package] = bare
    return importlib.import_module(package + "." + name)


def zipnerf_module(zipnerf, name):
    """A module of camp_zipnerf/internal (coord, stepfun, loss_utils, math, ...)."""
    return internal_module(os.path.join(zipnerf, "camp_zipnerf", "internal"), "zipnerf_internal", name)


def multinerf_module(multinerf, name):
    """A module of multinerf/internal, whose modules import their siblings as `internal`."""
    return internal_module(os.path.join(multinerf, "internal"), "internal", name)


def official_arguments(doc, repository):
    """The generator's arguments: --REPOSITORY (a checkout, read), --REPOSITORY-commit (recorded) and --out."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument(f"--{repository}", required=True, help=f"a checkout of {repository} (its files are read)")
    parser.add_argument(f"--{repository}-commit", required=True)
    parser.add_argument("--out", required=True)
    return parser.parse_args()
