"""The model-level fixtures of make_vectors.py: the official MipNerfModel with fixed weights on rays of the Multicam
scene (model.json), the same model with density noise and randomized sampling given our draws (noise.json), and one
official train_step (loss with lossmult and the coarse weight, its gradient, clipping and the Adam update: adam.json).
make_vectors.py calls makers(); nothing here runs alone.

Bounds. A fixture holds the official values in float64; the C++ test's bound is our float32 error. For the model that
error enters at every stage (rays, edges, Gaussians, IPE, each dense layer, the activations, rendering) and is carried
by the model itself to its outputs. The script measures that carrying with the official model: each stage's value z is
replaced by z + eps * m (Probe below), m the magnitude our float32 bound of that stage multiplies (|t| for the edges,
|x|.|W| + |b| for a dense layer, ...), eps a variable that is 0, and the Jacobian of the outputs with respect to eps
gives, per output o and stage s, the first-order sensitivity S_s(o) = sum_i |d o / d eps_i|: an error of at most
c_s * u * m_i in every value of stage s moves o by at most c_s * u * S_s(o). The fixture stores S_s(o) (rounded up to
4 digits); the C++ test holds the constants c_s, derived there beside the assertion. The stop-gradient between the
levels is lifted for this (stop_level_grad False, the same values), so the fine level's sensitivities include its
resampling's response to the coarse level's errors.
"""

import contextlib
import functools
import math as pymath
import os
import sys
import types

import numpy as np

# Import-time and call-time stand-ins the model fixtures add to make_vectors.STUBS (in this process only).
STUBS = [
    ("flax.metrics.tensorboard", "a module with an empty SummaryWriter (train.py imports it; it needs TensorFlow)"),
    ("matplotlib, matplotlib.cm", "empty modules (vis.py imports them; train_step does not use them)"),
    ("flax.optim.Adam", "the optimiser train_step is handed: optax.adam(lr, b1=0.9, b2=0.999, eps=1e-8) behind "
                        "flax.optim.Optimizer's target/apply_gradient, the update of flax's Adam.apply_param_gradient"),
    ("jax.random.uniform, jax.random.normal", "noise.json: our draws xi and z (the uniform by make_vectors' formula)"),
]

# The model of model.json, noise.json and adam.json: the paper's MipNerfModel and MLP with fewer samples and a narrower
# MLP (4 trunk layers of 16, the skip after layer 2, a view branch of 8), keeping what the paper's has: IPE degrees 0..15,
# view PE 0..3 with identity, the skip connection, the view branch, rgb_padding 0.001, density_bias -1, softplus,
# padding 0.01 and the blur-pool in resampling, white background (the multiscale Blender defaults).
MODEL = dict(num_samples=16, num_levels=2, resample_padding=0.01, use_viewdirs=True, lindisp=False, ray_shape="cone",
             min_deg_point=0, max_deg_point=16, deg_view=4, density_bias=-1.0, rgb_padding=0.001,
             disable_integration=False)
MLP = dict(net_depth=4, net_width=16, net_depth_condition=1, net_width_condition=8, skip_layer=2)
N_RAYS = 16
# Our training keys of the randomized runs (noise.json): batch rays 0..R-1 of step STEP with seed SEED_OURS.
SEED_OURS, STEP = 20200823, 41


def rng_normal4(mv, seed, item, step, slot, stream):
    """host/core/rng.hpp's rng_normal4: Box-Muller of rng_uniform4's four uniforms, in double."""
    u = mv.rng_uniform4(seed, item, step, slot, stream)
    r0, r1 = pymath.sqrt(-2.0 * pymath.log(1.0 - u[0])), pymath.sqrt(-2.0 * pymath.log(1.0 - u[2]))
    two_pi = 6.283185307179586476925286766559
    return [r0 * pymath.cos(two_pi * u[1]), r0 * pymath.sin(two_pi * u[1]), r1 * pymath.cos(two_pi * u[3]),
            r1 * pymath.sin(two_pi * u[3])]


def our_normals(mv, key, n_rays, n_samples, level):
    """z[ray][i] = rng_normal4(seed, first_ray + ray, step, level * 2^24 + i / 4, stream 4)[i % 4], kernels/render.cl."""
    out = np.zeros((n_rays, n_samples))
    for ray in range(n_rays):
        for i in range(n_samples):
            out[ray, i] = rng_normal4(mv, key["seed"], key["first_ray"] + ray, key["step"], (level << 24) + i // 4,
                                      4)[i % 4]
    return out


def short32(a):
    """float32 values as the shortest decimals that read back (decimal -> double -> float32, as the C++ tests read
    them) to the same float32: about half the characters of full float64 digits."""
    a = np.asarray(a, dtype=np.float32)
    flat = [float(str(x)) for x in a.reshape(-1)]
    back = np.asarray(np.asarray(flat, dtype=np.float64), dtype=np.float32)
    if not np.array_equal(back.view(np.uint32), a.reshape(-1).view(np.uint32)):
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


class Official:
    """The official modules the model fixtures use, on top of make_vectors.Official (its stand-ins), plus the ones
    train.py needs to import: flax.metrics.tensorboard (TensorFlow), matplotlib (vis.py) and flax.optim.Adam, which
    main() alone uses (train_step is handed its optimiser)."""

    def __init__(self, off):
        self.off, self.jax, self.jnp = off, off.jax, off.jnp
        import flax
        tb = types.ModuleType("flax.metrics.tensorboard")
        tb.SummaryWriter = object
        sys.modules["flax.metrics.tensorboard"] = tb
        import flax.metrics
        flax.metrics.tensorboard = tb
        matplotlib = sys.modules.setdefault("matplotlib", types.ModuleType("matplotlib"))
        matplotlib.cm = sys.modules.setdefault("matplotlib.cm", types.ModuleType("matplotlib.cm"))
        argv, sys.argv = sys.argv, sys.argv[:1]  # train.py parses absl flags at import
        try:
            import train
            from internal import models
        finally:
            sys.argv = argv
        import gin
        self.train, self.models, self.gin = train, models, gin
        self.flax = flax


def official_model(o, **overrides):
    """MipNerfModel with MODEL (and overrides), its MLP configured through gin as the official configs do."""
    o.gin.clear_config()
    o.gin.parse_config([f"MLP.{k} = {v}" for k, v in MLP.items()])
    return o.models.MipNerfModel(**{**MODEL, **overrides})


def make_params(o, rays, key):
    """Fixed weights for every Dense layer, float32 values held in float64: Glorot-uniform kernels (flax's own
    initialiser's scale), the density head x2 and the rgb head x3 so that densities span thin to opaque and colours
    saturate (where rgb_padding shows), biases N(0, 0.2)."""
    jnp = o.jnp
    model = official_model(o, density_noise=0.0)
    variables = model.init(o.jax.random.PRNGKey(0), o.jax.random.PRNGKey(1), rays, randomized=False,
                           white_bkgd=True)
    rng = np.random.default_rng(key)
    dense = variables["params"]["MLP_0"]
    names = sorted(dense, key=lambda s: int(s.split("_")[1]))
    gains = {"Dense_4": 2.0, "Dense_7": 3.0}
    params = {}
    for name in names:
        n_in, n_out = dense[name]["kernel"].shape
        a = np.sqrt(6.0 / (n_in + n_out)) * gains.get(name, 1.0)
        kernel = np.asarray(rng.uniform(-a, a, (n_in, n_out)), np.float32).astype(np.float64)
        bias = np.asarray(rng.normal(0, 0.2, n_out), np.float32).astype(np.float64)
        params[name] = {"kernel": jnp.asarray(kernel), "bias": jnp.asarray(bias)}
    return {"params": {"MLP_0": params}}, names


class Probe:
    """Perturbation hooks in the official modules (module doc): while installed, each hooked stage's value z becomes
    z + eps[stage][call] * m. With eps None the hooks only record the stages' shapes (and pass values through)."""

    def __init__(self, o, focal_per_ray):
        self.o, self.jax, self.jnp = o, o.jax, o.jnp
        self.focal = focal_per_ray
        self.eps = None
        self.shapes = {}
        self.calls = {}
        self.quiet = 0  # > 0: inside an official function whose result a hook recomputes (no perturbation, no count)
        self.renders = []
        self.raw = []  # per level: the MLP's (raw_rgb, raw_density)
        self.lifted = None
        self.normals = None  # given standard normal draws per level (noise.json), or None
        self.uniforms = None  # given uniform draws xi per level (noise.json), or None

    def start(self, eps):
        self.eps, self.calls, self.renders, self.raw = eps, {}, [], []

    def perturb(self, stage, z, m):
        call = self.calls.get(stage, 0)
        self.calls[stage] = call + 1
        if self.eps is None:
            self.shapes.setdefault(stage, []).append(z.shape)
            return z
        return z + self.eps[stage][call] * self.jax.lax.stop_gradient(m)

    def perturb_rays(self, rays):
        jnp = self.jnp
        d = rays.directions
        n1 = jnp.sum(jnp.abs(d), -1, keepdims=True)
        n2 = jnp.linalg.norm(d, axis=-1, keepdims=True)
        return rays._replace(
            directions=self.perturb("directions", d, jnp.broadcast_to(n1, d.shape)),
            radii=self.perturb("radii", rays.radii, rays.radii * (1 + n2 * self.focal[:, None])),
            viewdirs=self.perturb("viewdirs", rays.viewdirs, jnp.broadcast_to(n1 / n2 + 0.5, d.shape)))

    @contextlib.contextmanager
    def installed(self):
        o, jax, jnp, mip = self.o, self.jax, self.jnp, self.o.off.mip
        from flax import linen as nn
        original = {name: getattr(mip, name) for name in
                    ["sample_along_rays", "resample_along_rays", "cast_rays", "lift_gaussian", "integrated_pos_enc",
                     "pos_enc", "volumetric_rendering"]}
        normal, uniform = jax.random.normal, jax.random.uniform
        probe = self

        @contextlib.contextmanager
        def quiet():
            probe.quiet += 1
            try:
                yield
            finally:
                probe.quiet -= 1

        def sample_along_rays(key, origins, directions, radii, num_samples, near, far, randomized, lindisp,
                              ray_shape):
            with quiet():
                t, _ = original["sample_along_rays"](key, origins, directions, radii, num_samples, near, far,
                                                     randomized, lindisp, ray_shape)
            t = probe.perturb("t", t, jnp.abs(t))
            return t, mip.cast_rays(t, origins, directions, radii, ray_shape)

        def resample_along_rays(key, origins, directions, radii, t_vals, weights, randomized, ray_shape, stop_grad,
                                resample_padding):
            previous = probe.renders[-1]
            weights = probe.perturb("coarse_weights", weights, (1 + previous["tau_after"]) * previous["weights"])
            with quiet():
                t, _ = original["resample_along_rays"](key, origins, directions, radii, t_vals, weights, randomized,
                                                       ray_shape, stop_grad, resample_padding)
            t = probe.perturb("t", t, jnp.abs(t))
            # Our resampling's own error (tests/official/test_ray_math.cpp): (4N + 8)u / p_min of the widest bin,
            # p_min >= padding / (2 sum w + N padding) (the blur-pool at most doubles the sum).
            w = jax.lax.stop_gradient(weights)
            n = w.shape[-1]
            p_min = resample_padding / (2 * jnp.sum(w, -1, keepdims=True) + n * resample_padding)
            widest = jnp.max(t_vals[..., 1:] - t_vals[..., :-1], -1, keepdims=True)
            t = probe.perturb("resample", t, jnp.broadcast_to(widest / p_min, t.shape))
            return t, mip.cast_rays(t, origins, directions, radii, ray_shape)

        def lift_gaussian(d, t_mean, t_var, r_var, diag):
            if not probe.quiet:
                probe.lifted = (t_var, r_var)
            return original["lift_gaussian"](d, t_mean, t_var, r_var, diag)

        def cast_rays(t_vals, origins, directions, radii, ray_shape, diag=True):
            means, covs = original["cast_rays"](t_vals, origins, directions, radii, ray_shape, diag)
            if probe.quiet:
                return means, covs
            t_var, r_var = probe.lifted
            o = origins[..., None, :]
            means = probe.perturb("means", means, jnp.abs(o) + jnp.abs(means - o))
            covs = probe.perturb("covs", covs, t_var[..., None] * directions[..., None, :]**2 + r_var[..., None])
            return means, covs

        def integrated_pos_enc(x_coord, min_deg, max_deg, diag=True):
            features = original["integrated_pos_enc"](x_coord, min_deg, max_deg, diag)
            cov = x_coord[1]
            scales = jnp.array([4.0**i for i in range(min_deg, max_deg)])
            y_var = jnp.reshape(cov[..., None, :] * scales[:, None], list(cov.shape[:-1]) + [-1])
            return probe.perturb("ipe", features, jnp.exp(-0.5 * jnp.concatenate([y_var] * 2, -1)))

        def pos_enc(x, min_deg, max_deg, append_identity=True):
            features = original["pos_enc"](x, min_deg, max_deg, append_identity)
            return probe.perturb("pe", features, jnp.ones_like(features))

        def volumetric_rendering(rgb, density, t_vals, dirs, white_bkgd):
            out = original["volumetric_rendering"](rgb, density, t_vals, dirs, white_bkgd)
            delta = (t_vals[..., 1:] - t_vals[..., :-1]) * jnp.linalg.norm(dirs[..., None, :], axis=-1)
            tau_after = jnp.cumsum(density[..., 0] * delta, -1)
            probe.renders.append({"weights": jax.lax.stop_gradient(out[3]),
                                  "tau_after": jax.lax.stop_gradient(tau_after), "t_vals": t_vals,
                                  "density": density})
            return out

        def uniform_draws(key, shape=(), dtype=None, minval=0.0, maxval=1.0):
            # make_vectors.Official.given_uniform's formula on level l's draws (l = the levels rendered so far).
            xi = probe.uniforms[len(probe.renders)]
            if tuple(shape) != xi.shape:
                raise RuntimeError(f"official draw of shape {tuple(shape)}, given {xi.shape}")
            return jnp.maximum(minval, jnp.asarray(xi, jnp.float64) * (maxval - minval) + minval)

        def normal_draws(key, shape=(), dtype=None):
            level = len(probe.renders)
            z = jnp.asarray(probe.normals[level]).reshape(shape)
            return probe.perturb("noise", z, jnp.abs(z))

        def dense_interceptor(next_fun, args, kwargs, context):
            if type(context.module).__name__ == "MLP" and context.method_name == "__call__":
                raw = next_fun(*args, **kwargs)
                probe.raw.append(raw)
                return raw
            if not (isinstance(context.module, nn.Dense) and context.method_name == "__call__"):
                return next_fun(*args, **kwargs)
            z = next_fun(*args, **kwargs)
            p = context.module.variables["params"]
            m = jnp.abs(args[0]) @ jnp.abs(p["kernel"]) + jnp.abs(p["bias"])
            return probe.perturb("dense/" + context.module.name, z, m)

        for name, fn in [("sample_along_rays", sample_along_rays), ("resample_along_rays", resample_along_rays),
                         ("cast_rays", cast_rays), ("lift_gaussian", lift_gaussian),
                         ("integrated_pos_enc", integrated_pos_enc), ("pos_enc", pos_enc),
                         ("volumetric_rendering", volumetric_rendering)]:
            setattr(mip, name, fn)
        if self.normals is not None:
            jax.random.normal = normal_draws
        if self.uniforms is not None:
            jax.random.uniform = uniform_draws
        try:
            with nn.intercept_methods(dense_interceptor):
                yield
        finally:
            for name, fn in original.items():
                setattr(mip, name, fn)
            jax.random.normal, jax.random.uniform = normal, uniform

    def activations(self):
        """The activations as MipNerfModel fields: softplus(x) perturbed by (softplus(x) + |x| sigmoid(x)) (our
        density's error: its own rounding relative to the value, and the rounding of x = raw + bias carried by
        softplus' = sigmoid), the sigmoid absolutely (the widened sigmoid's error is absolute)."""
        from flax import linen as nn
        jnp = self.jnp

        def density(x):
            y = nn.softplus(x)
            return self.perturb("density", y, y + jnp.abs(x) * nn.sigmoid(x))

        def rgb(x):
            y = nn.sigmoid(x)
            return self.perturb("rgb", y, jnp.ones_like(y))
        return dict(density_activation=density, rgb_activation=rgb)


def level_outputs(ret):
    """[levels][rays][5]: comp_rgb (3), acc, distance of each level."""
    import jax.numpy as jnp
    return jnp.stack([jnp.concatenate([comp, acc[:, None], dist[:, None]], -1) for comp, dist, acc in ret])


def run_with_sensitivities(o, probe, variables, rays, randomized, **model_overrides):
    """The model's outputs [levels][rays][5], the per-stage sensitivities (module doc) and what the render bound needs
    (per level and ray: sum_i (1 + tau_after_i) w_i, tau_after_i the optical depth through sample i)."""
    jax, jnp = o.jax, o.jnp
    model = official_model(o, stop_level_grad=False, **probe.activations(), **model_overrides)

    def outputs(eps):
        probe.start(eps)
        with probe.installed():
            ret = model.apply(variables, jax.random.PRNGKey(2), probe.perturb_rays(rays), randomized=randomized,
                              white_bkgd=True)
        return level_outputs(ret)

    probe.shapes = {}
    values = outputs(None)
    eps0 = {stage: [jnp.zeros(s) for s in shapes] for stage, shapes in probe.shapes.items()}
    jac = jax.jacrev(outputs)(eps0)
    sens = {}
    for stage, per_call in jac.items():
        total = 0
        for j in per_call:
            total = total + jnp.sum(jnp.abs(j).reshape(j.shape[:3] + (-1,)), -1)
        sens[stage] = np.asarray(total)
    values2 = outputs(eps0)  # the same values with the renders captured
    render_sums = [np.asarray(jnp.sum((1 + r["tau_after"]) * r["weights"], -1)) for r in probe.renders]
    if not np.array_equal(np.asarray(values), np.asarray(values2)):
        raise RuntimeError("the probe's zero perturbations changed the model's outputs")
    return np.asarray(values), sens, render_sums, probe


def model_batch(mv, off, o, tmp):
    """The rays and pixels of the model fixtures: N_RAYS pixels of the Multicam scene (all scales), official rays."""
    meta, images = mv.write_multicam_scene(tmp)
    ds = mv.load_multicam(off, tmp)
    flat = lambda xs: np.concatenate([np.asarray(x).reshape(-1, np.asarray(x).shape[-1]) for x in xs], 0)
    all_rays = off.utils.Rays(*[flat(x) for x in ds.rays])
    pixels = flat(ds.images)
    rng = np.random.default_rng(mv.SEED + 12)
    index = rng.choice(pixels.shape[0], N_RAYS, replace=False)
    # Also the scale of every ray's image: its focal length (the radii's bound).
    focal = np.concatenate([np.full(w * h, f) for w, h, f in zip(meta["width"], meta["height"], meta["focal"])])
    rays = off.utils.Rays(*[o.jnp.asarray(x[index], o.jnp.float64) for x in all_rays])
    return index, rays, o.jnp.asarray(pixels[index]), focal[index]


def sensitivities_json(sens, render_sums, names):
    """Stage -> [levels][rays][5] rounded up; dense layers under "dense/<flax name>" (the C++ maps them to ours)."""
    out = {stage: round_up4(s) for stage, s in sorted(sens.items())}
    out["render_weight_sums"] = round_up4(np.stack(render_sums))
    return out


def makers(mv, off, commit):
    """name -> function(tmp) writing that fixture (make_vectors.py's main)."""
    state = {}

    def setup(tmp):
        if "o" not in state:
            o = Official(off)
            index, rays, pixels, focal = model_batch(mv, off, o, os.path.join(tmp, "model_scene"))
            variables, names = make_params(o, rays, mv.SEED + 13)
            state.update(o=o, index=index, rays=rays, pixels=pixels, focal=focal, variables=variables, names=names)
        return state

    def params_json(s):
        dense = s["variables"]["params"]["MLP_0"]
        return [{"name": n, "kernel": short32(dense[n]["kernel"]), "bias": short32(dense[n]["bias"])}
                for n in s["names"]]

    def model_json(tmp):
        s = setup(tmp)
        probe = Probe(s["o"], s["focal"])
        values, sens, render_sums, _probe = run_with_sensitivities(s["o"], probe, s["variables"], s["rays"], False,
                                                              density_noise=0.0)
        return {**mv.header(commit, "models.MipNerfModel.apply(variables, key, rays, randomized=False, "
                                    "white_bkgd=True) with the weights given here, on rays of multicam.json's scene"),
                "model": MODEL, "mlp": MLP, "rays": {"multicam_pixels": [int(i) for i in s["index"]]},
                "params": params_json(s),
                "outputs": mv.tolist(values), "output_layout": "[level][ray][comp_rgb 0..2, acc, distance]",
                "sensitivities": sensitivities_json(sens, render_sums, s["names"])}

    def noise_json(tmp):
        """The model with llff.gin's density noise (1) while randomized: stratified and resampled edges drawn from our
        uniforms (jax.random.uniform given them, as sample.json), the noise from our normals (jax.random.normal given
        them), keyed as our training graph keys batch rays 0..R-1 of step STEP: level l's noise at slot l * 2^24."""
        s = setup(tmp)
        key = {"seed": SEED_OURS, "step": STEP, "first_ray": 0}
        n = MODEL["num_samples"]
        xi = [mv.our_draws(key, N_RAYS, n + 1, 0), mv.our_draws(key, N_RAYS, n + 1, 1)]
        z = [our_normals(mv, key, N_RAYS, n, level) for level in range(2)]
        probe = Probe(s["o"], s["focal"])
        probe.normals = [zl[..., None] for zl in z]
        probe.uniforms = xi
        values, sens, render_sums, probe = run_with_sensitivities(s["o"], probe, s["variables"], s["rays"], True,
                                                                  density_noise=1.0)
        levels = []
        for (raw_rgb, raw_density), r, v in zip(probe.raw, probe.renders, values):
            levels.append({"raw_rgb": mv.tolist(raw_rgb), "raw_density": mv.tolist(raw_density[..., 0]),
                           "t_vals": mv.tolist(r["t_vals"]), "weights": mv.tolist(r["weights"]),
                           "comp_rgb": mv.tolist(v[:, :3]), "acc": mv.tolist(v[:, 3]), "distance": mv.tolist(v[:, 4])})
        return {**mv.header(commit, "models.MipNerfModel.apply(variables, key, rays, randomized=True, white_bkgd=True) "
                                    "with density_noise=1 (llff.gin), model.json's weights and rays; jax.random.uniform "
                                    "given our draws xi (level 0: sample_along_rays, level 1: resampling) and "
                                    "jax.random.normal our normal draws z"),
                "model": {**MODEL, "density_noise": 1.0}, "mlp": MLP, "rays": {"multicam_pixels": [int(i) for i in s["index"]]},
                "key": key, "xi": [mv.tolist(x) for x in xi], "z": [mv.tolist(x) for x in z],
                "levels": levels, "outputs": mv.tolist(values),
                "output_layout": "[level][ray][comp_rgb 0..2, acc, distance]",
                "sensitivities": sensitivities_json(sens, render_sums, s["names"])}

    def adam_json(tmp):
        return train_step_fixture(mv, commit, setup(tmp))

    return {"model.json": model_json, "noise.json": noise_json, "adam.json": adam_json}


def flat_params(tree, names):
    """The flax tree as our flat buffer: per layer kernel [in][out] row-major, then bias (host/mlp/mlp_config.hpp)."""
    dense = tree["params"]["MLP_0"]
    return np.concatenate([np.concatenate([np.asarray(dense[n]["kernel"]).reshape(-1), np.asarray(dense[n]["bias"])])
                           for n in names])


def tree_of(flat, like, names):
    """Our flat buffer back into a tree shaped as `like`."""
    import jax.numpy as jnp
    dense, out, at = like["params"]["MLP_0"], {}, 0
    for n in names:
        k_shape, b_size = dense[n]["kernel"].shape, dense[n]["bias"].shape[0]
        k_size = k_shape[0] * k_shape[1]
        out[n] = {"kernel": jnp.asarray(flat[at:at + k_size].reshape(k_shape)),
                  "bias": jnp.asarray(flat[at + k_size:at + k_size + b_size])}
        at += k_size + b_size
    return {"params": {"MLP_0": out}}


def train_step_fixture(mv, commit, s):
    """train.train_step itself, vmapped over one device (its pmean over 'batch' is then the identity), on the batch of
    model.json with Config(randomized=False) (sampling deterministic, so the model is model.json's) and the official
    defaults otherwise: coarse_loss_mult 0.1, lossmult (disable_multiscale_loss False), weight_decay_mult 0. The
    optimiser it is handed stands in for flax.optim.Adam (STUB below): the state after ADAM_COUNT updates, the moments
    zero but on a subset of the parameters; update number ADAM_COUNT + 1 at the learning rate train.py gives it,
    learning_rate_fn(step) of the official defaults. Two cases: clipping off (the official configs) and grad_max_norm
    at half the gradient's norm."""
    import flax
    import optax
    o = s["o"]
    jax, jnp = o.jax, o.jnp
    adam_count, step = 41, 42  # train.py: init_step = optimizer.state.step + 1, lr = learning_rate_fn(step)

    @flax.struct.dataclass
    class AdamStandIn:
        """flax.optim.Optimizer's face to train_step (target, apply_gradient(grad, learning_rate=)) over optax.adam:
        optax's scale_by_adam is flax 0.3's Adam.apply_param_gradient (m, v decay, bias correction with t = count + 1,
        p - lr * m_hat / (sqrt(v_hat) + eps)). Keeps the gradient it was given."""
        target: object
        mu: object
        nu: object
        count: object
        given_grad: object

        def apply_gradient(self, grad, learning_rate):
            tx = optax.adam(learning_rate, b1=0.9, b2=0.999, eps=1e-8)
            state = (optax.ScaleByAdamState(count=self.count, mu=self.mu, nu=self.nu), optax.EmptyState())
            updates, (adam_state, _) = tx.update(grad, state, self.target)
            return AdamStandIn(target=optax.apply_updates(self.target, updates), mu=adam_state.mu, nu=adam_state.nu,
                               count=adam_state.count, given_grad=grad)

    config_defaults = o.off.utils.Config()
    lr = float(o.off.math.learning_rate_decay(step, lr_init=config_defaults.lr_init, lr_final=config_defaults.lr_final,
                                              max_steps=config_defaults.max_steps,
                                              lr_delay_steps=config_defaults.lr_delay_steps,
                                              lr_delay_mult=config_defaults.lr_delay_mult))
    variables, names = s["variables"], s["names"]
    model = official_model(o, density_noise=0.0)
    batch = {"rays": s["rays"], "pixels": s["pixels"]}

    def run(config, m_flat, v_flat):
        zeros = lambda flat: tree_of(flat, variables, names)
        opt = AdamStandIn(target=variables, mu=zeros(m_flat), nu=zeros(v_flat), count=jnp.asarray(adam_count, jnp.int32),
                          given_grad=zeros(np.zeros_like(m_flat)))
        state = o.off.utils.TrainState(optimizer=opt)
        lead = lambda tree: jax.tree_util.tree_map(lambda x: jnp.asarray(x)[None], tree)
        step_fn = jax.vmap(functools.partial(o.train.train_step, model, config), axis_name="batch",
                           in_axes=(0, 0, 0, None))
        new_state, stats, _ = step_fn(lead(jax.random.PRNGKey(3)), lead(state), lead(batch), lr)
        first = lambda tree: jax.tree_util.tree_map(lambda x: np.asarray(x)[0], tree)
        return first(new_state.optimizer), first(stats)

    n_params = flat_params(variables, names).size
    plain = o.off.utils.Config(randomized=False)
    opt, stats = run(plain, np.zeros(n_params), np.zeros(n_params))
    grad = flat_params({"params": opt.given_grad["params"]}, names)
    # The moments of the subset: as a run would hold them, m ~ g and v ~ g^2 (float32 values).
    rng = np.random.default_rng(mv.SEED + 14)
    state_indices = np.sort(rng.choice(n_params, 384, replace=False))
    m = np.zeros(n_params)
    v = np.zeros(n_params)
    m[state_indices] = np.asarray(grad[state_indices] * rng.uniform(-1.0, 2.0, state_indices.size), np.float32)
    v[state_indices] = np.asarray(grad[state_indices]**2 * rng.uniform(0.5, 3.0, state_indices.size), np.float32)
    zero_state = np.setdiff1d(np.arange(n_params), state_indices)
    compared = np.sort(np.concatenate([state_indices, rng.choice(zero_state, 128, replace=False)]))
    cases = []
    for grad_max_norm in [0.0, 0.5 * float(stats.grad_norm)]:
        config = o.off.utils.Config(randomized=False, grad_max_norm=grad_max_norm)
        opt_case, stats_case = run(config, m, v)
        new_flat = flat_params({"params": opt_case.target["params"]}, names)
        cases.append({"grad_max_norm": grad_max_norm, "grad_max_val": float(config.grad_max_val),
                      "grad_norm": float(stats_case.grad_norm), "grad_norm_clipped": float(stats_case.grad_norm_clipped),
                      "new_params": mv.tolist(new_flat[compared]),
                      "new_m": mv.tolist(flat_params({"params": opt_case.mu["params"]}, names)[compared]),
                      "new_v": mv.tolist(flat_params({"params": opt_case.nu["params"]}, names)[compared])})
    return {**mv.header(commit, "train.train_step(model, Config(randomized=False[, grad_max_norm]), rng, state, batch, "
                                "lr), vmapped over one device, on model.json's weights and batch; the optimiser "
                                "stands in for flax.optim.Adam (optax.adam, the same update)"),
            "model": {**MODEL, "density_noise": 0.0}, "mlp": MLP,
            "rays": {"multicam_pixels": [int(i) for i in s["index"]]},
            "config": {"coarse_loss_mult": plain.coarse_loss_mult, "disable_multiscale_loss": plain.disable_multiscale_loss,
                       "weight_decay_mult": plain.weight_decay_mult, "lr_init": plain.lr_init, "lr_final": plain.lr_final,
                       "max_steps": plain.max_steps, "lr_delay_steps": plain.lr_delay_steps,
                       "lr_delay_mult": plain.lr_delay_mult, "randomized": plain.randomized,
                       "white_bkgd": plain.white_bkgd},
            "loss": float(stats.loss), "losses": mv.tolist(stats.losses), "weight_l2": float(stats.weight_l2),
            "grad": short32(grad), "grad_note": "the gradient of loss_fn before clipping, as float32 values",
            "adam": {"count_before": adam_count, "step": step, "lr": lr, "beta1": 0.9, "beta2": 0.999, "eps": 1e-8,
                     "state_indices": [int(i) for i in state_indices], "m": short32(m[state_indices]),
                     "v": short32(v[state_indices]), "compared_indices": [int(i) for i in compared]},
            "cases": cases}
