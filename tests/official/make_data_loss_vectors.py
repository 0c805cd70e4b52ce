#!/usr/bin/env python3
"""mip-NeRF 360's data loss as test vectors from the official multinerf code
(tests/official/fixtures/multinerf_data_loss.json).

Run by hand, never by the test suite: it needs JAX and a checkout of github:google-research/multinerf (read through
sys.path, never copied). It calls train_utils.compute_data_loss itself, with the official Config's defaults but for
data_loss_type ('charb', the default, with charb_padding 0.001; and 'mse'), on one rendering of a batch of rays, and
records the loss it returns and jax.grad of it with respect to the rendered colour. The residuals span the scales the
Charbonnier term treats differently (far below the padding, about it, and far above), and the batch is weighed once
by lossmult = 1 and once by a multiscale dataset's footprint areas (1, 4, 16, 64). This pins what
kernels/loss.cl computes with CHARBONNIER_LOSS and LOSS_CHANNEL_MEAN (tests/official/test_data_loss.cpp): the term
√(residual² + padding²) and the per-channel mean (multinerf's denominator counts each channel: lossmult is broadcast
to the colour's shape).

Official commit: 5b4d4f64608ec8077222c52fdf814d40acc10bc1 (github:google-research/multinerf), recorded in the fixture.

    git -C /work/.mirror/google-research+multinerf/repo archive HEAD | tar -x -C /tmp/multinerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_data_loss_vectors.py \\
        --multinerf /tmp/multinerf --multinerf-commit 5b4d4f64608ec8077222c52fdf814d40acc10bc1 \\
        --out tests/official/fixtures/multinerf_data_loss.json

train_utils imports every sibling module (datasets, image, models and more, which import cv2, dm_pix, pycolmap);
compute_data_loss uses none of them, so those siblings are empty stand-ins (STUBS below, recorded in the fixture).
Inputs come from numpy.random.default_rng(20261202) and are float32 values; the official function runs under
jax_enable_x64 on float64 arrays holding them.
"""
import json
import os
import sys
import types

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from official_modules import multinerf_module, official_arguments  # noqa: E402

RAYS = 48
STUBS = ["datasets", "image", "models", "camera_utils", "robustnerf", "ref_utils", "utils"]


def load_train_utils(multinerf):
    multinerf_module(multinerf, "math")  # the bare `internal` package, and a sibling train_utils does use
    for name in STUBS:
        stand_in = types.ModuleType("internal." + name)
        stand_in.__getattr__ = lambda attribute: object  # type annotations at import time
        sys.modules["internal." + name] = stand_in
    return multinerf_module(multinerf, "train_utils"), multinerf_module(multinerf, "configs")


def batch_inputs(rng):
    """Targets in [0, 1] and renderings off them by residuals of every scale, as float32 values."""
    target = rng.uniform(0.0, 1.0, (RAYS, 3)).astype(np.float32)
    scales = np.array([1e-6, 1e-4, 1e-3, 3e-3, 1e-2, 0.1, 0.5], dtype=np.float64)
    magnitude = scales[rng.integers(0, len(scales), (RAYS, 3))] * rng.uniform(0.5, 2.0, (RAYS, 3))
    residual = magnitude * rng.choice([-1.0, 1.0], (RAYS, 3))
    residual[0] = 0.0  # a ray rendered exactly
    rendered = (target + residual).astype(np.float32)
    footprints = rng.choice([1.0, 4.0, 16.0, 64.0], (RAYS, 1)).astype(np.float32)
    return target, rendered, footprints


def official_case(train_utils, configs, jax, jnp, loss_type, target, rendered, lossmult):
    config = configs.Config(data_loss_type=loss_type)
    batch = types.SimpleNamespace(rgb=jnp.asarray(target, jnp.float64))
    rays = types.SimpleNamespace(lossmult=jnp.asarray(lossmult, jnp.float64))

    def loss_of(rgb):
        loss, _ = train_utils.compute_data_loss(batch, [{"rgb": rgb}], rays, None, config)
        return loss

    rgb = jnp.asarray(rendered, jnp.float64)
    return {"data_loss_type": loss_type, "charb_padding": float(config.charb_padding),
            "lossmult": np.asarray(lossmult, np.float64).ravel().tolist(),
            "loss": float(loss_of(rgb)), "d_rgb": np.asarray(jax.grad(loss_of)(rgb)).tolist()}


def main():
    args = official_arguments(__doc__, "multinerf")
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    train_utils, configs = load_train_utils(args.multinerf)
    rng = np.random.default_rng(20261202)
    target, rendered, footprints = batch_inputs(rng)
    cases = []
    for loss_type in ("charb", "mse"):
        for lossmult in (np.ones((RAYS, 1), np.float32), footprints):
            cases.append(official_case(train_utils, configs, jax, jnp, loss_type, target, rendered, lossmult))
    fixture = {
        "generator": "tests/official/make_data_loss_vectors.py",
        "multinerf_commit": args.multinerf_commit,
        "versions": {"jax": jax.__version__, "numpy": np.__version__},
        "stubs": [{"name": "multinerf internal." + name, "why": "an empty module: train_utils imports it, "
                   "compute_data_loss does not use it"} for name in STUBS],
        "target_rgb": target.tolist(), "rendered_rgb": rendered.tolist(), "cases": cases,
    }
    with open(args.out, "w") as out:
        json.dump(fixture, out)
        out.write("\n")
    print(f"wrote {len(cases)} cases of {RAYS} rays to {args.out}")


if __name__ == "__main__":
    main()
