#!/usr/bin/env python3
"""Test vectors from the official google/mipnerf code itself, for tests/official (run by hand; needs JAX).

Our kernels are otherwise checked against host/ref, a reference that mirrors them, so a misreading of the official
code shared by both would pass every test. This script runs the official functions on fixed inputs and writes what
they return as small JSON fixtures; tests/official/*.cpp feed the same inputs to our kernels, loaders, metrics and
schedule and compare. The official checkout is only read (sys.path), never copied or patched on disk; a few
import-time stand-ins that modern jax/flax need are installed in this process's memory only (STUBS below).

Official commit: 84c969e0a623edd183b75693aed72a7e7c22902d (github:google/mipnerf; recorded in every fixture).

Command used for the committed fixtures (the checkout is a `git archive` of that commit, hence --official-commit):
  python3 -m venv ~/.cache/mipnerf-cl/vs-official-venv     # once, as bench/studies/vs_official.py does, then:
  ~/.cache/mipnerf-cl/vs-official-venv/bin/pip install 'jax[cpu]' flax optax gin-config numpy pillow
  ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_vectors.py --official /tmp/official \\
      --official-commit 84c969e0a623edd183b75693aed72a7e7c22902d --out tests/official/fixtures

--only NAME,NAME writes just those fixtures (the others keep their bytes).

Inputs: every input comes from numpy.random.default_rng(SEED + k) with a fixed k per fixture (see each make_*), and is
rounded to float32 first, so our float32 kernels and the official functions receive exactly the same numbers.

Precision: the official jax functions (mip.py, math.py) run with jax_enable_x64 on float64 arrays holding those float32
inputs, so a fixture is the official math without float32 rounding and each test's bound is our float32 error alone.
IPE is also written as the official code computes it in float32 (`official_float32`), where safe_sin's reduction
modulo a float32 100π shifts the phase by up to |y|/(100π)·ulp(100π). The dataset code (datasets.py) is numpy that
casts to float32 itself; it runs exactly as the official loaders run it.

Random draws: sample_along_rays and sorted_piecewise_constant_pdf draw with jax.random.uniform(key, shape, minval,
maxval) = max(minval, ξ·(maxval − minval) + minval), ξ in [0, 1). Our kernels draw ξ from Philox4x32-10 keyed by
(seed, step, ray, slot, stream) (host/core/rng.hpp). This script computes those ξ (philox4x32_10 below mirrors
rng.hpp) and substitutes jax.random.uniform for the call, in memory, with the formula above on our ξ; the fixture
records the key and the ξ, and the C++ test first checks that rng_uniform4 gives exactly those ξ.

Fixtures (each < 200 kB; all together well under 2 MB):
  cast_rays.json     mip.cast_rays (cone and cylinder, diag True and False)
  encode.json        mip.integrated_pos_enc (degrees 0..15, diag; float64 and float32), IPE of cast_rays' cone
                     Gaussians (our fused kernel), mip.pos_enc (view directions, degrees 0..3 + identity)
  sample.json        mip.sample_along_rays (randomized with our draws / not; lindisp on / off)
  resample.json      mip.resample_along_rays (blur-pool, padding 0.01; randomized with our draws / not)
  render.json        mip.volumetric_rendering (white_bkgd True / False)
  render_grad.json   jax.vjp of mip.volumetric_rendering w.r.t. rgb and density, for given comp_rgb and acc cotangents
  blender_rays.json  datasets.Blender on a 2-view 7x5 scene written here: pixels and _generate_rays
  ndc.json           datasets.LLFF._generate_rays (convert_to_ndc, near = 1) for two forward-facing cameras
  llff.json          datasets.LLFF on a 10-view poses_bounds.npy + 8x6 images written here (train/test split, recentred
                     poses, rescaled bounds, spiral render poses, test rays), and on a 12-view 360° set with spherify
  model.json         models.MipNerfModel.apply with fixed weights on 16 rays of multicam.json's scene, both levels, and
                     each output's first-order sensitivity to every stage's float32 error (model_vectors.py)
  noise.json         the same with density_noise 1 while randomized, given our uniform and normal draws
  adam.json          train.train_step: the losses (lossmult, coarse weight 0.1), the gradient, and the Adam update
                     with clipping off and on (model_vectors.py)
  multicam.json      datasets.Multicam on a 2-view x 3-scale scene written here (metadata.json as
                     scripts/convert_blender_data.py writes it): pixels, rays, radii, lossmult, near, far per image
  schedule.json      math.learning_rate_decay
  metrics.json       math.mse_to_psnr and math.compute_ssim(max_val=1) as train.py/eval.py call them
"""

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import types

import numpy as np

EXPECTED_COMMIT = "84c969e0a623edd183b75693aed72a7e7c22902d"
SEED = 20240607

# Import-time stand-ins the official modules need with modern jax/flax (installed in this process only).
STUBS = [
    ("flax.nn", "relu/sigmoid/softplus from flax.linen (utils.py registers them with gin; flax.nn was removed)"),
    ("flax.optim", "a module with an empty Optimizer class (utils.TrainState annotates with it; not used here)"),
    ("jax.tree_map", "= jax.tree_util.tree_map when missing (utils.shard; not used here)"),
    ("cv2", "empty module (datasets.py imports it; only its factor-2 Blender resize uses it, not used here)"),
]


def fail(message):
    sys.exit(f"make_vectors.py: {message}")


# ---- Our draws: Philox4x32-10 exactly as host/core/rng.hpp and kernels/common.cl ----

MASK32 = 0xFFFFFFFF


def philox4x32_10(counter, key):
    c, k = list(counter), list(key)
    for _ in range(10):
        p0, p1 = 0xD2511F53 * c[0], 0xCD9E8D57 * c[2]
        c = [(p1 >> 32) ^ c[1] ^ k[0], p1 & MASK32, (p0 >> 32) ^ c[3] ^ k[1], p0 & MASK32]
        k = [(k[0] + 0x9E3779B9) & MASK32, (k[1] + 0xBB67AE85) & MASK32]
    return c


def rng_uniform4(seed, item, step, slot, stream):
    bits = philox4x32_10([item, step, slot, stream], [seed & MASK32, seed >> 32])
    return [(b >> 8) * (1.0 / 16777216.0) for b in bits]  # exact in float32 and float64


def our_draws(key, n_rays, n_values, stream):
    """ξ[ray][j] = rng_uniform4(seed, first_ray + ray, step, j // 4, stream)[j % 4], as our kernels draw them."""
    out = np.zeros((n_rays, n_values))
    for ray in range(n_rays):
        for j in range(n_values):
            out[ray, j] = rng_uniform4(key["seed"], key["first_ray"] + ray, key["step"], j // 4, stream)[j % 4]
    return out


# ---- The official code ----

class Official:
    def __init__(self, checkout):
        sys.path.insert(0, os.path.abspath(checkout))
        import jax
        jax.config.update("jax_enable_x64", True)
        from flax import linen
        import flax
        sys.modules["flax.nn"] = flax.nn = types.SimpleNamespace(
            relu=linen.relu, sigmoid=linen.sigmoid, softplus=linen.softplus)
        optim = types.ModuleType("flax.optim")
        optim.Optimizer = type("Optimizer", (), {})
        sys.modules["flax.optim"] = flax.optim = optim
        if not hasattr(jax, "tree_map"):
            jax.tree_map = jax.tree_util.tree_map
        sys.modules.setdefault("cv2", types.ModuleType("cv2"))
        from internal import datasets, math, mip, utils
        self.jax, self.jnp = jax, jax.numpy
        self.datasets, self.math, self.mip, self.utils = datasets, math, mip, utils
        self.key = jax.random.PRNGKey(0)  # passed where a key is required; the draws come from given_uniform

    @contextlib.contextmanager
    def given_uniform(self, xi):
        """jax.random.uniform returns max(minval, ξ·(maxval − minval) + minval) for the given ξ (its own formula)."""
        jax, jnp = self.jax, self.jnp
        original = jax.random.uniform

        def uniform(key, shape=(), dtype=None, minval=0.0, maxval=1.0):
            if tuple(shape) != xi.shape:
                raise RuntimeError(f"official draw of shape {tuple(shape)}, given {xi.shape}")
            return jnp.maximum(minval, jnp.asarray(xi, jnp.float64) * (maxval - minval) + minval)

        jax.random.uniform = uniform
        try:
            yield
        finally:
            jax.random.uniform = original

    def config(self, **kwargs):
        return self.utils.Config(**kwargs)


def f32(a):
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def tolist(a):
    return np.asarray(a, dtype=np.float64).tolist()


def require_f32(name, *arrays):
    """Inputs must be float32 values, so our float32 kernels receive exactly the official function's inputs."""
    for a in arrays:
        a = np.asarray(a, dtype=np.float64)
        if not np.array_equal(a, f32(a)):
            fail(f"{name}: an input is not a float32 value")


def header(commit, what):
    return {"official_commit": commit, "generator": "tests/official/make_vectors.py", "what": what}


# ---- Fixtures ----

def rays_inputs(rng, n_rays, n_samples):
    origins = f32(rng.uniform(-2, 2, (n_rays, 3)))
    dirs = rng.normal(size=(n_rays, 3))
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    dirs = f32(dirs * rng.uniform(0.5, 2.0, (n_rays, 1)))
    dirs[3] = f32([1e-3, -2e-3, -1.0])  # nearly axis-aligned: 1 − d_i²/|d|² near 0 and near 1
    radii = f32(np.exp(rng.uniform(np.log(1e-4), np.log(1e-1), (n_rays, 1))))
    t = np.sort(rng.uniform(0, 1, (n_rays, n_samples + 1)), axis=-1)
    t = f32(2.0 + 4.0 * t)
    t[1] = f32(np.linspace(0, 1, n_samples + 1) ** 2)  # starts at t = 0 (NDC-like): the frustum's apex
    t[2, 3] = f32(t[2, 2] + 1e-4)                      # a thin interval
    return origins, dirs, radii, t


def make_cast_rays(off, commit):
    rng = np.random.default_rng(SEED + 1)
    origins, dirs, radii, t = rays_inputs(rng, 5, 8)
    require_f32("cast_rays", origins, dirs, radii, t)
    out = {}
    for shape in ["cone", "cylinder"]:
        for diag in [True, False]:
            means, covs = off.mip.cast_rays(t, origins, dirs, radii, shape, diag)
            out[f"{shape}_{'diag' if diag else 'full'}"] = {"means": tolist(means), "covs": tolist(covs)}
    return {**header(commit, "mip.cast_rays(t_vals, origins, directions, radii, ray_shape, diag)"),
            "inputs": {"t_vals": tolist(t), "origins": tolist(origins), "directions": tolist(dirs),
                       "radii": tolist(radii[:, 0])},
            "outputs": out}


def make_encode(off, commit):
    rng = np.random.default_rng(SEED + 2)
    jnp = off.jnp
    n = 12
    x = f32(rng.uniform(-3, 3, (n, 3)))
    # Variances from 1e-12 (degree 15 still undamped: 0.5·1e-12·4^15 ≈ 5e-4) to 1 (everything above degree 2 damped).
    cov = f32(np.exp(rng.uniform(np.log(1e-12), np.log(1.0), (n, 3))))
    cov[0] = f32([1e-12, 3e-11, 1e-10])
    require_f32("integrated_pos_enc", x, cov)
    ipe64 = off.mip.integrated_pos_enc((x, cov), 0, 16, diag=True)
    x32, cov32 = jnp.asarray(x, jnp.float32), jnp.asarray(cov, jnp.float32)
    ipe32 = off.mip.integrated_pos_enc((x32, cov32), 0, 16, diag=True)
    if ipe32.dtype != jnp.float32:
        fail(f"the float32 IPE ran in {ipe32.dtype}")

    # The fused Gaussian + IPE kernel: official IPE of official cone Gaussians (cast_rays' inputs).
    rng_rays = np.random.default_rng(SEED + 1)
    origins, dirs, radii, t = rays_inputs(rng_rays, 5, 8)
    means, covs = off.mip.cast_rays(t, origins, dirs, radii, "cone", True)
    fused = off.mip.integrated_pos_enc((means, covs), 0, 16, diag=True)

    v = rng.normal(size=(6, 3))
    v = f32(v / np.linalg.norm(v, axis=-1, keepdims=True))
    require_f32("pos_enc", v)
    pe = off.mip.pos_enc(v, 0, 4, append_identity=True)
    return {**header(commit, "mip.integrated_pos_enc((x, cov_diag), 0, 16, diag=True); the same on cast_rays' cone "
                             "Gaussians; mip.pos_enc(viewdirs, 0, 4, append_identity=True)"),
            "ipe": {"min_deg": 0, "max_deg": 16, "inputs": {"x": tolist(x), "cov_diag": tolist(cov)},
                    "official_float64": tolist(ipe64), "official_float32": tolist(ipe32)},
            "fused": {"min_deg": 0, "max_deg": 16, "cast_rays_inputs": "cast_rays.json inputs (cone, diag)",
                      "means": tolist(means), "covs": tolist(covs), "features": tolist(fused)},
            "pe": {"min_deg": 0, "max_deg": 4, "append_identity": True, "inputs": {"x": tolist(v)},
                   "features": tolist(pe)}}


def make_sample(off, commit):
    near = f32([[2.0], [0.5], [0.01], [3.0]])
    far = f32([[6.0], [100.0], [1.0], [3.5]])
    n_rays, n_samples = 4, 16
    rng = np.random.default_rng(SEED + 3)
    origins = f32(rng.uniform(-1, 1, (n_rays, 3)))
    dirs = f32(rng.normal(size=(n_rays, 3)))
    radii = f32(np.full((n_rays, 1), 1e-3))
    require_f32("sample_along_rays", near, far)
    key = {"seed": 1234567, "step": 42, "first_ray": 5, "stream": 0}
    xi = our_draws(key, n_rays, n_samples + 1, key["stream"])
    cases = []
    for randomized in [True, False]:
        for lindisp in [False, True]:
            with off.given_uniform(xi):
                t_vals, _ = off.mip.sample_along_rays(off.key, origins, dirs, radii, n_samples, near, far,
                                                      randomized, lindisp, "cone")
            cases.append({"randomized": randomized, "lindisp": lindisp, "t_vals": tolist(t_vals)})
    return {**header(commit, "mip.sample_along_rays(key, origins, directions, radii, 16, near, far, randomized, "
                             "lindisp, 'cone'), random.uniform given our draws xi"),
            "inputs": {"near": tolist(near[:, 0]), "far": tolist(far[:, 0]), "num_samples": n_samples},
            "key": key, "xi": tolist(xi), "cases": cases}


def make_resample(off, commit):
    rng = np.random.default_rng(SEED + 4)
    n_rays, n = 5, 16
    t = np.sort(rng.uniform(0, 1, (n_rays, n + 1)), axis=-1)
    t = f32(2.0 + 4.0 * (t - t[:, :1]) / (t[:, -1:] - t[:, :1]))
    w = np.zeros((n_rays, n))
    w[0] = rng.uniform(0, 0.2, n)            # spread
    w[1] = 0.0                               # empty: the padding alone (and the 1e-5 floor without padding)
    w[2, 7] = 0.97                           # one spike
    w[3] = np.exp(-0.5 * ((np.arange(n) - 10.3) / 1.5) ** 2) * 0.3
    w[4] = rng.uniform(0, 1e-8, n)           # tiny
    w = f32(w)
    origins = f32(rng.uniform(-1, 1, (n_rays, 3)))
    dirs = f32(rng.normal(size=(n_rays, 3)))
    radii = f32(np.full((n_rays, 1), 1e-3))
    require_f32("resample_along_rays", t, w)
    key = {"seed": 987654321987, "step": 7, "first_ray": 3, "stream": 1}
    xi = our_draws(key, n_rays, n + 1, key["stream"])
    cases = []
    for randomized in [True, False]:
        with off.given_uniform(xi):
            t_new, _ = off.mip.resample_along_rays(off.key, origins, dirs, radii, t, w, randomized, "cone",
                                                   stop_grad=True, resample_padding=0.01)
        cases.append({"randomized": randomized, "t_vals": tolist(t_new)})
    return {**header(commit, "mip.resample_along_rays(key, origins, directions, radii, t_vals, weights, randomized, "
                             "'cone', stop_grad=True, resample_padding=0.01), random.uniform given our draws xi"),
            "inputs": {"t_vals": tolist(t), "weights": tolist(w), "resample_padding": 0.01},
            "key": key, "xi": tolist(xi), "cases": cases}


def make_render(off, commit):
    rng = np.random.default_rng(SEED + 5)
    n_rays, n = 6, 16
    t = f32(np.sort(rng.uniform(2, 6, (n_rays, n + 1)), axis=-1))
    t[5, 6] = t[5, 5]  # a zero-length interval (with a large density below)
    dirs = f32(rng.normal(size=(n_rays, 3)) * rng.uniform(0.5, 2, (n_rays, 1)))
    density = np.exp(rng.uniform(np.log(1e-2), np.log(5.0), (n_rays, n)))
    density[1] = 0.0                                   # empty ray: acc = 0, distance = t_0
    density[2] = np.exp(rng.uniform(np.log(5), np.log(40), n))  # opaque early (optical depth to ~60)
    density[3] = np.exp(rng.uniform(np.log(1e-6), np.log(1e-4), n))  # nearly transparent
    density[4, ::3] = 0.0
    density[5, 5] = 300.0
    density = f32(density)
    rgb = f32(rng.uniform(0, 1, (n_rays, n, 3)))
    require_f32("volumetric_rendering", t, dirs, density, rgb)
    out = {}
    for white in [True, False]:
        comp_rgb, distance, acc, weights = off.mip.volumetric_rendering(rgb, density[..., None], t, dirs, white)
        out["white" if white else "black"] = {"comp_rgb": tolist(comp_rgb), "distance": tolist(distance),
                                              "acc": tolist(acc), "weights": tolist(weights)}
    return {**header(commit, "mip.volumetric_rendering(rgb, density, t_vals, dirs, white_bkgd)"),
            "inputs": {"rgb": tolist(rgb), "density": tolist(density), "t_vals": tolist(t), "dirs": tolist(dirs)},
            "outputs": out}


def make_render_grad(off, commit):
    """jax.vjp of mip.volumetric_rendering with respect to rgb and density, on render.json's inputs, for fixed
    cotangents of comp_rgb and acc (those our render backward takes; distance and weights get none)."""
    jax, jnp = off.jax, off.jnp
    render = make_render(off, commit)["inputs"]
    rgb, density = np.array(render["rgb"]), np.array(render["density"])
    t, dirs = np.array(render["t_vals"]), np.array(render["dirs"])
    rng = np.random.default_rng(SEED + 15)
    n_rays = density.shape[0]
    d_comp = f32(rng.normal(0, 1, (n_rays, 3)))
    d_acc = f32(rng.normal(0, 1, n_rays))
    require_f32("volumetric_rendering cotangents", d_comp, d_acc)
    out = {}
    for white in [True, False]:
        def comp_and_acc(rgb_, density_):
            comp_rgb, _, acc, _ = off.mip.volumetric_rendering(rgb_, density_[..., None], t, dirs, white)
            return comp_rgb, acc
        _, vjp = jax.vjp(comp_and_acc, jnp.asarray(rgb), jnp.asarray(density))
        d_rgb, d_density = vjp((jnp.asarray(d_comp), jnp.asarray(d_acc)))
        out["white" if white else "black"] = {"d_rgb": tolist(d_rgb), "d_density": tolist(d_density)}
    return {**header(commit, "jax.vjp of mip.volumetric_rendering(rgb, density, t_vals, dirs, white_bkgd) -> "
                             "(comp_rgb, acc) with respect to (rgb, density), float64, on render.json's inputs"),
            "inputs": "render.json inputs", "cotangents": {"d_comp_rgb": tolist(d_comp), "d_acc": tolist(d_acc)},
            "outputs": out}


def rotation(rng, max_angle):
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    a = rng.uniform(0, max_angle)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


def look_at(eye, target, up):
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    return np.stack([right, np.cross(back, right), back, eye], 1)  # 3x4, OpenGL axes


def make_blender(off, commit, tmp):
    rng = np.random.default_rng(SEED + 6)
    w, h, n = 7, 5, 2
    camera_angle_x = 0.6911112070083618
    frames, images = [], []
    os.makedirs(os.path.join(tmp, "train"))
    for k in range(n):
        angle = 0.7 * k + 0.3
        eye = np.array([4 * np.cos(angle), 4 * np.sin(angle), 1 + 0.5 * k])
        pose = np.concatenate([look_at(eye, np.zeros(3), np.array([0, 0, 1.0])), [[0, 0, 0, 1]]], 0)
        pose = f32(pose)  # as Blender's JSON: float32 values
        rgba = rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
        rgba[0, 0, 3], rgba[1, 2, 3] = 0, 255
        from PIL import Image
        Image.fromarray(rgba, "RGBA").save(os.path.join(tmp, "train", f"r_{k}.png"))
        frames.append({"file_path": f"./train/r_{k}", "transform_matrix": tolist(pose)})
        images.append(rgba.tolist())
    with open(os.path.join(tmp, "transforms_train.json"), "w") as f:
        json.dump({"camera_angle_x": camera_angle_x, "frames": frames}, f)

    ds = off.datasets.Blender.__new__(off.datasets.Blender)
    ds.split, ds.data_dir, ds.near, ds.far = "train", tmp, 2.0, 6.0
    ds._load_renderings(off.config(dataset_loader="blender", factor=0, white_bkgd=True, render_path=False))
    ds._generate_rays()
    r = ds.rays
    return {**header(commit, "datasets.Blender._load_renderings (white_bkgd, factor 0) and _generate_rays on the "
                             "scene given here: transforms_train.json + train/r_<k>.png"),
            "inputs": {"camera_angle_x": camera_angle_x, "width": w, "height": h, "frames": frames,
                       "rgba8": images},
            "outputs": {"focal": float(ds.focal), "pixels": tolist(ds.images), "origins": tolist(r.origins),
                        "directions": tolist(r.directions), "viewdirs": tolist(r.viewdirs),
                        "radii": tolist(r.radii[..., 0]), "near": float(ds.near), "far": float(ds.far)}}


def make_ndc(off, commit):
    rng = np.random.default_rng(SEED + 7)
    w, h, focal = 8, 6, 7.5
    poses = []
    for _ in range(2):
        pose = np.concatenate([rotation(rng, 0.25), rng.uniform(-0.3, 0.3, (3, 1))], 1)
        poses.append(f32(pose))
    ds = off.datasets.LLFF.__new__(off.datasets.LLFF)
    ds.split, ds.spherify, ds.near, ds.far = "train", False, 0.0, 1.0
    ds.w, ds.h, ds.focal = w, h, np.float64(focal)  # a float64 focal: the ray math runs in float64
    ds.camtoworlds = np.stack(poses).astype(np.float64)
    ds._generate_rays()
    r = ds.rays
    return {**header(commit, "datasets.LLFF._generate_rays (convert_to_ndc with its default near = 1, NDC radii) in "
                             "float64 for the cameras given here, near 0, far 1"),
            "inputs": {"width": w, "height": h, "focal": focal, "camtoworlds": tolist(np.stack(poses)),
                       "ndc_near_plane": 1.0},
            "outputs": {"origins": tolist(r.origins), "directions": tolist(r.directions),
                        "viewdirs": tolist(r.viewdirs), "radii": tolist(r.radii[..., 0])}}


def llff_poses_bounds(rng, n, spherical):
    """poses_bounds.npy rows: the 3x5 [down, right, backwards, position, (h, w, focal)] then near, far."""
    h, w, focal = 6, 8, 9.25
    rows = []
    for k in range(n):
        if spherical:
            angle = 2 * np.pi * k / n + rng.uniform(-0.1, 0.1)
            centre = np.array([1.0, -0.5, 0.3])
            eye = centre + np.array([4 * np.cos(angle), 4 * np.sin(angle), rng.uniform(-1, 1)])
            c2w = look_at(eye, centre + rng.uniform(-0.2, 0.2, 3), np.array([0, 0, 1.0]))
            near, far = rng.uniform(2.0, 2.5), rng.uniform(5.5, 7.0)
        else:
            c2w = np.concatenate([rotation(rng, 0.15), [[rng.uniform(-0.6, 0.6)], [rng.uniform(-0.4, 0.4)],
                                                        [rng.uniform(-0.1, 0.1)]]], 1)
            near, far = rng.uniform(3.0, 4.0), rng.uniform(15.0, 25.0)
        x, y, z, p = c2w[:, 0], c2w[:, 1], c2w[:, 2], c2w[:, 3]
        llff = np.stack([-y, x, z, p, [h, w, focal]], 1)  # the official loader reorders back to [x, y, z]
        rows.append(np.concatenate([llff.reshape(-1), [near, far]]))
    return np.array(rows), (h, w)


def run_llff(off, tmp, rows, size, spherify):
    from PIL import Image
    rng = np.random.default_rng(SEED + 9)
    h, w = size
    os.makedirs(os.path.join(tmp, "images"))
    np.save(os.path.join(tmp, "poses_bounds.npy"), rows)
    names, images = [], []
    for k in range(len(rows)):
        rgb = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        name = f"view_{k:02d}.png"
        Image.fromarray(rgb, "RGB").save(os.path.join(tmp, "images", name))
        names.append(name)
        images.append(rgb.tolist())
    config = off.config(dataset_loader="llff", factor=0, spherify=spherify, llffhold=8, render_path=False,
                        white_bkgd=False, near=0.0, far=1.0)
    out = {}
    for split in ["train", "test"]:
        ds = off.datasets.LLFF.__new__(off.datasets.LLFF)
        ds.split, ds.data_dir, ds.near, ds.far = split, tmp, config.near, config.far
        captured = {}
        # The rescaled (and spherified) bounds are a local of _load_renderings: read them where they are passed on.
        if spherify:
            original = off.datasets.LLFF._generate_spherical_poses

            def spherical(self, poses, bds, original=original):
                result = original(self, poses, bds)
                captured["bounds"] = bds.copy()  # scaled in place by the official code
                return result
            ds._generate_spherical_poses = types.MethodType(spherical, ds)
        elif split == "test":
            original = off.datasets.LLFF._generate_spiral_poses

            def spiral(self, poses, bds, original=original):
                captured["bounds"] = bds.copy()
                return original(self, poses, bds)
            ds._generate_spiral_poses = types.MethodType(spiral, ds)
        ds._load_renderings(config)
        ds._generate_rays()
        entry = {"camtoworlds": tolist(ds.camtoworlds), "images": tolist(ds.images)}
        if split == "test":
            r = ds.rays
            entry["rays"] = {"origins": tolist(r.origins), "directions": tolist(r.directions),
                             "viewdirs": tolist(r.viewdirs), "radii": tolist(r.radii[..., 0])}
            entry["render_poses"] = tolist(ds.render_poses)
        if "bounds" in captured:
            out["bounds"] = tolist(captured["bounds"])
        out[split] = entry
        out["focal"], out["height"], out["width"] = float(ds.focal), int(ds.h), int(ds.w)
    n = len(rows)
    out["test_indices"] = list(range(0, n, 8))
    out["train_indices"] = [i for i in range(n) if i % 8]
    return {"poses_bounds": tolist(rows), "image_names": names, "rgb8": images}, out


def make_llff(off, commit, tmp):
    rng = np.random.default_rng(SEED + 8)
    rows, size = llff_poses_bounds(rng, 10, spherical=False)
    inputs, forward = run_llff(off, os.path.join(tmp, "forward"), rows, size, spherify=False)
    rows360, size360 = llff_poses_bounds(rng, 12, spherical=True)
    inputs360, spherified = run_llff(off, os.path.join(tmp, "spherical"), rows360, size360, spherify=True)
    return {**header(commit, "datasets.LLFF (factor 0, llffhold 8, near 0, far 1, render_path False) on the captures "
                             "given here: poses_bounds.npy (float64) + images/view_<k>.png (RGB); forward-facing "
                             "(NDC rays) and 360-degree with spherify (world rays)"),
            "forward_facing": {"inputs": inputs, "outputs": forward},
            "spherify": {"inputs": inputs360, "outputs": spherified}}


def write_multicam_scene(tmp):
    """A tiny multiscale Blender scene as scripts/convert_blender_data.py lays it out (metadata.json + images_train/):
    2 views x 3 scales (8x12, 4x6, 2x3), each image random RGBA; near and far vary per image, so a loader must read
    them per image. Every image is at least 3 rows high: Multicam pads its row differences with the second-to-last
    one (dx[-2:-1]), which a 2-row image does not have (its radii would come out one row short).
    Returns the train split's metadata and the images (RGBA8)."""
    from PIL import Image
    rng = np.random.default_rng(SEED + 11)
    w0, h0, n_views, n_scales = 8, 12, 2, 3
    camera_angle_x = 0.6911112070083618
    focal0 = 0.5 * w0 / np.tan(0.5 * camera_angle_x)
    keys = ["file_path", "cam2world", "width", "height", "focal", "label", "near", "far", "lossmult"]
    meta = {k: [] for k in keys}
    images = []
    os.makedirs(os.path.join(tmp, "images_train"))
    for k in range(n_views):
        angle = 0.9 * k + 0.2
        eye = np.array([4 * np.cos(angle), 4 * np.sin(angle), 0.8 + 0.6 * k])
        pose = f32(np.concatenate([look_at(eye, np.zeros(3), np.array([0, 0, 1.0])), [[0, 0, 0, 1]]], 0))
        for j in range(n_scales):
            w, h = w0 >> j, h0 >> j
            rgba = rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
            rgba[0, 0, 3], rgba[-1, -1, 3] = 0, 255
            name = f"images_train/{k:03d}_d{j}.png"
            Image.fromarray(rgba, "RGBA").save(os.path.join(tmp, name))
            images.append(rgba.tolist())
            for key, value in zip(keys, [name, tolist(pose), w, h, focal0 / 2**j, j, 2.0 + 0.25 * k, 6.0 - 0.5 * j,
                                         4.0**j]):
                meta[key].append(value)
    # pix2cam exactly as convert_blender_data.py writes it: the inverse intrinsics, principal point at the centre.
    fx = fy = np.array(meta["focal"])
    cx, cy = np.array(meta["width"]) * .5, np.array(meta["height"]) * .5
    zero, one = np.zeros_like(cx), np.ones_like(cx)
    meta["pix2cam"] = np.moveaxis(np.array([[one / fx, zero, -cx / fx], [zero, -one / fy, cy / fy],
                                            [zero, zero, -one]]), -1, 0).tolist()
    with open(os.path.join(tmp, "metadata.json"), "w") as f:
        json.dump({"train": meta}, f)
    return meta, images


def load_multicam(off, tmp):
    """datasets.Multicam on the scene in `tmp`: _load_renderings (white_bkgd) and _generate_rays, as _train_init
    runs them (the per-image arrays, before its flattening)."""
    ds = off.datasets.Multicam.__new__(off.datasets.Multicam)
    ds.split, ds.data_dir = "train", tmp
    ds._load_renderings(off.config(dataset_loader="multicam", white_bkgd=True, render_path=False))
    ds._generate_rays()
    return ds


def make_multicam(off, commit, tmp):
    meta, images = write_multicam_scene(tmp)
    ds = load_multicam(off, tmp)
    r = ds.rays
    outputs = []
    for i in range(len(images)):
        outputs.append({"pixels": tolist(ds.images[i]), "origins": tolist(r.origins[i]),
                        "directions": tolist(r.directions[i]), "viewdirs": tolist(r.viewdirs[i]),
                        "radii": tolist(r.radii[i][..., 0]), "lossmult": float(r.lossmult[i][0, 0, 0]),
                        "near": float(r.near[i][0, 0, 0]), "far": float(r.far[i][0, 0, 0])})
    return {**header(commit, "datasets.Multicam._load_renderings (white_bkgd) and _generate_rays on the multiscale "
                             "scene given here: metadata.json (as scripts/convert_blender_data.py writes it) + "
                             "images_train/<view>_d<scale>.png"),
            "inputs": {"metadata": {"train": meta}, "rgba8": images},
            "outputs": outputs}


def make_schedule(off, commit):
    steps = [0, 1, 2, 100, 511, 512, 513, 1250, 2499, 2500, 2501, 100000, 249999, 250000, 500000, 999999, 1000000,
             1000001, 2000000]
    configs = [  # lr_init, lr_final, max_steps, lr_delay_steps, lr_delay_mult
        (5e-4, 5e-6, 1000000, 2500, 0.01),   # the official defaults (utils.Config)
        (5e-4, 5e-6, 1000000, 0, 1.0),       # no warm-up
        (1e-3, 1e-5, 250000, 512, 0.1),
    ]
    cases = []
    for lr_init, lr_final, max_steps, delay_steps, delay_mult in configs:
        values = [float(off.math.learning_rate_decay(s, lr_init, lr_final, max_steps, delay_steps, delay_mult))
                  for s in steps]
        cases.append({"lr_init": lr_init, "lr_final": lr_final, "max_steps": max_steps,
                      "lr_delay_steps": delay_steps, "lr_delay_mult": delay_mult, "lr": values})
    return {**header(commit, "math.learning_rate_decay(step, lr_init, lr_final, max_steps, lr_delay_steps, "
                             "lr_delay_mult)"),
            "steps": steps, "cases": cases}


def make_metrics(off, commit):
    rng = np.random.default_rng(SEED + 10)
    jnp = off.jnp
    yy, xx = np.mgrid[0:24, 0:24] / 23.0
    base = np.stack([0.5 + 0.4 * np.sin(6 * xx + 2 * yy), xx * yy, 0.3 + 0.5 * np.cos(4 * yy) ** 2], -1)
    pairs = []
    truth = f32(np.clip(base + rng.normal(0, 0.02, base.shape), 0, 1))
    noisy = f32(np.clip(truth + rng.normal(0, 0.08, base.shape), 0, 1))
    pairs.append((truth, noisy))
    flat = f32(np.full((24, 24, 3), 0.25))       # constant: zero variances (SSIM's clamps)
    other = f32(np.clip(0.25 + rng.normal(0, 0.01, (24, 24, 3)), 0, 1))
    pairs.append((other, flat))
    ssim_fn = lambda a, b: off.math.compute_ssim(a, b, max_val=1.)  # as train.py and eval.py bind it
    out = []
    for pred, gt in pairs:
        mse = float(((jnp.asarray(pred) - jnp.asarray(gt)) ** 2).mean())
        out.append({"pred": tolist(pred), "gt": tolist(gt), "mse": mse,
                    "psnr": float(off.math.mse_to_psnr(mse)), "ssim": float(ssim_fn(pred, gt))})
    return {**header(commit, "math.mse_to_psnr(((pred - gt)**2).mean()) and math.compute_ssim(pred, gt, max_val=1.) "
                             "(train.py/eval.py), float64"),
            "pairs": out}


# ---- Output ----

def dump(value, indent=0):
    """JSON with objects one key a line and arrays on one line (floats as repr: full float64 precision)."""
    if isinstance(value, dict):
        pad = "  " * (indent + 1)
        items = [f"{pad}{json.dumps(k)}: {dump(v, indent + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + "  " * indent + "}"
    return json.dumps(value, separators=(",", ":"), allow_nan=False)


def official_commit(args):
    if args.official_commit:
        return args.official_commit
    r = subprocess.run(["git", "-C", args.official, "rev-parse", "HEAD"], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"--official {args.official} is not a git work tree: pass --official-commit (e.g. {EXPECTED_COMMIT})")
    return r.stdout.strip()


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--official", required=True, help="checkout of github:google/mipnerf (holds internal/mip.py)")
    p.add_argument("--official-commit", help="its commit, when --official is not a git work tree (a git archive)")
    p.add_argument("--out", required=True, help="folder for the fixtures (tests/official/fixtures)")
    p.add_argument("--only", help="comma-separated fixture names (e.g. model.json,adam.json): write only these")
    args = p.parse_args(argv)
    if not os.path.isfile(os.path.join(args.official, "internal", "mip.py")):
        fail(f"--official {args.official}: no internal/mip.py there; pass a google/mipnerf checkout")
    commit = official_commit(args)
    if commit != EXPECTED_COMMIT:
        print(f"make_vectors.py: note: official commit {commit}, the committed fixtures came from {EXPECTED_COMMIT}",
              file=sys.stderr)
    off = Official(args.official)
    os.makedirs(args.out, exist_ok=True)
    makers = {
        "cast_rays.json": lambda tmp: make_cast_rays(off, commit),
        "encode.json": lambda tmp: make_encode(off, commit),
        "sample.json": lambda tmp: make_sample(off, commit),
        "resample.json": lambda tmp: make_resample(off, commit),
        "render.json": lambda tmp: make_render(off, commit),
        "render_grad.json": lambda tmp: make_render_grad(off, commit),
        "blender_rays.json": lambda tmp: make_blender(off, commit, os.path.join(tmp, "blender")),
        "ndc.json": lambda tmp: make_ndc(off, commit),
        "llff.json": lambda tmp: make_llff(off, commit, os.path.join(tmp, "llff")),
        "multicam.json": lambda tmp: make_multicam(off, commit, os.path.join(tmp, "multicam")),
        "schedule.json": lambda tmp: make_schedule(off, commit),
        "metrics.json": lambda tmp: make_metrics(off, commit),
    }
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import model_vectors
    model_makers = model_vectors.makers(sys.modules[__name__], off, commit)
    makers.update(model_makers)
    wanted = list(makers) if not args.only else args.only.split(",")
    for name in wanted:
        if name not in makers:
            fail(f"--only: no fixture '{name}'; the fixtures are {', '.join(makers)}")
    with tempfile.TemporaryDirectory(prefix="mipnerf_official_") as tmp:
        fixtures = {name: makers[name](tmp) for name in wanted}
    import flax
    import PIL
    versions = {"python": sys.version.split()[0], "jax": off.jax.__version__, "flax": flax.__version__,
                "numpy": np.__version__, "pillow": PIL.__version__}
    total = 0
    for name, value in fixtures.items():
        stubs = STUBS + (model_vectors.STUBS if name in model_makers else [])
        value["stubs"] = [{"name": n, "what": w} for n, w in stubs]
        value["versions"] = versions
        text = dump(value) + "\n"
        with open(os.path.join(args.out, name), "w") as f:
            f.write(text)
        total += len(text)
        print(f"{name}: {len(text)} bytes")
    print(f"total: {total} bytes (official commit {commit})")


if __name__ == "__main__":
    main(sys.argv[1:])
