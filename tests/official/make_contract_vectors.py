#!/usr/bin/env python3
"""mip-NeRF 360's contraction of Gaussians and its ray warps as test vectors from the official multinerf code
(tests/official/fixtures/multinerf_contract.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:google-research/multinerf (read through
sys.path, never copied). It calls the official functions themselves on fixed inputs and records what they return:
  - coord.contract on means inside the unit ball, on the unit sphere and one float32 ulp either side of it, at the
    origin, and far out (|x| of 1e3, 1e6, 1e30: |x|² of the last overflows float32);
  - coord.track_linearize(coord.contract, mean, cov) on full 3x3 covariances (random, diagonal, and near-degenerate
    rank-1 ones along and across the radial direction), and the vector-Jacobian product of that map w.r.t. the mean
    and the covariance for seeded cotangents (jax.vjp);
  - coord.construct_ray_warps(jnp.reciprocal, near, far) (configs/360.gin's raydist_fn): t_to_s on distances from
    near to far, s_to_t on s in [0, 1] and its derivative ds -> dt (jax.grad), for several (near, far), far = inf
    included; and near = 0, where the official gives NaN (our wrapper refuses it).
host/ref/contract.hpp and kernels/contract.cl are checked against them (tests/official/test_contract.cpp).

Official commit: 5b4d4f64608ec8077222c52fdf814d40acc10bc1 (github:google-research/multinerf), recorded in the fixture.

    git -C /work/.mirror/google-research+multinerf/repo archive HEAD | tar -x -C /tmp/multinerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_contract_vectors.py \\
        --multinerf /tmp/multinerf --multinerf-commit 5b4d4f64608ec8077222c52fdf814d40acc10bc1 \\
        --out tests/official/fixtures/multinerf_contract.json

Inputs come from numpy.random.default_rng(20261128) and are float32 values; the official functions run under
jax_enable_x64 on float64 arrays holding them, so the fixture is the official math without float32 rounding.
Non-finite outputs (s_to_t(1) = inf for far = inf, the NaNs of near = 0) are written as the strings "inf" and "nan"
(JSON has no such numbers).
"""
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from official_modules import multinerf_module, official_arguments  # noqa: E402


def f32(a):
    return np.asarray(a, np.float32).astype(np.float64)


def finite_or_string(a):
    """Nested lists of floats, with inf / -inf / nan as strings."""
    def one(x):
        x = float(x)
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return x
    return np.vectorize(one, otypes=[object])(np.asarray(a, np.float64)).tolist()


def unit_vectors(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def contract_means(rng):
    """Means (float32 values) with a name per group."""
    groups = []
    groups.append(("inside", f32(unit_vectors(rng, 6) * rng.uniform(0.05, 0.95, size=(6, 1)))))
    groups.append(("origin", np.zeros((1, 3))))
    # Exactly on the sphere (axis points: |x| = 1 in every precision), and float32 vectors one ulp inside and outside.
    groups.append(("on sphere", f32([[1, 0, 0], [0, -1, 0], [0, 0, 1]])))
    near = unit_vectors(rng, 4)
    inside = f32(near * (1 - 2.0**-23))
    outside = f32(near * (1 + 2.0**-22))
    groups.append(("just inside", inside[np.linalg.norm(inside, axis=-1) < 1]))
    groups.append(("just outside", outside[np.linalg.norm(outside, axis=-1) > 1]))
    groups.append(("outside", f32(unit_vectors(rng, 6) * rng.uniform(1.05, 20.0, size=(6, 1)))))
    for scale in (1e3, 1e6, 1e30):
        groups.append((f"|x| ~ {scale:g}", f32(unit_vectors(rng, 3) * scale)))
    groups.append(("far on an axis", f32([[1e6, 0, 0], [0, 0, -1e30]])))
    return groups


def covariance_for(rng, mean, kind):
    """A float32-valued symmetric covariance at `mean`, scaled with |mean| as a frustum's would be."""
    r = max(1.0, float(np.linalg.norm(mean)))
    scale = (0.05 * r) ** 2 if r < 1e15 else 1e34  # float32 holds variances up to 3.4e38
    if kind == "random":
        a = rng.normal(size=(3, 3))
        cov = a @ a.T * scale / 3
    elif kind == "diagonal":
        cov = np.diag(rng.uniform(0.1, 1.0, size=3)) * scale
    elif kind == "rank1 radial":
        u = mean / r if np.linalg.norm(mean) > 0 else np.array([1.0, 0.0, 0.0])
        cov = np.outer(u, u) * scale + np.eye(3) * scale * 1e-6
    else:  # rank 1 across the radial direction
        u = mean / r if np.linalg.norm(mean) > 0 else np.array([1.0, 0.0, 0.0])
        v = np.cross(u, [0.3, 0.5, 0.8])
        v /= np.linalg.norm(v)
        cov = np.outer(v, v) * scale
    cov = 0.5 * (cov + cov.T)
    return f32(cov)


def main():
    args = official_arguments(__doc__, "multinerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    coord = multinerf_module(args.multinerf, "coord")
    rng = np.random.default_rng(20261128)

    kinds = ("random", "diagonal", "rank1 radial", "rank1 across")
    names, means, covs = [], [], []
    for name, group in contract_means(rng):
        for i, mean in enumerate(group):
            kind = kinds[(len(means) + i) % len(kinds)]
            names.append(f"{name} ({kind})")
            means.append(mean)
            covs.append(covariance_for(rng, mean, kind))
    means = np.stack(means)
    covs = np.stack(covs)
    assert (means.astype(np.float32) == means).all() and (covs.astype(np.float32) == covs).all()

    contracted = np.asarray(coord.contract(jnp.asarray(means)))

    def linearized(mean, cov):
        return coord.track_linearize(coord.contract, mean, cov)

    fn_mean, fn_cov = jax.vmap(linearized)(jnp.asarray(means), jnp.asarray(covs))
    # Cotangents: any mean cotangent, a symmetric covariance cotangent (the output covariance is symmetric).
    d_fn_mean = f32(rng.normal(size=means.shape))
    g = rng.normal(size=covs.shape)
    d_fn_cov = f32(0.5 * (g + np.swapaxes(g, -1, -2)))
    _, vjp = jax.vjp(jax.vmap(linearized), jnp.asarray(means), jnp.asarray(covs))
    d_mean, d_cov = vjp((jnp.asarray(d_fn_mean), jnp.asarray(d_fn_cov)))

    warp_cases = []
    for near, far in ((0.2, 1e6), (0.2, math.inf), (1.0, math.inf), (2.0, 6.0), (0.5, 100.0)):
        near, far = float(f32(near)), float(f32(far))
        t_to_s, s_to_t = coord.construct_ray_warps(jnp.reciprocal, jnp.float64(near), jnp.float64(far))
        finite_far = far if math.isfinite(far) else 1e8
        t = f32(np.concatenate([[near], np.geomspace(near, finite_far, 12)[1:-1], [finite_far]]))
        if not math.isfinite(far):
            t = np.concatenate([t, [math.inf]])
        s = f32(np.concatenate([[0.0], np.sort(rng.uniform(0, 1, size=10)), [1 - 2.0**-24, 1.0]]))
        ds_dt = jax.vmap(jax.grad(s_to_t))(jnp.asarray(s))
        warp_cases.append({"near": near, "far": finite_or_string(far), "t": finite_or_string(t),
                           "s_of_t": finite_or_string(t_to_s(jnp.asarray(t))), "s": s.tolist(),
                           "t_of_s": finite_or_string(s_to_t(jnp.asarray(s))), "dt_ds": finite_or_string(ds_dt)})
    t_to_s0, s_to_t0 = coord.construct_ray_warps(jnp.reciprocal, jnp.float64(0.0), jnp.float64(f32(6.0)))
    near_zero = {"near": 0.0, "far": float(f32(6.0)), "t": [1.0, 3.0], "s": [0.25, 0.75],
                 "s_of_t": finite_or_string(t_to_s0(jnp.asarray([1.0, 3.0]))),
                 "t_of_s": finite_or_string(s_to_t0(jnp.asarray([0.25, 0.75])))}

    out = {
        "generator": "tests/official/make_contract_vectors.py",
        "multinerf_commit": args.multinerf_commit,
        "jax": jax.__version__,
        "gaussians": {
            "names": names, "means": means.tolist(), "covs": covs.tolist(), "contract": contracted.tolist(),
            "fn_means": np.asarray(fn_mean).tolist(), "fn_covs": np.asarray(fn_cov).tolist(),
            "d_fn_means": d_fn_mean.tolist(), "d_fn_covs": d_fn_cov.tolist(),
            "d_means": np.asarray(d_mean).tolist(), "d_covs": np.asarray(d_cov).tolist(),
        },
        "ray_warps": warp_cases,
        "ray_warps_near_zero": near_zero,
    }
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
