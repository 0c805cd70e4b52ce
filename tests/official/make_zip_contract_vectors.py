#!/usr/bin/env python3
"""Zip-NeRF's contraction of its multisamples as test vectors from its official code
(tests/official/fixtures/zipnerf_contract.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:jonbarron/camp_zipnerf (read through
sys.path, never copied). On unbounded scenes the official model (models.py predict_density, warp_fn = coord.contract)
moves each multisample through mip-NeRF 360's contraction and multiplies its footprint by the cube root of the
contraction's Jacobian determinant there, coord.contract3_isoscale (the fast form of coord.track_isotropic). It
records, on fixed points:
  - coord.contract(x) and coord.contract3_isoscale(x): inside the unit ball, on the unit sphere and one float32 ulp
    either side of it, at the origin, at |x| of 1.5, 10, 1e3, 1e6 and 1e15, and random points at log-uniform radii;
  - coord.track_isotropic(coord.contract, x, scale): the general form, whose scale equals scale ·
    contract3_isoscale(x) except where the determinant falls below float32's tiny (|x| ≳ 1e13), which the general
    form clamps there (its guard of the gradient at 0) and the fast form the model calls does not.
kernels/zip_features.cl (ZIP_CONTRACT) and host/ref/zip_features.hpp are checked against them
(tests/official/test_grid_encoding.cpp).

Official commit: 8e6d57e3aee34235faf3ef99decca0994efe66c9 (github:jonbarron/camp_zipnerf), recorded in the fixture.

    git -C /work/.mirror/jonbarron+camp_zipnerf/repo archive HEAD | tar -x -C /tmp/camp_zipnerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_zip_contract_vectors.py \\
        --zipnerf /tmp/camp_zipnerf --zipnerf-commit 8e6d57e3aee34235faf3ef99decca0994efe66c9 \\
        --out tests/official/fixtures/zipnerf_contract.json

Inputs come from numpy.random.default_rng(20261128) and are float32 values; the official functions run under
jax_enable_x64 on float64 arrays holding them, so the fixture is the official math without float32 rounding.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from official_modules import official_arguments, zipnerf_module  # noqa: E402


def f32(a):
    return np.asarray(a, np.float32).astype(np.float64)


def main():
    args = official_arguments(__doc__, "zipnerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    coord = zipnerf_module(args.zipnerf, "coord")
    rng = np.random.default_rng(20261128)

    unit = np.float32(1.0)
    below, above = float(np.nextafter(unit, np.float32(0))), float(np.nextafter(unit, np.float32(2)))
    fixed = [[0.0, 0.0, 0.0], [0.25, -0.5, 0.125], [1.0, 0.0, 0.0], [0.0, below, 0.0], [0.0, 0.0, above],
             [0.6, 0.8, 0.0], [1.5, 0.0, 0.0], [-6.0, 8.0, 0.0], [1e3, -2e3, 5e2], [0.0, 1e6, 0.0],
             [-1e15, 3e14, 2e15]]
    directions = rng.normal(size=(24, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = 10.0 ** rng.uniform(-1, 6, size=(24, 1))
    points = f32(np.concatenate([f32(fixed), f32(directions * radii)]))
    scales = f32(10.0 ** rng.uniform(-4, 0, size=len(points)))

    x = jnp.asarray(points)
    contracted = np.asarray(coord.contract(x))
    isoscale = np.asarray(coord.contract3_isoscale(x))
    tracked_mean, tracked_scale = coord.track_isotropic(coord.contract, x, jnp.asarray(scales))
    fixture = {
        "generator": "tests/official/make_zip_contract_vectors.py",
        "zipnerf_commit": args.zipnerf_commit,
        "jax": jax.__version__,
        "points": points.tolist(),
        "scales": scales.tolist(),
        "contract": contracted.tolist(),
        "contract3_isoscale": isoscale.tolist(),
        "track_isotropic_mean": np.asarray(tracked_mean).tolist(),
        "track_isotropic_scale": np.asarray(tracked_scale).tolist(),
    }
    with open(args.out, "w") as out:
        json.dump(fixture, out, indent=1)
        out.write("\n")
    print(f"wrote {args.out}: {len(points)} points")


if __name__ == "__main__":
    main()
