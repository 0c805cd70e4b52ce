#!/usr/bin/env python3
"""Zip-NeRF's ray distance of unbounded scenes as test vectors from its official code
(tests/official/fixtures/zipnerf_ray_distance.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:jonbarron/camp_zipnerf (read through
sys.path, never copied). On 360-degree scenes (configs/zipnerf/360.gin) the official model maps proposal sampling's
normalised distances s to metric distances t by coord.construct_ray_warps with raydist_fn = (math.power_ladder,
math.inv_power_ladder, {'p': -1.5, 'premult': 2}) between near 0 and far 1e6 (models.py Model.__call__: each function
given the keyword arguments by functools.partial, as here). It records s_to_t on fixed s for several (near, far):
the official's own (0, 1e6), a positive near, short and long ranges; s from 0 through the last float32 values below 1
(where inv_power_ladder's clip at minus_eps(5/3) holds the last edge at t = 5.99e4) and random s.
kernels/sample_intervals.cl (RAY_DISTANCE = 1) and host/ref/sample_intervals.hpp are checked against them
(tests/official/test_sample_intervals.cpp).

Official commit: 8e6d57e3aee34235faf3ef99decca0994efe66c9 (github:jonbarron/camp_zipnerf), recorded in the fixture.

    git -C /work/.mirror/jonbarron+camp_zipnerf/repo archive HEAD | tar -x -C /tmp/camp_zipnerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_ray_distance_vectors.py \\
        --zipnerf /tmp/camp_zipnerf --zipnerf-commit 8e6d57e3aee34235faf3ef99decca0994efe66c9 \\
        --out tests/official/fixtures/zipnerf_ray_distance.json

Inputs come from numpy.random.default_rng(20261201) and are float32 values; the official functions run under
jax_enable_x64 on float64 arrays holding them, so the fixture is the official math without float32 rounding.
"""
import functools
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from official_modules import official_arguments, zipnerf_module  # noqa: E402

# camp_zipnerf configs/zipnerf/360.gin: Model.raydist_fn's keyword arguments.
POWER_LADDER_KWARGS = {"p": -1.5, "premult": 2}


def s_values(rng):
    one = np.float32(1.0)
    below_one = [np.nextafter(one, np.float32(0.0))]
    for _ in range(3):
        below_one.append(np.nextafter(below_one[-1], np.float32(0.0)))
    fixed = [0.0, 1e-30, 1e-7, 1e-3, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 0.999, 0.9999, 0.99999, 0.999999,
             0.9999999] + [float(b) for b in below_one] + [1.0]
    drawn = rng.uniform(0.0, 1.0, 40).tolist()
    return np.sort(np.asarray(fixed + drawn, np.float32)).astype(np.float64)


def main():
    args = official_arguments(__doc__, "zipnerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    coord = zipnerf_module(args.zipnerf, "coord")
    zmath = zipnerf_module(args.zipnerf, "math")
    rng = np.random.default_rng(20261201)
    s = s_values(rng)
    bounds = [(0.0, 1e6), (0.2, 1e6), (0.0, 10.0), (1e-3, 3.0), (0.5, 60.0)]
    cases = []
    for near, far in bounds:
        near64, far64 = [np.float64(np.float32(x)) for x in (near, far)]
        _, s_to_t = coord.construct_ray_warps(
            functools.partial(zmath.power_ladder, **POWER_LADDER_KWARGS), jnp.asarray(near64), jnp.asarray(far64),
            fn_inv=functools.partial(zmath.inv_power_ladder, **POWER_LADDER_KWARGS))
        t = np.asarray(s_to_t(jnp.asarray(s)))
        if not np.all(np.isfinite(t)) or not np.all(np.diff(t) >= 0):
            raise RuntimeError(f"official t not finite or not sorted for near {near}, far {far}")
        cases.append({"near": float(near64), "far": float(far64), "t": t.tolist()})
    out = {
        "zipnerf_commit": args.zipnerf_commit,
        "generator": "tests/official/make_ray_distance_vectors.py",
        "raydist_fn": {"fn": "math.power_ladder", "fn_inv": "math.inv_power_ladder", "kwargs": POWER_LADDER_KWARGS},
        "versions": {"jax": jax.__version__, "numpy": np.__version__},
        "s": s.tolist(),
        "cases": cases,
    }
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(out, f)


if __name__ == "__main__":
    main()
