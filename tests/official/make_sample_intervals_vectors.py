#!/usr/bin/env python3
"""Zip-NeRF's proposal sampler as test vectors from its official code
(tests/official/fixtures/zipnerf_sample_intervals.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:jonbarron/camp_zipnerf (read through
sys.path, never copied). It calls the official functions themselves on fixed inputs and records what they return:
  - the resampling logits of models.py Model.__call__ (where(sdist[1:] > sdist[:-1], anneal * math.safe_log(weights +
    resample_padding), -inf)), written here as that expression over the official math.safe_log, then
    stepfun.sample_intervals(rng, sdist, logits, num_samples, single_jitter, domain) for several rays (zero-width
    intervals, all-zero weights, one interval holding the weight, random ones), anneal exponents, paddings, interval
    counts M (2 included) and domains;
  - deterministic (rng None) and randomised: jax.random.uniform is replaced by our draws, xi[ray][j] =
    rng_uniform4(seed, first_ray + ray, step, j // 4, stream 6)[j % 4] (make_vectors.rng_uniform4; one per ray,
    xi[ray][0], for single_jitter), returned as the official's uniform would scale them: xi * maxval;
  - Schlick's bias, the anneal schedule: the lambda of models.py's Model.__call__ itself, taken from its source text
    and evaluated, on several (train_frac, anneal_slope).
host/ref/sample_intervals.hpp and kernels/sample_intervals.cl are checked against them
(tests/official/test_sample_intervals.cpp).

Official commit: 8e6d57e3aee34235faf3ef99decca0994efe66c9 (github:jonbarron/camp_zipnerf), recorded in the fixture.

    git -C /work/.mirror/jonbarron+camp_zipnerf/repo archive HEAD | tar -x -C /tmp/camp_zipnerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_sample_intervals_vectors.py \\
        --zipnerf /tmp/camp_zipnerf --zipnerf-commit 8e6d57e3aee34235faf3ef99decca0994efe66c9 \\
        --out tests/official/fixtures/zipnerf_sample_intervals.json

Inputs come from numpy.random.default_rng(20261129) and are float32 values; the official functions run under
jax_enable_x64 on float64 arrays holding them, so the fixture is the official math without float32 rounding (its
constants stay float32: eps = finfo(float32).eps, safe_log's clip to float32 tiny, and the numpy-scalar arithmetic on
eps in sample's u_max and linspace stop, which rounds to float32 — the test allows for that).
"""
import json
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from official_modules import official_arguments, zipnerf_module  # noqa: E402

import make_vectors  # noqa: E402  (rng_uniform4: our Philox draws)

RNG_STREAM_PROPOSAL = 6  # host/core/rng.hpp rng_stream_proposal


def official_bias(zipnerf):
    """models.py's `bias = lambda x, s: ...` (Schlick's bias), evaluated from the official source line."""
    with open(os.path.join(zipnerf, "camp_zipnerf", "internal", "models.py")) as f:
        match = re.search(r"^\s*bias = (lambda x, s: .*)$", f.read(), re.MULTILINE)
    if match is None:
        raise RuntimeError("models.py has no `bias = lambda x, s: ...` line; the official code changed")
    return eval(match.group(1))  # noqa: S307 (the official's own expression)


def rays(rng):
    """Sorted float32 edges in [0, 1] and float32 weights, [R][N+1] and [R][N], N = 8: the cases of the fixture."""
    n = 8
    s_rows, w_rows = [], []
    def add(s, w):
        s_rows.append(np.asarray(s, np.float32))
        w_rows.append(np.asarray(w, np.float32))
    uniform = np.linspace(0, 1, n + 1)
    add(uniform, rng.uniform(0, 1, n))                                   # random weights
    add(uniform, np.zeros(n))                                            # all zero: uniform
    add(uniform, np.eye(n)[3] * 2.5)                                     # one interval holds the weight
    s = np.sort(rng.uniform(0, 1, n + 1)); s[0], s[-1] = 0, 1
    s[2] = s[3]; s[5] = s[6]                                             # zero-width intervals 2 and 5
    add(s, np.where(np.arange(n) % 3 == 2, 1e4, rng.uniform(0, 1, n)))   # with large weights on them
    s = np.sort(rng.uniform(0, 1, n + 1)); s[0], s[-1] = 0, 1
    add(s, np.where(rng.uniform(0, 1, n) < 0.4, rng.uniform(0, 1, n), 0))  # sparse
    add(uniform, np.exp(-0.5 * ((np.arange(n) - 6.0) / 0.7) ** 2))      # a sharp bump near the far end
    return np.stack(s_rows), np.stack(w_rows)


def main():
    args = official_arguments(__doc__, "zipnerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    stepfun = zipnerf_module(args.zipnerf, "stepfun")
    zmath = zipnerf_module(args.zipnerf, "math")
    bias = official_bias(args.zipnerf)
    rng = np.random.default_rng(20261129)
    s_all, w_all = rays(rng)
    n_rays = s_all.shape[0]
    key = {"seed": 20261129, "step": 17, "first_ray": 5}

    given = {}  # the uniforms the stub returns: [R][d] for the current call
    original_uniform = jax.random.uniform

    def given_uniform(rng_key, shape=(), dtype=None, minval=0.0, maxval=1.0):
        xi = given["xi"]
        if tuple(shape) != xi.shape:
            raise RuntimeError(f"official draw of shape {tuple(shape)}, given {xi.shape}")
        return jnp.maximum(minval, jnp.asarray(xi, jnp.float64) * (maxval - minval) + minval)

    cases = []
    settings = [  # (mode, anneal, padding, M, domain)
        ("deterministic", 1.0, 0.0, 2, (0.0, 1.0)),
        ("deterministic", 1.0, 0.0, 5, (0.0, 1.0)),
        ("deterministic", 0.37, 0.01, 16, (0.0, 1.0)),
        ("deterministic", 0.0, 0.0, 7, (0.0, 1.0)),
        ("deterministic", 1.0, 0.01, 9, (0.125, 0.875)),  # domains exact in float32, as the model's float32 bounds are
        ("per_sample", 1.0, 0.0, 2, (0.0, 1.0)),
        ("per_sample", 0.5, 0.01, 13, (0.0, 1.0)),
        ("per_sample", 1.0, 0.0, 32, (0.0625, 1.0)),
        ("single_jitter", 1.0, 0.0, 6, (0.0, 1.0)),
        ("single_jitter", 0.8, 0.005, 24, (0.0, 0.9375)),
    ]
    jax.random.uniform = given_uniform
    try:
        for mode, anneal, padding, m, domain in settings:
            s = jnp.asarray(s_all.astype(np.float64))
            w = jnp.asarray(w_all.astype(np.float64))
            # models.py Model.__call__'s resampling logits, over the official safe_log.
            logits = jnp.where(s[:, 1:] > s[:, :-1], anneal * zmath.safe_log(w + padding), -jnp.inf)
            if mode == "deterministic":
                rng_key, xi = None, None
            else:
                d = 1 if mode == "single_jitter" else m
                xi = make_vectors.our_draws(key, n_rays, d, RNG_STREAM_PROPOSAL)
                given["xi"] = xi
                rng_key = jax.random.PRNGKey(0)
            edges = stepfun.sample_intervals(rng_key, s, logits, m, single_jitter=(mode == "single_jitter"),
                                             domain=domain)
            edges = np.asarray(edges)
            if not np.all(np.isfinite(edges)):
                raise RuntimeError(f"non-finite official edges for {mode}, M = {m}")
            cases.append({"mode": mode, "anneal": anneal, "resample_padding": padding, "new_intervals": m,
                          "domain": list(domain), "xi": None if xi is None else xi.tolist(),
                          "s_new": edges.tolist()})
    finally:
        jax.random.uniform = original_uniform

    bias_rows = [{"train_frac": x, "anneal_slope": sl, "anneal": float(bias(np.float64(x), np.float64(sl)))}
                 for x in (0.0, 0.01, 1.0 / 11.0, 0.25, 0.5, 0.9, 1.0) for sl in (1.0, 2.0, 10.0, 100.0)]
    out = {
        "zipnerf_commit": args.zipnerf_commit,
        "generator": "tests/official/make_sample_intervals_vectors.py",
        "rng_key": key,
        "rng_stream": RNG_STREAM_PROPOSAL,
        "n_rays": int(n_rays),
        "n_intervals": int(w_all.shape[1]),
        "s_edges": s_all.astype(np.float64).tolist(),
        "weights": w_all.astype(np.float64).tolist(),
        "cases": cases,
        "bias": bias_rows,
    }
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(out, f)


if __name__ == "__main__":
    main()
