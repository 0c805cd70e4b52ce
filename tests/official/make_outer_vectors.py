#!/usr/bin/env python3
"""mip-NeRF 360's proposal supervision as test vectors from the official multinerf code
(tests/official/fixtures/multinerf_proposal.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:google-research/multinerf (read through
sys.path, never copied). It calls the official functions themselves on fixed inputs and records what they return:
  - stepfun.inner_outer and stepfun.lossfun_outer per interval for single rays chosen for their edges: proposal edges
    coinciding with NeRF edges, NeRF edges past either end of the proposal's, one proposal interval holding every NeRF
    interval, proposal weights of 0 under NeRF mass, an empty NeRF histogram;
  - train_utils.interlevel_loss's sum over two proposal rounds (64 and 32 intervals against a NeRF of 24, mult 1, the
    official 360 default) on a batch of random sorted histograms, and jax.grad of it w.r.t. each round's weights
    (written here as the official writes it: its mean of lossfun_outer, the NeRF's (c, w) under stop_gradient);
  - stepfun.max_dilate_weights (dilation, domain (0, 1), renormalize) on random histograms, the dilation of the
    official Model.__call__ (dilation_bias + dilation_multiplier / the samples so far).
host/ref/interlevel_outer.hpp and its kernel are checked against them (tests/official/test_proposal_losses.cpp).

Official commit: 5b4d4f64608ec8077222c52fdf814d40acc10bc1 (github:google-research/multinerf), recorded in the fixture.

    git -C /work/.mirror/google-research+multinerf/repo archive HEAD | tar -x -C /tmp/multinerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_outer_vectors.py \\
        --multinerf /tmp/multinerf --multinerf-commit 5b4d4f64608ec8077222c52fdf814d40acc10bc1 \\
        --out tests/official/fixtures/multinerf_proposal.json

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


def sorted_edges(rng, count, lo=0.0, hi=1.0):
    inner = np.sort(rng.uniform(lo, hi, size=count - 2))
    return f32(np.concatenate([[lo], inner, [hi]]))


def histogram(rng, count, total=1.0):
    w = rng.uniform(0, 1, size=count) * rng.uniform(0, 1, size=count)
    return f32(w * total / w.sum())


def single_rays(rng):
    """(name, c, w, cp, wp) for one ray each."""
    cases = []
    c = sorted_edges(rng, 9)
    cp = f32(np.concatenate([c[::2], [0.05, 0.55]]))
    cases.append(("proposal edges on NeRF edges", c, histogram(rng, 8), np.sort(cp), histogram(rng, len(cp) - 1)))
    c = sorted_edges(rng, 7, -0.2, 1.3)
    cases.append(("NeRF past both ends", c, histogram(rng, 6), sorted_edges(rng, 6, 0.1, 0.9), histogram(rng, 5)))
    c = sorted_edges(rng, 8, 0.4, 0.6)
    cases.append(("one proposal interval holds all", c, histogram(rng, 7), f32([0.0, 0.3, 0.7, 1.0]),
                  f32([0.1, 0.2, 0.05])))
    c = sorted_edges(rng, 10)
    wp = histogram(rng, 7)
    wp[2:5] = 0
    cases.append(("proposal zeros under NeRF mass", c, histogram(rng, 9), sorted_edges(rng, 8), wp))
    cases.append(("empty NeRF histogram", sorted_edges(rng, 6), np.zeros(5), sorted_edges(rng, 5), histogram(rng, 4)))
    return cases


def main():
    args = official_arguments(__doc__, "multinerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    stepfun = multinerf_module(args.multinerf, "stepfun")
    rng = np.random.default_rng(20261202)

    singles = []
    for name, c, w, cp, wp in single_rays(rng):
        inner, outer = stepfun.inner_outer(jnp.asarray(c), jnp.asarray(cp), jnp.asarray(wp))
        loss = stepfun.lossfun_outer(jnp.asarray(c), jnp.asarray(w), jnp.asarray(cp), jnp.asarray(wp))
        singles.append({"name": name, "c": c.tolist(), "w": w.tolist(), "cp": cp.tolist(), "wp": wp.tolist(),
                        "outer": np.asarray(outer).tolist(), "loss": np.asarray(loss).tolist()})

    n_rays, n, sizes, mult = 6, 24, (64, 32), 1.0
    c = np.stack([sorted_edges(rng, n + 1) for _ in range(n_rays)])
    w = np.stack([histogram(rng, n, rng.uniform(0.5, 1.0)) for _ in range(n_rays)])
    rounds = []
    for m in sizes:
        cp = np.stack([sorted_edges(rng, m + 1) for _ in range(n_rays)])
        wp = np.stack([histogram(rng, m, rng.uniform(0.3, 1.0)) for _ in range(n_rays)])
        wp[0, m // 3: m // 2] = 0  # a gap under NeRF mass: the constant gradient at bound 0
        rounds.append((cp, wp))

    def interlevel(wps):
        # train_utils.interlevel_loss with the NeRF's histogram held (its stop_gradient).
        cc, ww = jax.lax.stop_gradient(jnp.asarray(c)), jax.lax.stop_gradient(jnp.asarray(w))
        total = 0.0
        for (cp, _), wp in zip(rounds, wps):
            total += jnp.mean(stepfun.lossfun_outer(cc, ww, jnp.asarray(cp), wp))
        return mult * total

    wps = [jnp.asarray(wp) for _, wp in rounds]
    loss, grads = jax.value_and_grad(interlevel)(wps)
    per_round = [float(mult * jnp.mean(stepfun.lossfun_outer(jnp.asarray(c), jnp.asarray(w), jnp.asarray(cp),
                                                              jnp.asarray(wp)))) for cp, wp in rounds]

    dilations = []
    for count, dilation in ((64, 0.0025 + 0.5 / 64), (32, 0.0025 + 0.5 / (64 * 64)), (8, 0.2)):
        t = np.stack([sorted_edges(rng, count + 1) for _ in range(3)])
        wd = np.stack([histogram(rng, count) for _ in range(3)])
        td, wdil = stepfun.max_dilate_weights(jnp.asarray(t), jnp.asarray(wd), dilation, domain=(0.0, 1.0),
                                              renormalize=True)
        dilations.append({"t": t.tolist(), "w": wd.tolist(), "dilation": dilation,
                          "t_dilate": np.asarray(td).tolist(), "w_dilate": np.asarray(wdil).tolist()})

    out = {
        "generator": "tests/official/make_outer_vectors.py",
        "multinerf_commit": args.multinerf_commit,
        "jax": jax.__version__,
        "lossfun_outer": singles,
        "interlevel_loss": {"c": c.tolist(), "w": w.tolist(), "mult": mult, "loss": float(loss),
                            "round_losses": per_round,
                            "rounds": [{"cp": cp.tolist(), "wp": wp.tolist(), "d_wp": np.asarray(g).tolist()}
                                       for (cp, wp), g in zip(rounds, grads)]},
        "max_dilate_weights": dilations,
    }
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
