#!/usr/bin/env python3
"""Zip-NeRF's grid encoding as test vectors from its official code (tests/official/fixtures/zipnerf_grid.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:jonbarron/camp_zipnerf (read through
sys.path, never copied). It calls the official functions themselves on fixed inputs and records what they return:
  - grid_utils.HashEncoding.grid_sizes for several (min, max, supersample) settings (its level sizes);
  - hash_resample.hash_resample_3d (the hashed levels: the corner hash and the trilinear weights, half-pixel centres)
    on a small fixed table, at coordinates that include cell boundaries, negative cells and far-out ones;
  - resample.resample_3d as grid_utils.trilerp calls it for the dense levels (coordinates − 0.5, flipped, zero
    outside the grid), on a small fixed grid, inside, on the border and outside it;
  - math.approx_erf at 1 / (√8 · scale · grid_size), the weight each level's features get (models' downweighting);
  - coord.hexify without a random key: the 6 multisamples of each interval (one ray along +z, the basis' other case).
host/ref/grid_encoding.hpp is checked against them (tests/official/test_grid_encoding.cpp).

Official commit: 8e6d57e3aee34235faf3ef99decca0994efe66c9 (github:jonbarron/camp_zipnerf), recorded in the fixture.

    git -C /work/.mirror/jonbarron+camp_zipnerf/repo archive HEAD | tar -x -C /tmp/camp_zipnerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_grid_vectors.py \\
        --zipnerf /tmp/camp_zipnerf --zipnerf-commit 8e6d57e3aee34235faf3ef99decca0994efe66c9 \\
        --out tests/official/fixtures/zipnerf_grid.json

Inputs come from numpy.random.default_rng(20261127) and are float32 values; the official functions run under
jax_enable_x64 on float64 arrays holding them, so the fixture is the official math without float32 rounding.
"""
import importlib
import importlib.util
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from official_modules import official_arguments, zipnerf_module  # noqa: E402


def load(zipnerf, name):
    """One module of camp_zipnerf/internal by file (hash_resample, resample and math import jax and numpy only)."""
    path = os.path.join(zipnerf, "camp_zipnerf", "internal", name + ".py")
    spec = importlib.util.spec_from_file_location("zipnerf_" + name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def level_sizes(min_size, max_size, supersample):
    # grid_utils.HashEncoding.grid_sizes, evaluated on its own numbers (the class needs flax and gin to construct).
    desired = 1 + supersample * np.log2(max_size / min_size)
    count = int(np.round(desired))
    if abs(desired - count) > 1e-4:
        raise ValueError(f"({min_size}, {max_size}, {supersample}) gives {desired} levels, which the official refuses")
    return np.round(np.geomspace(min_size, max_size, count)).astype(np.int32).tolist()


def main():
    args = official_arguments(__doc__, "zipnerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    hash_resample = load(args.zipnerf, "hash_resample")
    resample = load(args.zipnerf, "resample")
    zmath = load(args.zipnerf, "math")
    rng = np.random.default_rng(20261127)

    def f32(a):
        return np.asarray(a, np.float32).astype(np.float64)

    # The hashed level: a table of T = 64 entries with F = 2 features; coordinates in cells (x · grid size), including
    # exact cell boundaries, negative cells (the hash sees them as uint32) and large ones (the products wrap).
    table = f32(rng.uniform(-1, 1, size=(64, 2)))
    coords = np.concatenate([
        f32(rng.uniform(0, 40, size=(24, 3))),
        f32([[0.5, 0.5, 0.5], [1.0, 2.0, 3.0], [7.5, 0.5, 12.5], [-0.25, 3.0, 1.75], [-3.5, -7.25, -1.0],
             [100000.5, 3.25, 77777.75], [2047.9, 2047.9, 0.1]]),
    ])
    hashed = np.asarray(hash_resample.hash_resample_3d(jnp.asarray(table), jnp.asarray(coords)))

    # A dense level: G = 5 cells a side, F = 2, as grid_utils.trilerp calls resample_3d (values[x][y][z]).
    grid = f32(rng.uniform(-1, 1, size=(5, 5, 5, 2)))
    grid_coords = np.concatenate([
        f32(rng.uniform(0, 5, size=(24, 3))),
        f32([[0.5, 0.5, 0.5], [0.0, 2.5, 4.9], [5.0, 5.0, 5.0], [-0.7, 2.2, 3.3], [6.1, 1.0, 1.0], [2.5, 2.5, 2.5]]),
    ])
    flipped = jnp.flip(jnp.asarray(grid_coords) - 0.5, axis=-1)
    dense = np.asarray(resample.resample_3d(jnp.asarray(grid), flipped[None, None])[0, 0])

    # The downweighting: approx_erf(1 / (√8 · scale · N)) for a spread of footprints against cell sizes.
    scale_cells = f32(np.concatenate([rng.uniform(0.01, 3.0, size=12), [1e-6, 1e-3, 0.1, 1.0, 10.0, 1e3]]))
    weights = np.asarray(zmath.approx_erf(1 / (jnp.sqrt(8) * jnp.asarray(scale_cells))))

    # The deterministic multisamples (coord.hexify with rng=None): 5 rays, 4 intervals each; one ray along +z, where
    # construct_perp_basis takes its other cross product.
    coord = zipnerf_module(args.zipnerf, "coord")
    origins = f32(rng.uniform(-1, 1, size=(5, 3)))
    directions = f32(rng.uniform(-1, 1, size=(5, 3)))
    directions[4] = [0.0, 0.0, 1.0]
    radii = f32(rng.uniform(0.0005, 0.01, size=(5, 1)))
    tdist = np.sort(f32(rng.uniform(0.5, 6.0, size=(5, 5))), axis=-1)
    control, perp_mag = coord.hexify(None, origins=jnp.asarray(origins), directions=jnp.asarray(directions),
                                     radii=jnp.asarray(radii), tdist=jnp.asarray(tdist))

    out = {
        "generator": "tests/official/make_grid_vectors.py",
        "zipnerf_commit": args.zipnerf_commit,
        "jax": jax.__version__,
        "level_sizes": [{"min": a, "max": b, "supersample": s, "sizes": level_sizes(a, b, s)}
                        for a, b, s in [(16, 2048, 2.0), (16, 8192, 1.0), (16, 4096, 0.5), (16, 2048, 1.0)]],
        "hash": {"table": table.tolist(), "coords": coords.tolist(), "values": hashed.tolist()},
        "dense": {"grid": grid.tolist(), "coords": grid_coords.tolist(), "values": dense.tolist()},
        "weight": {"scale_cells": scale_cells.tolist(), "values": weights.tolist()},
        "hexify": {"origins": origins.tolist(), "directions": directions.tolist(), "radii": radii.tolist(),
                   "tdist": tdist.tolist(), "control": np.asarray(control).tolist(),
                   "perp_mag": np.asarray(perp_mag).tolist()},
    }
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
