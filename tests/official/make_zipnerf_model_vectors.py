#!/usr/bin/env python3
"""One level of the official Zip-NeRF model with fixed weights on fixed rays and interval edges, as test vectors
(tests/official/fixtures/zipnerf_model.json).

Run by hand, never by the test suite: it needs JAX, flax, gin, ml_collections and a checkout of
github:jonbarron/camp_zipnerf (read through sys.path, never copied). Our `--model zipnerf` samples with mip-NeRF's
coarse and fine levels, not the official proposal networks, so the comparison is one level on given edges: the official
modules themselves, instantiated with keyword arguments (no gin configuration), with weights drawn here:
  - coord.hexify's deterministic multisamples (rng None), as models.MLP calls it (unscented_mip_basis 'hexify');
  - grid_utils.HashEncoding (4 levels of 4, 8, 16, 32 cells: two dense, two hashed into 2^9 entries; 2 features;
    append_scale; precondition 10; the box [-1.5, 1.5]^3, ours for world rays) with math.average_across_multisamples,
    called by models.MLP.predict_density with x_scale = unscented_scale_mult (0.5) * perp_mag;
  - models.MLP with our zipnerf architecture at a small width: one trunk layer of 16, the density from it, a bottleneck
    of 16 (= our trunk width), one view layer of 8 on [bottleneck | view PE degrees 0..3 with identity], softplus
    density with density_bias -1, sigmoid colour with rgb_padding 0.001;
  - render.compute_alpha_weights and render.volumetric_rendering (white background, compute_extras).
The fixture holds the inputs (float32 values), the weights (the official parameter trees; our table and flat MLP
buffer are the same numbers in order, see test_zipnerf_model.cpp), the MLP's input features, the raw density and colour
of each interval, each ray's colour, acc and distances, and the first-order sensitivities that bound our float32 error.

warp_fn. models.MLP computes the footprint (x_scale) only when warp_fn is not None: with warp_fn None the official grid
gets x_scale None, so no level is downweighted and no scale feature is appended. Our model (no contraction) is the
official one with the identity as warp_fn: predict_density then calls coord.track_isotropic(identity, control,
perp_mag), which keeps the points and multiplies perp_mag by cbrt(|det I|) = 1. The identity carries a __wrapped__
attribute because predict_density compares warp_fn.__wrapped__ with coord.contract (gin wraps configured functions).
The density mask of models.MLP (density zero where a Gaussian's mean is outside the box) is kept: every mean of these
rays is inside the box (checked here), so it changes nothing; ours has no such mask.

Distance. The official distance_mean is exp(E[log t_mid]), a geometric mean; ours (kernels/render.cl) is mip-NeRF's
E[t_mid]. The fixture holds both: distance_mean from the official code, and "distance", mip-NeRF's formula
clip(nan_to_num(sum(w t_mid) / acc, inf), t_0, t_N) evaluated here in float64 on the official weights.

Bounds. As tests/official/model_vectors.py: each stage's value z becomes z + eps * m (m the magnitude our float32 bound
of that stage multiplies), and the Jacobian of the outputs with respect to eps at 0 gives, per output o and stage s,
S_s(o) = sum_i |d o / d eps_i| m_i. Stages: grid_position (each grid feature's m = precondition * max|table_l| *
mag_r * N_l / box, mag_r = |o| + t_max |d| + sqrt(1/2) r t_max), grid_values (precondition * max|table_l| for a grid
feature, precondition * level_scale_l for a scale feature), dense/Dense_k (|x| |W| + |b|), pe (1), density
(softplus(x) + |x| sigmoid(x)), rgb (1). The C++ test holds the constants c_s.

    git -C /work/.mirror/jonbarron+camp_zipnerf/repo archive HEAD | tar -x -C /tmp/camp_zipnerf
    ~/.cache/mipnerf-cl/vs-official-venv/bin/pip install ml_collections   # models.py imports it
    ~/.cache/mipnerf-cl/vs-official-venv/bin/python tests/official/make_zipnerf_model_vectors.py \\
        --zipnerf /tmp/camp_zipnerf --zipnerf-commit 8e6d57e3aee34235faf3ef99decca0994efe66c9 \\
        --out tests/official/fixtures/zipnerf_model.json

Stand-ins (in this process only): internal/configs.py and internal/image_utils.py are empty modules (models.py imports
them; configs pulls chex, jaxcam and optax, image_utils dm_pix and matplotlib; models.MLP's path here uses neither).
Inputs come from numpy.random.default_rng(20261128) rounded to float32; the official functions run under
jax_enable_x64 on float64 arrays holding them.
"""
import argparse
import contextlib
import functools
import importlib
import json
import os
import sys
import types

import numpy as np

SEED = 20261128
N_RAYS = 12
N_INTERVALS = 16
GRID = dict(hash_map_size=2**9, num_features=2, scale_supersample=1.0, min_grid_size=4, max_grid_size=32,
            hash_init_range=1e-4, precondition_scaling=10.0, bbox_scaling=1.5, append_scale=True)
MLP = dict(net_depth=1, net_width=16, bottleneck_width=16, net_depth_viewdirs=1, net_width_viewdirs=8, deg_view=4,
           density_bias=-1.0, rgb_padding=0.001, unscented_mip_basis="hexify", unscented_scale_mult=0.5,
           disable_density_normals=True)
STUBS = [
    ("camp_zipnerf internal.configs", "an empty module (models.py imports it; it imports chex, jaxcam and optax)"),
    ("camp_zipnerf internal.image_utils", "an empty module (models.py imports it for the vignette and diffuse colour, "
                                          "unused here; it imports dm_pix and matplotlib)"),
]


def load_official(zipnerf):
    """models, grid_utils, render, coord of camp_zipnerf/internal as a bare package (its __init__ imports every
    module), with the stand-ins above."""
    package = types.ModuleType("zipnerf_internal")
    package.__path__ = [os.path.join(zipnerf, "camp_zipnerf", "internal")]
    sys.modules["zipnerf_internal"] = package
    for name in ["configs", "image_utils"]:
        sys.modules["zipnerf_internal." + name] = types.ModuleType("zipnerf_internal." + name)
    return {name: importlib.import_module("zipnerf_internal." + name)
            for name in ["models", "grid_utils", "render", "coord", "math"]}


def identity(x):
    return x


# warp_fn for a model without contraction (module doc): the identity, wrapped as gin wraps a configured function (so
# that predict_density can read warp_fn.__wrapped__, which is not coord.contract).
identity_warp = functools.wraps(identity)(lambda x: identity(x))


def f32(a):
    return np.asarray(a, np.float32).astype(np.float64)


def make_rays(rng):
    """Cone rays from inside [-0.4, 0.4]^3 with |d| in about [0.8, 1.2] and t in [0.05, 0.85], so every point stays
    within |x| < 1.45 of the box [-1.5, 1.5]^3; radii from a pixel's to wide (footprints from a fraction of the finest
    cell to several of the coarsest); ray 0 along +z (construct_perp_basis' other cross product); one zero-width
    interval."""
    origins = f32(rng.uniform(-0.4, 0.4, size=(N_RAYS, 3)))
    dirs = rng.normal(size=(N_RAYS, 3))
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    dirs *= rng.uniform(0.8, 1.2, size=(N_RAYS, 1))
    dirs[0] = [0.0, 0.0, 1.0]
    directions = f32(dirs)
    radii = f32(np.array([0.002, 0.0005, 0.004, 0.01, 0.02, 0.04, 0.08, 0.15, 0.3, 0.6, 0.003, 0.05])[:, None])
    viewdirs = f32(directions / np.linalg.norm(directions, axis=-1, keepdims=True))
    near = rng.uniform(0.05, 0.2, size=(N_RAYS, 1))
    far = rng.uniform(0.6, 0.85, size=(N_RAYS, 1))
    u = np.sort(rng.uniform(0, 1, size=(N_RAYS, N_INTERVALS - 1)), axis=-1)
    tdist = f32(np.concatenate([near, near + (far - near) * u, far], axis=-1))
    tdist[3, 5] = tdist[3, 6]  # a zero-width interval
    return origins, directions, radii, viewdirs, tdist


def make_weights(rng, params):
    """Every parameter drawn anew, by name and shape: table values U(-0.1, 0.1) (features of up to ~1 after the
    preconditioning); kernels U(+-sqrt(6 / (in + out))) (flax's he/glorot scale), biases U(-0.5, 0.5), the density
    layer's bias +2 so that the rays are partly opaque (acc from ~0.2 to ~1)."""
    out = {"grid": {}, "mlp": {}}
    for name, value in params["grid"].items():
        out["grid"][name] = f32(rng.uniform(-0.1, 0.1, size=np.shape(value)))
    for name in sorted(params["mlp"], key=lambda n: int(n.split("_")[1])):
        kernel = params["mlp"][name]["kernel"]
        n_in, n_out = np.shape(kernel)
        limit = np.sqrt(6.0 / (n_in + n_out))
        bias = rng.uniform(-0.5, 0.5, size=(n_out,)) + (2.0 if name == "Dense_1" else 0.0)
        out["mlp"][name] = {"kernel": f32(rng.uniform(-limit, limit, size=(n_in, n_out))), "bias": f32(bias)}
    return out


class Probe:
    """Perturbation hooks (module doc): while installed, each hooked stage's value z becomes z + eps[stage] * m. With
    eps None the hooks record the stages' shapes and pass the values through."""

    def __init__(self, jax, jnp):
        self.jax, self.jnp = jax, jnp
        self.eps = None
        self.shapes = {}
        self.captured = {}
        self.grid_magnitudes = None  # (position, values) m of the features [R][N][L*(F+1)]

    def perturb(self, stage, z, m):
        if self.eps is None:
            self.shapes[stage] = z.shape
            return z
        return z + self.eps[stage] * self.jax.lax.stop_gradient(m)

    def activations(self):
        from flax import linen as nn
        jnp = self.jnp

        def density(x):
            y = nn.softplus(x)
            return self.perturb("density", y, y + jnp.abs(x) * nn.sigmoid(x))

        def rgb(x):
            y = nn.sigmoid(x)
            return self.perturb("rgb", y, jnp.ones_like(y))
        return dict(density_activation=density, rgb_activation=rgb)

    @contextlib.contextmanager
    def installed(self, off):
        from flax import linen as nn
        jnp, probe, coord = self.jnp, self, off["coord"]
        pos_enc = coord.pos_enc

        def view_pe(x, min_deg, max_deg, append_identity=True):
            z = pos_enc(x, min_deg, max_deg, append_identity)
            return probe.perturb("pe", z, jnp.ones_like(z))

        def interceptor(next_fun, args, kwargs, context):
            z = next_fun(*args, **kwargs)
            if context.method_name != "__call__":
                return z
            if isinstance(context.module, off["grid_utils"].HashEncoding):
                position, values = probe.grid_magnitudes
                z = probe.perturb("grid_position", z, position)
                z = probe.perturb("grid_values", z, values)
                probe.captured["features"] = z
                return z
            if isinstance(context.module, nn.Dense):
                p = context.module.variables["params"]
                m = jnp.abs(args[0]) @ jnp.abs(p["kernel"]) + jnp.abs(p["bias"])
                z = probe.perturb("dense/" + context.module.name, z, m)
                probe.captured["dense/" + context.module.name] = z
            return z

        coord.pos_enc = view_pe
        try:
            with nn.intercept_methods(interceptor):
                yield
        finally:
            coord.pos_enc = pos_enc


def grid_magnitudes(weights, sizes, origins, directions, radii, tdist):
    """The m of the two grid stages for every feature [R][N][L*(F+1)] (module doc; tests/ops/test_zip_features.cpp
    derives the float32 error of a feature from them)."""
    f = GRID["num_features"]
    box = 2 * GRID["bbox_scaling"]
    pre = GRID["precondition_scaling"]
    maxval = GRID["hash_init_range"] / pre
    t_max = np.abs(tdist).max(-1)
    mag = (np.linalg.norm(origins, axis=-1) + t_max * np.linalg.norm(directions, axis=-1)
           + np.sqrt(0.5) * radii[:, 0] * t_max)
    position = np.zeros((N_RAYS, N_INTERVALS, len(sizes) * (f + 1)))
    values = np.zeros_like(position)
    for l, (name, n) in enumerate(sizes):
        table = weights["grid"][name]
        largest = np.abs(table).max()
        level_scale = np.sqrt(maxval**2 + np.mean(table**2))
        position[:, :, l * (f + 1):l * (f + 1) + f] = (pre * largest * mag * n / box)[:, None, None]
        values[:, :, l * (f + 1):l * (f + 1) + f] = pre * largest
        values[:, :, l * (f + 1) + f] = pre * level_scale
    return position, values


def short32(a):
    """float32 values as the shortest decimals that read back to the same float32."""
    a = np.asarray(a, dtype=np.float32)
    flat = [float(str(x)) for x in a.reshape(-1)]
    if not np.array_equal(np.asarray(flat, np.float64).astype(np.float32), a.reshape(-1)):
        raise RuntimeError("a float32 value does not survive its shortest decimal")
    return np.asarray(flat).reshape(a.shape).tolist()


def round_up4(a):
    """Non-negative magnitudes to 4 significant digits, rounded up (a sensitivity may only grow)."""
    out = []
    for x in np.asarray(a, dtype=np.float64).reshape(-1):
        if x <= 0:
            out.append(0.0)
            continue
        q = 10.0**(np.floor(np.log10(x)) - 3)
        out.append(float(f"{np.ceil(x * (1 + 1e-12) / q) * q:.4g}"))
    return np.asarray(out).reshape(np.shape(a)).tolist()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--zipnerf", required=True, help="a checkout of camp_zipnerf (its files are read)")
    parser.add_argument("--zipnerf-commit", required=True)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    import flax
    from flax import linen as nn
    off = load_official(args.zipnerf)
    probe = Probe(jax, jnp)
    rng = np.random.default_rng(SEED)
    origins, directions, radii, viewdirs, tdist = make_rays(rng)
    rays = types.SimpleNamespace(origins=jnp.asarray(origins), directions=jnp.asarray(directions),
                                 radii=jnp.asarray(radii), viewdirs=jnp.asarray(viewdirs))
    gaussians = off["render"].cast_rays(jnp.asarray(tdist), rays.origins, rays.directions, rays.radii, "cone",
                                        diag=False)

    class ZipLevel(nn.Module):
        """One level of the official Model: its grid and MLP (the Model builds both in setup and hands the grid to
        the MLP), then the weights and the rendering as Model.__call__ does them."""

        def setup(self):
            self.grid = off["grid_utils"].HashEncoding(**GRID)
            self.mlp = off["models"].MLP(**MLP, warp_fn=identity_warp, **probe.activations())

        def __call__(self, gaussians, rays, tdist):
            results = self.mlp(None, gaussians, viewdirs=rays.viewdirs, grid=self.grid, rays=rays, tdist=tdist,
                               train=False)
            weights = off["render"].compute_alpha_weights(results["density"], tdist, rays.directions)
            rendering = off["render"].volumetric_rendering(results["rgb"], weights, tdist, 1.0, True)
            return results, weights, rendering

    level = ZipLevel()
    with probe.installed(off):
        probe.grid_magnitudes = (0.0, 0.0)
        params = level.init(jax.random.PRNGKey(0), gaussians, rays, jnp.asarray(tdist))["params"]
    params = flax.core.unfreeze(params)
    official_params = {"grid": params["grid"], "mlp": params["mlp"]}
    weights = make_weights(rng, official_params)
    variables = {"params": {"grid": {k: jnp.asarray(v) for k, v in weights["grid"].items()},
                            "mlp": {k: {p: jnp.asarray(v) for p, v in d.items()} for k, d in weights["mlp"].items()}}}
    grid = off["grid_utils"].HashEncoding(**GRID)
    sizes = [(f"{'grid' if n**3 <= GRID['hash_map_size'] else 'hash'}_{str(n).zfill(len(str(max(grid.grid_sizes))))}",
              int(n)) for n in grid.grid_sizes]
    if sorted(name for name, _ in sizes) != sorted(weights["grid"]):
        raise RuntimeError(f"the grid's parameters are {sorted(weights['grid'])}, expected {sizes}")
    probe.grid_magnitudes = tuple(jnp.asarray(m) for m in grid_magnitudes(weights, sizes, origins, directions, radii,
                                                                          tdist))
    if not np.all(np.abs(np.asarray(gaussians[0])) < GRID["bbox_scaling"]):
        raise RuntimeError("a Gaussian's mean is outside the box: the official density mask would zero it")

    t_mids = 0.5 * (tdist[:, :-1] + tdist[:, 1:])

    def outputs(eps):
        """[R][5] (rgb, acc, distance) and [R][N][4] (raw density, raw rgb), mip-NeRF's distance as the module doc."""
        probe.eps, probe.captured = eps, {}
        with probe.installed(off):
            results, w, rendering = level.apply(variables, gaussians, rays, jnp.asarray(tdist))
        acc = rendering["acc"]
        distance = jnp.clip(jnp.nan_to_num(jnp.sum(w * t_mids, -1) / acc, nan=jnp.inf), tdist[:, 0], tdist[:, -1])
        per_ray = jnp.concatenate([rendering["rgb"], acc[:, None], distance[:, None]], -1)
        raw = jnp.concatenate([probe.captured["dense/Dense_1"], probe.captured["dense/Dense_4"]], -1)
        return per_ray, raw, (results, w, rendering, probe.captured["features"])

    probe.shapes = {}
    per_ray, raw, (results, w, rendering, features) = outputs(None)
    eps0 = {stage: jnp.zeros(shape) for stage, shape in probe.shapes.items()}
    jac_ray, jac_raw = jax.jacrev(lambda e: outputs(e)[:2])(eps0)
    sens_ray, sens_raw = {}, {}
    for stage in eps0:
        sens_ray[stage] = round_up4(jnp.sum(jnp.abs(jac_ray[stage]).reshape(N_RAYS, 5, -1), -1))
        sens_raw[stage] = round_up4(jnp.sum(jnp.abs(jac_raw[stage]).reshape(N_RAYS, N_INTERVALS, 4, -1), -1))
    again = outputs(eps0)
    if not (np.array_equal(np.asarray(again[0]), np.asarray(per_ray))
            and np.array_equal(np.asarray(again[1]), np.asarray(raw))):
        raise RuntimeError("the probe's zero perturbations changed the model's outputs")

    # What our render bound needs per ray: sum_i (1 + tau_{i+1}) w_i, tau_{i+1} the optical depth through interval i.
    delta = np.diff(tdist, axis=-1) * np.linalg.norm(directions, axis=-1)[:, None]
    tau_after = np.cumsum(np.asarray(results["density"]) * delta, -1)
    weight_sums = np.sum((1 + tau_after) * np.asarray(w), -1)
    print("acc", np.round(np.asarray(rendering["acc"]), 3), file=sys.stderr)
    print("raw density range", float(np.min(raw[..., 0])), float(np.max(raw[..., 0])), file=sys.stderr)

    out = {
        "generator": "tests/official/make_zipnerf_model_vectors.py",
        "zipnerf_commit": args.zipnerf_commit,
        "versions": {"jax": jax.__version__, "flax": flax.__version__, "numpy": np.__version__},
        "stubs": [{"name": n, "why": why} for n, why in STUBS],
        "grid": dict(GRID, level_sizes=[n for _, n in sizes], level_names=[name for name, _ in sizes]),
        "mlp": dict(MLP, warp_fn="identity (module doc)", density_activation="softplus", rgb_activation="sigmoid"),
        "background": "white",
        "rays": {"origins": short32(origins), "directions": short32(directions), "radii": short32(radii[:, 0]),
                 "viewdirs": short32(viewdirs), "t_edges": short32(tdist)},
        "params": {"grid": [short32(weights["grid"][name]) for name, _ in sizes],
                   "mlp": [{"name": name, "kernel": short32(d["kernel"]), "bias": short32(d["bias"])}
                           for name, d in sorted(weights["mlp"].items(), key=lambda kv: int(kv[0].split("_")[1]))]},
        "features": np.asarray(features).tolist(),
        "raw": np.asarray(raw).tolist(),
        "raw_layout": "[ray][interval][raw density, raw rgb 0..2] (pre-activation)",
        "density": np.asarray(results["density"]).tolist(),
        "weights": np.asarray(w).tolist(),
        "outputs": np.asarray(per_ray).tolist(),
        "output_layout": "[ray][comp_rgb 0..2, acc, distance (mip-NeRF's formula on the official weights)]",
        "distance_mean": np.asarray(rendering["distance_mean"]).tolist(),
        "sensitivities": {"outputs": sens_ray, "raw": sens_raw,
                          "render_weight_sums": round_up4(weight_sums)},
    }
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
