#!/usr/bin/env python3
"""Zip-NeRF's proposal losses as test vectors from its official code (tests/official/fixtures/zipnerf_proposal.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:jonbarron/camp_zipnerf (read through a bare
package object, never copied). It calls the official functions themselves on fixed inputs and records what they return:
  - stepfun.blur_and_resample_weights(tq, t, w, r) for several histograms and half-widths: wide and narrow blurs,
    a zero-width interval, queries reaching past the histogram, an empty histogram (all w = 0);
  - loss_utils.spline_interlevel_loss on a batch of rays with two proposal rounds (mults 0.01, blurs (0.03, 0.003),
    the official Zip-NeRF config), with proposal weights of 0 where the NeRF has mass, and jax.grad of the sum of the
    two rounds' losses w.r.t. each round's weights;
  - stepfun.lossfun_distortion per ray, loss_utils.distortion_loss (mult 0.01) and jax.grad of the mean of
    lossfun_distortion w.r.t. the weights and the edges.
host/ref/interlevel.hpp, host/ref/distortion.hpp and their kernels are checked against them
(tests/official/test_proposal_losses.cpp).

Official commit: 8e6d57e3aee34235faf3ef99decca0994efe66c9 (github:jonbarron/camp_zipnerf), recorded in the fixture.

    git -C /work/.mirror/jonbarron+camp_zipnerf/repo archive HEAD | tar -x -C /tmp/camp_zipnerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_proposal_vectors.py \\
        --zipnerf /tmp/camp_zipnerf --zipnerf-commit 8e6d57e3aee34235faf3ef99decca0994efe66c9 \\
        --out tests/official/fixtures/zipnerf_proposal.json

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


def sorted_edges(rng, rays, edges, lo=0.0, hi=1.0):
    """Sorted edges per ray from lo to hi: the two ends and edges − 2 uniform draws between."""
    inner = rng.uniform(lo, hi, size=(rays, edges - 2))
    ends = np.broadcast_to(np.array([lo, hi]), (rays, 2))
    return f32(np.sort(np.concatenate([ends, inner], axis=-1), axis=-1))


def normalised(rng, rays, n, total=1.0):
    w = rng.uniform(0.0, 1.0, size=(rays, n)) ** 2
    return f32(total * w / w.sum(axis=-1, keepdims=True))


def main():
    args = official_arguments(__doc__, "zipnerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    stepfun = zipnerf_module(args.zipnerf, "stepfun")
    loss_utils = zipnerf_module(args.zipnerf, "loss_utils")
    rng = np.random.default_rng(20261128)

    # blur_and_resample_weights: each case one batch of rays sharing a half-width.
    resample_cases = []

    def resample_case(name, t, w, tq, r):
        wq = stepfun.blur_and_resample_weights(jnp.asarray(tq), jnp.asarray(t), jnp.asarray(w), r)
        resample_cases.append({"name": name, "t": t.tolist(), "w": w.tolist(), "tq": tq.tolist(), "halfwidth": r,
                               "wq": np.asarray(wq).tolist()})

    t = sorted_edges(rng, 3, 9)
    w = normalised(rng, 3, 8)
    tq = sorted_edges(rng, 3, 7)
    for r in (0.03, 0.003, 0.5):  # the official rounds' blurs, and one wider than the whole histogram
        resample_case(f"random r={r}", t, w, tq, float(f32(r)))
    # A zero-width interval carrying weight (dropped by weight_to_pdf), queries reaching past both ends, one interval
    # holding all the weight.
    t_odd = f32([[0.1, 0.2, 0.2, 0.35, 0.6, 0.9], [0.0, 0.25, 0.5, 0.5, 0.75, 1.0]])
    w_odd = f32([[0.1, 0.3, 0.2, 0.4, 0.0], [0.0, 0.0, 0.0, 1.0, 0.0]])
    tq_odd = f32([[-0.2, 0.05, 0.3, 0.31, 0.7, 1.3], [0.0, 0.5, 0.74, 0.76, 0.9, 1.0]])
    resample_case("zero width and outside", t_odd, w_odd, tq_odd, float(f32(0.03)))
    resample_case("empty histogram", t[:1], np.zeros_like(w[:1]), tq[:1], float(f32(0.03)))

    # spline_interlevel_loss: 4 rays, the NeRF with 16 intervals, rounds of 12 and 10; some proposal weights 0.
    rays = 4
    c = sorted_edges(rng, rays, 17)
    w_nerf = normalised(rng, rays, 16)
    cp = [sorted_edges(rng, rays, 13), sorted_edges(rng, rays, 11)]
    wp = [normalised(rng, rays, 12), normalised(rng, rays, 10)]
    wp[0][0, 3:6] = 0.0
    wp[1][2, :4] = 0.0
    mults, blurs = 0.01, (float(f32(0.03)), float(f32(0.003)))

    def interlevel(wp0, wp1):
        history = [{"sdist": jnp.asarray(cp[0]), "weights": wp0}, {"sdist": jnp.asarray(cp[1]), "weights": wp1},
                   {"sdist": jnp.asarray(c), "weights": jnp.asarray(w_nerf)}]
        return loss_utils.spline_interlevel_loss(history, mults=mults, blurs=blurs)

    losses = interlevel(jnp.asarray(wp[0]), jnp.asarray(wp[1]))
    grads = jax.grad(lambda a, b: sum(interlevel(a, b)), argnums=(0, 1))(jnp.asarray(wp[0]), jnp.asarray(wp[1]))

    # Distortion: 5 rays of 12 intervals, t in [0, 1] (s-distances) and one ray of metric distances [2, 6].
    t_dist = np.concatenate([sorted_edges(rng, 4, 13), sorted_edges(rng, 1, 13, 2.0, 6.0)])
    w_dist = normalised(rng, 5, 12)
    per_ray = stepfun.lossfun_distortion(jnp.asarray(t_dist), jnp.asarray(w_dist))
    dist_loss = loss_utils.distortion_loss([{"sdist": jnp.asarray(t_dist), "weights": jnp.asarray(w_dist)}],
                                           mult=0.01)
    d_t, d_w = jax.grad(lambda a, b: jnp.mean(stepfun.lossfun_distortion(a, b)), argnums=(0, 1))(
        jnp.asarray(t_dist), jnp.asarray(w_dist))

    out = {
        "generator": "tests/official/make_proposal_vectors.py",
        "zipnerf_commit": args.zipnerf_commit,
        "jax": jax.__version__,
        "blur_and_resample_weights": resample_cases,
        "spline_interlevel": {
            "c": c.tolist(), "w": w_nerf.tolist(), "mults": mults, "blurs": list(blurs),
            "rounds": [{"cp": cp[k].tolist(), "wp": wp[k].tolist(), "loss": float(losses[k]),
                        "d_wp": np.asarray(grads[k]).tolist()} for k in range(2)],
        },
        "distortion": {"t": t_dist.tolist(), "w": w_dist.tolist(), "per_ray": np.asarray(per_ray).tolist(),
                       "mult": 0.01, "loss": float(dist_loss), "d_t_of_mean": np.asarray(d_t).tolist(),
                       "d_w_of_mean": np.asarray(d_w).tolist()},
    }
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
