#!/usr/bin/env python3
"""mip-NeRF 360's encoding of contracted frustums as test vectors from the official multinerf code
(tests/official/fixtures/multinerf_contracted_ipe.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:google-research/multinerf (read through
sys.path, never copied). It calls the official functions themselves on fixed inputs and records what they return:
  - geopoly.generate_basis('icosahedron', 2), the 21 directions MLP.pos_basis_t holds (its transpose);
  - for rays of several kinds (origins inside and outside the unit ball, an axis-aligned direction, a wide cone far
    out, a tiny cone with short intervals), intervals spaced by coord.construct_ray_warps(jnp.reciprocal, 0.2, 1e6)
    (configs/360.gin), their t rounded to float32: render.cast_rays(..., 'cone', diag=False), then
    coord.track_linearize(coord.contract, ...), coord.lift_and_diagonalize onto the basis and
    coord.integrated_pos_enc(0, 12): the lifted means and variances of every interval, and the 504 features
    MLP.predict_density feeds its first layer for the first FEATURE_ROWS intervals of each ray (the encoding of a
    lifted pair is elementwise; the rows kept test its order and arithmetic, and keep the fixture small).
host/ref/contracted_ipe.hpp and kernels/contracted_ipe.cl are checked against them
(tests/official/test_contracted_ipe.cpp).

Official commit: 5b4d4f64608ec8077222c52fdf814d40acc10bc1 (github:google-research/multinerf), recorded in the fixture.

    git -C /work/.mirror/google-research+multinerf/repo archive HEAD | tar -x -C /tmp/multinerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_contracted_ipe_vectors.py \\
        --multinerf /tmp/multinerf --multinerf-commit 5b4d4f64608ec8077222c52fdf814d40acc10bc1 \\
        --out tests/official/fixtures/multinerf_contracted_ipe.json

Inputs come from numpy.random.default_rng(20261202) and are float32 values; the official functions run under
jax_enable_x64 on float64 arrays holding them, so the fixture is the official math without float32 rounding.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from official_modules import multinerf_module, official_arguments  # noqa: E402


def f32(a):
    return np.asarray(a, np.float32).astype(np.float64)


NEAR, FAR = 0.2, 1e6  # configs/360.gin
MIN_DEG, MAX_DEG = 0, 12  # models.MLP defaults
FEATURE_ROWS = 3


def ray_cases(rng):
    """(name, origin, direction, radius, s edges) per ray; directions are not unit, as the official's rays are not."""
    n = 24
    uniform = np.linspace(0.0, 1.0, n + 1)
    random_s = np.concatenate([[0.0], np.sort(rng.uniform(0, 1, size=n - 1)), [1.0]])
    return [
        ("origin inside the ball", [0.3, -0.2, 0.4], [0.7, 0.5, -1.1], 0.0012, uniform),
        ("origin outside, towards the centre", [1.5, 0.8, -2.0], [-0.6, -0.3, 0.8], 0.004, random_s),
        ("axis-aligned (no off-diagonal)", [0.0, 0.0, 3.0], [0.0, 0.0, -1.0], 0.002, uniform),
        ("wide cone far out", [0.1, 0.2, -0.3], [0.2, -0.9, 0.4], 0.5, np.linspace(0.9, 1.0, n + 1)),
        ("tiny cone, short intervals", [-0.5, 0.4, 0.1], [0.3, 0.3, 0.9], 1e-6,
         np.linspace(0.0, 0.02, n + 1)),
        ("intervals around the unit sphere", [0.0, 0.1, 0.0], [1.0, 0.05, -0.02], 0.003,
         np.linspace(0.76, 0.85, n + 1)),
    ]


def main():
    args = official_arguments(__doc__, "multinerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    coord = multinerf_module(args.multinerf, "coord")
    render = multinerf_module(args.multinerf, "render")
    geopoly = multinerf_module(args.multinerf, "geopoly")
    rng = np.random.default_rng(20261202)

    basis = np.asarray(geopoly.generate_basis("icosahedron", 2))  # [21, 3]
    _, s_to_t = coord.construct_ray_warps(jnp.reciprocal, jnp.float64(f32(NEAR)), jnp.float64(f32(FAR)))

    def encode(mean, cov):
        mean, cov = coord.track_linearize(coord.contract, mean, cov)
        lifted_mean, lifted_var = coord.lift_and_diagonalize(mean, cov, jnp.asarray(basis.T))
        return lifted_mean, lifted_var, coord.integrated_pos_enc(lifted_mean, lifted_var, MIN_DEG, MAX_DEG)

    rays = []
    for name, origin, direction, radius, s in ray_cases(rng):
        origin, direction, radius = f32(origin), f32(direction), float(f32(radius))
        t = f32(np.asarray(s_to_t(jnp.asarray(f32(s)))))
        means, covs = render.cast_rays(jnp.asarray(t), jnp.asarray(origin), jnp.asarray(direction),
                                       jnp.float64(radius), "cone", diag=False)
        lifted_mean, lifted_var, features = jax.vmap(encode)(means, covs)
        rays.append({"name": name, "origin": origin.tolist(), "direction": direction.tolist(), "radius": radius,
                     "t_edges": t.tolist(), "lifted_means": np.asarray(lifted_mean).tolist(),
                     "lifted_vars": np.asarray(lifted_var).tolist(), "features": np.asarray(features)[:FEATURE_ROWS].tolist()})

    out = {
        "generator": "tests/official/make_contracted_ipe_vectors.py",
        "multinerf_commit": args.multinerf_commit,
        "jax": jax.__version__,
        "near": float(f32(NEAR)), "far": float(f32(FAR)), "min_deg": MIN_DEG, "max_deg": MAX_DEG,
        "basis": basis.tolist(),
        "rays": rays,
    }
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
