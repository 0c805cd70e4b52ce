"""The official google/mipnerf code, run for comparison (never copied): what every study that runs it shares.

The worker side runs in a python that has JAX (the studies' venv, or a GPU image's): install_stubs() puts in the
import-time stand-ins the official code needs with modern jax/flax (STUBS lists them for the records), Official
holds the official model, train_step and render in that process, serve_requests() is a worker's loop (one JSON
request per stdin line, one JSON reply per stdout line), bind_gin() configures the official model through gin,
llff_split() runs the official LLFF loader without its batch thread. The orchestrator side: Worker drives such a
process, official_settings() maps our preset's config to the official MipNerfModel/MLP/Config settings (checked by
check_computable(), not assumed; model_settings() the model's and MLP's part), ensure_venv() makes the venv once,
official_commit() names the checkout.

Used by bench/studies/vs_official.py, vs_official_llff.py, same_weights_llff.py and official_step.py
(scripts/device-check.sh). Standard library at import; JAX, numpy and the official code are imported inside the
functions that run them.
"""

import json
import os
import platform
import subprocess
import sys
import time


class OfficialError(Exception):
    """What a study reports in one line and stops on: settings without an official equivalent, a missing checkout, a
    worker that died or failed a request."""


PIP_PACKAGES = ["jax[cpu]", "flax", "optax", "gin-config", "numpy", "pillow"]

# Import-time stand-ins the official code needs with modern jax/flax (installed in the worker only).
STUBS = [
    ("flax.nn", "module with relu/sigmoid/softplus from flax.linen; utils.py registers them with gin "
                "(old flax.nn was removed from flax)"),
    ("flax.optim", "module whose Optimizer is a flax.struct dataclass (target, opt_state) with "
                   "apply_gradient(grad, learning_rate) running optax.adam (b1 0.9, b2 0.999, eps 1e-8 = "
                   "flax.optim.Adam's defaults) through optax.inject_hyperparams"),
    ("jax.tree_map", "= jax.tree_util.tree_map (removed from jax; used by utils.shard)"),
    ("flax.metrics.tensorboard", "empty SummaryWriter (needs tensorflow; train.py imports it, never used here)"),
    ("cv2", "empty module (internal/datasets.py imports it; its loader is not used: Blender supports only "
            "factor 0 or 2)"),
    ("matplotlib, matplotlib.cm", "empty modules (internal/vis.py imports them; not used here)"),
    ("absl flags", "train.py defines its flags at import; they are parsed with no arguments"),
]


DEFAULT_VENV = os.path.join(os.path.expanduser("~"), ".cache", "mipnerf-cl", "vs-official-venv")


def add_official_arguments(parser, repo, out_dir):
    """The arguments every study that runs the official code beside ours takes (vs_official.py,
    vs_official_llff.py): the checkout, our executable, the venv, the tree rule, where the results go."""
    p = parser
    p.add_argument("--official", help="checkout of github:google/mipnerf (contains train.py and internal/)")
    p.add_argument("--official-commit", help="commit of --official when it is not a git work tree (e.g. a git archive)")
    p.add_argument("--bin", default=os.path.join(repo, "build", "mipnerf-cl"), help="mipnerf-cl executable")
    p.add_argument("--venv", default=DEFAULT_VENV, help="virtual environment for the official code")
    p.add_argument("--python", default=sys.executable, help="python used to create the venv")
    p.add_argument("--allow-dirty", action="store_true",
                   help="run although the mipnerf-cl checkout has uncommitted changes (their sha256 is recorded)")
    p.add_argument("--device-name", default="pocl_cpu", help="suffix of the results files")
    p.add_argument("--out-dir", default=out_dir)
    p.add_argument("--note", action="append", default=[], help="a line for the results' Notes (repeatable)")
    p.add_argument("--report-only", metavar="JSON",
                   help="regenerate the .md beside a results .json from it (keeping its hand-written notes); "
                        "measure nothing")


def check_official_checkout(official):
    """Raises OfficialError unless `official` is a google/mipnerf checkout (the folder holding internal/models.py)."""
    if not official:
        raise OfficialError("pass --official DIR, a checkout of github:google/mipnerf (the folder holding train.py)")
    if not os.path.isfile(os.path.join(official, "internal", "models.py")):
        raise OfficialError(f"--official {official}: no internal/models.py there; pass the google/mipnerf checkout")


def check_computable(c, required):
    """Raises OfficialError unless our config `c` is one the official MipNerfModel computes: the official skip rule,
    and every setting in `required` (name: the value the official model has) as required. The concatenated-PE
    variant's covariance encoding must be off (0, as in MipNerfModel) where the config has it."""
    depth, skip = c["mlp_depth"], c["mlp_skip"]
    # Official MLP: concat after layer i when i % skip_layer == 0 and i > 0; ours after layer mlp_skip.
    if [i for i in range(depth) if i > 0 and i % skip == 0] != [skip]:
        raise OfficialError(f"mlp_depth {depth} with mlp_skip {skip} has no official equivalent")
    if "cov_max_deg" in c:
        required = dict(required, cov_max_deg=0)
    for key, want in required.items():
        if c.get(key) != want:
            raise OfficialError(f"our setting {key} = {c.get(key)} is not what the official MipNerfModel computes "
                                f"(it needs {want})")


def model_settings(c, density_noise):
    """The official MipNerfModel's and MLP's gin settings for our config `c` (checked by check_computable first);
    `density_noise`: the official model's (it only acts on randomized renders)."""
    model = dict(num_samples=c["num_samples"], num_levels=c["num_levels"],
                 resample_padding=c["resample_padding"], stop_level_grad=True,
                 use_viewdirs=c["view_dependence"], lindisp=c["lindisp"], ray_shape=c["ray_shape"],
                 min_deg_point=c["pos_min_deg"], max_deg_point=c["pos_max_deg"], deg_view=c["view_max_deg"],
                 density_noise=density_noise, density_bias=c["density_bias"], rgb_padding=c["rgb_padding"],
                 disable_integration=not c["integrated_encoding"])
    mlp = dict(net_depth=c["mlp_depth"], net_width=c["mlp_width"], net_depth_condition=1,
               net_width_condition=c["view_branch_width"], skip_layer=c["mlp_skip"])
    return model, mlp


def official_settings(our_config):
    """The official model's and config's settings equal to our preset's (checked, not assumed)."""
    c = our_config
    check_computable(c, {"single_mlp": True, "pos_identity": False, "multiscale": False, "resample_blur": True,
                         "density_activation": "softplus", "jitter_pixels": False, "variant": "mipnerf"})
    model, mlp = model_settings(c, density_noise=0.0)
    config = dict(batch_size=c["batch_size"], coarse_loss_mult=c["coarse_loss_mult"],
                  randomized=c["randomized"], white_bkgd=c["background"] == "white",
                  near=c["near"] or 2.0, far=c["far"] or 6.0, lr_init=c["lr_init"], lr_final=c["lr_final"],
                  lr_delay_steps=c["lr_warmup_steps"], lr_delay_mult=c["lr_warmup_mult"],
                  grad_max_norm=c["grad_max_norm"], disable_multiscale_loss=not c["area_loss"],
                  batching="all_images", max_steps=1000000)
    return model, mlp, config



def official_commit(official):
    r = subprocess.run(["git", "--no-optional-locks", "-C", official, "rev-parse", "HEAD"], capture_output=True,
                       text=True)
    return r.stdout.strip() if r.returncode == 0 else "unknown (not a git work tree)"




def ensure_venv(venv, python):
    """The venv's python, the venv created with `python` and the official code's dependencies installed from PyPI
    (once: a marker file says it is ready)."""
    py = os.path.join(venv, "bin", "python")
    marker = os.path.join(venv, ".vs_official_ready")
    if os.path.exists(marker):
        return py
    print(f"creating {venv} and installing {' '.join(PIP_PACKAGES)} from PyPI", flush=True)
    subprocess.run([python, "-m", "venv", venv], check=True)
    subprocess.run([py, "-m", "pip", "install", "-q"] + PIP_PACKAGES, check=True)
    open(marker, "w").close()
    return py


class Worker:
    """A worker process (a study run with --worker in the venv's python), driven by one JSON line per request."""

    def __init__(self, command):
        self.proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def call(self, **request):
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise OfficialError(f"the official worker died during {request.get('cmd')} (see its stderr above)")
        reply = json.loads(line)
        if "error" in reply:
            raise OfficialError(f"the official worker failed during {request.get('cmd')}: {reply['error']}")
        return reply

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


# ---- worker side (runs where JAX is; imports jax and the official code) ----

INSTALLED_COMPAT_SHIMS = []  # install_compat_shims' names, in this process


def install_compat_shims():
    """Stand-ins for what newer jax/flax releases removed and the official train.py still touches at import, put in
    only where missing (none with the studies' JAX 0.10); their names join INSTALLED_COMPAT_SHIMS (recorded in the
    results) and are returned."""
    import types
    import jax
    shims = []
    if not hasattr(jax.config, "parse_flags_with_absl"):
        try:
            jax.config.parse_flags_with_absl = lambda *a, **k: None
            shims.append("jax.config.parse_flags_with_absl (no-op)")
        except Exception:
            pass
    try:
        import flax.training.checkpoints  # noqa: F401  (train.py imports it; never used in a step)
    except Exception:
        import flax.training
        module = types.ModuleType("flax.training.checkpoints")
        sys.modules["flax.training.checkpoints"] = flax.training.checkpoints = module
        shims.append("flax.training.checkpoints (empty module: it did not import)")
    INSTALLED_COMPAT_SHIMS.extend(s for s in shims if s not in INSTALLED_COMPAT_SHIMS)
    return shims


def install_stubs():
    import types
    import jax
    import optax
    import flax
    from flax import linen, struct

    sys.modules["flax.nn"] = flax.nn = types.SimpleNamespace(
        relu=linen.relu, sigmoid=linen.sigmoid, softplus=linen.softplus)

    tx = optax.inject_hyperparams(optax.adam)(learning_rate=0.0, b1=0.9, b2=0.999, eps=1e-8)

    @struct.dataclass
    class Optimizer:
        target: object
        opt_state: object

        @classmethod
        def create(cls, target):
            return cls(target=target, opt_state=tx.init(target))

        def apply_gradient(self, grad, learning_rate):
            state = self.opt_state
            state.hyperparams["learning_rate"] = learning_rate
            updates, state = tx.update(grad, state, self.target)
            return self.replace(target=optax.apply_updates(self.target, updates), opt_state=state)

    optim = types.ModuleType("flax.optim")
    optim.Optimizer = Optimizer
    sys.modules["flax.optim"] = flax.optim = optim
    if not hasattr(jax, "tree_map"):
        jax.tree_map = jax.tree_util.tree_map
    tb = types.ModuleType("flax.metrics.tensorboard")
    tb.SummaryWriter = object
    sys.modules["flax.metrics.tensorboard"] = tb
    for name in ["cv2", "matplotlib", "matplotlib.cm"]:
        sys.modules[name] = types.ModuleType(name)
    install_compat_shims()
    return Optimizer



class Official:
    """The official model, train_step and render in this process."""

    def __init__(self, official, data, factor):
        sys.path.insert(0, os.path.abspath(official))
        self.Optimizer = install_stubs()
        import numpy as np
        from absl import flags
        import train  # the official train.py: defines its flags, gives train_step
        from internal import datasets, models, utils
        flags.FLAGS(["train"])  # parse no arguments, so FLAGS defaults are readable
        self.np, self.train, self.models, self.utils = np, train, models, utils
        self.data, self.factor, self.datasets = data, factor, datasets
        self.loaded = None

    def versions(self):
        import jax, jaxlib, flax, optax, numpy, gin
        return {"python": platform.python_version(), "jax": jax.__version__, "jaxlib": jaxlib.__version__,
                "flax": flax.__version__, "optax": optax.__version__, "numpy": numpy.__version__,
                "gin": getattr(gin, "__version__", "installed"), "jax_devices": str(jax.devices())}

    def setup(self, model, mlp, config):
        import functools
        import gin
        import jax
        from jax import random
        bind_gin(model, mlp)
        cfg = self.utils.Config(dataset_loader="blender", **config)
        self.config, self.rng = cfg, random.PRNGKey(20200823)
        if self.loaded != (cfg.near, cfg.far):
            self.views, images = load_blender(self.np, self.datasets, self.data, self.factor, cfg.near, cfg.far)
            flat = self.utils.namedtuple_map(lambda r: r.reshape(-1, r.shape[-1]), self.views)
            self.scene, self.loaded = (flat, images.reshape(-1, 3)), (cfg.near, cfg.far)
        self.batches = [self.batch(cfg.batch_size, seed) for seed in range(8)]
        key, self.rng = random.split(self.rng)
        self.model, variables = self.models.construct_mipnerf(key, jax.device_put(self.batches[0]))
        params = sum(int(x.size) for x in jax.tree_util.tree_leaves(variables))
        state = self.utils.TrainState(optimizer=self.Optimizer.create(variables))
        self.state = jax.tree_util.tree_map(lambda x: jax.numpy.asarray(x)[None], state)
        self.pstep = jax.pmap(functools.partial(self.train.train_step, self.model, cfg), axis_name="batch",
                              in_axes=(0, 0, 0, None), donate_argnums=(2,))
        self.keys = random.split(self.rng, jax.local_device_count())
        self.lr = functools.partial(self.train.math.learning_rate_decay, lr_init=cfg.lr_init,
                                    lr_final=cfg.lr_final, max_steps=cfg.max_steps,
                                    lr_delay_steps=cfg.lr_delay_steps, lr_delay_mult=cfg.lr_delay_mult)
        self.step_index, self.render_pfn = 1, None
        t0 = time.time()
        self.steps(2)  # compile + one warm-up step
        return {"parameters": params, "compile_s": time.time() - t0}

    def batch(self, n, seed):
        """Random rays over all training images, utils.shard'ed on the host (as datasets.py does)."""
        np = self.np
        rays, pixels = self.scene
        idx = np.random.RandomState(seed).randint(0, pixels.shape[0], (n,))
        b = {"pixels": pixels[idx], "rays": self.utils.namedtuple_map(lambda r: r[idx], rays)}
        return self.utils.shard(b)

    def steps(self, n):
        import jax
        out = []
        for _ in range(n):
            # a fresh device copy each step: train_step donates its batch (donate_argnums as train.py)
            b = jax.block_until_ready(jax.device_put(self.batches[self.step_index % len(self.batches)]))
            t0 = time.perf_counter()
            self.state, stats, self.keys = self.pstep(self.keys, self.state, b, self.lr(self.step_index))
            jax.block_until_ready((self.state, stats))
            out.append(time.perf_counter() - t0)
            self.step_index += 1
        return out

    def render(self, reps, chunk):
        """Warm renders of the first training view through models.render_image (first call apart)."""
        import jax
        rays = self.view_rays(0)
        t0 = time.perf_counter()
        jax.block_until_ready(self.render_view(rays, chunk))
        first = time.perf_counter() - t0
        seconds = []
        for _ in range(reps):
            t0 = time.perf_counter()
            jax.block_until_ready(self.render_view(rays, chunk))
            seconds.append(time.perf_counter() - t0)
        h, w = rays.origins.shape[:2]
        return {"seconds": seconds, "first_call_s": first, "megapixels": h * w / 1e6}

    def train_and_score(self, model, mlp, config, steps, val_views, chunk):
        """Train from scratch for `steps` (fresh random batches each step, made in the loop), then the
        mean PSNR of the first `val_views` val views (eval: randomized = False)."""
        import jax
        import numpy as np
        setup = self.setup(model, mlp, dict(config, max_steps=steps))  # compiles (2 steps taken) ...
        self.setup_state_fresh()  # ... then fresh parameters and Adam state: training starts at step 1
        rng = np.random.RandomState(20201473)
        t0 = time.time()
        for step in range(1, steps + 1):
            idx = rng.randint(0, self.scene[1].shape[0], (self.config.batch_size,))
            b = jax.device_put(self.utils.shard({"pixels": self.scene[1][idx],
                                                 "rays": self.utils.namedtuple_map(lambda r: r[idx], self.scene[0])}))
            self.state, stats, self.keys = self.pstep(self.keys, self.state, b, self.lr(step))
        jax.block_until_ready(self.state)
        train_s = time.time() - t0
        views, images = load_blender(np, self.datasets, self.data, self.factor, self.config.near,
                                     self.config.far, split="val")
        psnrs = []
        for i in range(val_views):
            rays = self.utils.namedtuple_map(lambda r: jax.numpy.asarray(r[i]), views)
            rgb = np.asarray(self.render_view(rays, chunk))
            psnrs.append(float(self.train.math.mse_to_psnr(((rgb - images[i]) ** 2).mean())))
        return {"train_seconds": train_s, "compile_s": setup["compile_s"], "psnrs": psnrs,
                "mean_psnr": sum(psnrs) / len(psnrs), "steps": steps}

    def setup_state_fresh(self):
        """Fresh parameters and Adam state for the already compiled step (same shapes: no recompile)."""
        import jax
        from jax import random
        key, self.rng = random.split(random.PRNGKey(20200823))
        _, variables = self.models.construct_mipnerf(key, jax.device_put(self.batches[0]))
        state = self.utils.TrainState(optimizer=self.Optimizer.create(variables))
        self.state = jax.tree_util.tree_map(lambda x: jax.numpy.asarray(x)[None], state)
        self.keys = random.split(self.rng, jax.local_device_count())

    def render_view(self, rays, chunk):
        import functools
        import jax
        from jax import random
        model, cfg = self.model, self.config

        def render_eval_fn(variables, _, rays):  # as in train.py
            return jax.lax.all_gather(model.apply(variables, random.PRNGKey(0), rays, randomized=False,
                                                  white_bkgd=cfg.white_bkgd), axis_name="batch")

        if getattr(self, "render_pfn", None) is None:
            self.render_pfn = jax.pmap(render_eval_fn, in_axes=(None, None, 0), donate_argnums=(2,),
                                       axis_name="batch")
        variables = jax.tree_util.tree_map(lambda x: x[0], self.state).optimizer.target
        rgb, _, _ = self.models.render_image(functools.partial(self.render_pfn, variables), rays, self.keys[0],
                                             chunk=chunk)
        return rgb

    def view_rays(self, index):
        import jax.numpy as jnp
        return self.utils.namedtuple_map(lambda r: jnp.asarray(r[index]), self.views)



def gin_value(v):
    return repr(v) if isinstance(v, str) else ("True" if v is True else "False" if v is False else str(v))


def bind_gin(model, mlp):
    """Configures the official MipNerfModel and MLP through gin, as its configs/*.gin do (earlier bindings
    cleared): `model` and `mlp` as model_settings returns them."""
    import gin
    gin.clear_config()
    gin.parse_config([f"MipNerfModel.{k} = {gin_value(v)}" for k, v in model.items()] +
                     [f"MLP.{k} = {gin_value(v)}" for k, v in mlp.items()])


def llff_split(datasets, data, cfg, split, first_views=None):
    """The official LLFF loader's rays and images of a split (internal/datasets.py LLFF on an object made without
    Dataset.__init__, which would start its batch thread); the test split's 120-pose video spiral is dropped before
    its rays are made (only videos use it, and it would cost GBs of rays). `first_views`: keep only that many
    cameras, the rays of the rest never made. `cfg`: a utils.Config (factor, near, far, llffhold, spherify)."""
    ds = datasets.LLFF.__new__(datasets.LLFF)
    ds.split, ds.data_dir, ds.near, ds.far = split, data, cfg.near, cfg.far
    ds._load_renderings(cfg)
    if split == "test":
        ds.render_poses = ds.render_poses[:0]
    if first_views is not None:
        ds.camtoworlds, ds.images = ds.camtoworlds[:first_views], ds.images[:first_views]
    ds._generate_rays()
    return ds



def load_blender(np, datasets, data, factor, near, far, split="train"):
    """The scene's training rays by the official Blender._generate_rays (run on an object without its
    loader thread), with the images box-downsampled by `factor` and composited on white here
    (the official loader supports factor 0 or 2 only)."""
    from PIL import Image
    with open(os.path.join(data, f"transforms_{split}.json")) as f:
        meta = json.load(f)
    images, cams = [], []
    for frame in meta["frames"]:
        img = np.asarray(Image.open(os.path.join(data, frame["file_path"] + ".png")), dtype=np.float32) / 255.0
        h, w = img.shape[0] // factor, img.shape[1] // factor
        img = img[:h * factor, :w * factor].reshape(h, factor, w, factor, -1).mean(axis=(1, 3))
        images.append(img[..., :3] * img[..., 3:] + (1.0 - img[..., 3:]))
        cams.append(np.array(frame["transform_matrix"], dtype=np.float32))
    scene = datasets.Blender.__new__(datasets.Blender)
    scene.images, scene.camtoworlds = np.stack(images), np.stack(cams)
    scene.h, scene.w = scene.images.shape[1:3]
    scene.focal = 0.5 * scene.w / np.tan(0.5 * float(meta["camera_angle_x"]))
    scene.near, scene.far = near, far
    scene._generate_rays()
    return scene.rays, scene.images



def train_once(worker, path, request, recorded):
    """A training request to `worker`, once: its reply (with `recorded` added and the call's wall time) is kept as JSON
    at `path` and read back on a later call, so an interrupted study resumes where it stopped."""
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    before = time.time()
    record = worker.call(**request)
    record.update(recorded, this_call={"wall_seconds": time.time() - before})
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(record, f, indent=2)
    return record


def side_summary(runs):
    """One side's test PSNRs and train seconds over its runs (dicts with mean_psnr and train_seconds)."""
    import statistics
    psnrs = [r["mean_psnr"] for r in runs]
    secs = [r["train_seconds"] for r in runs]
    return {"runs": len(runs), "mean_psnr": statistics.mean(psnrs),
            "sd_psnr": statistics.stdev(psnrs) if len(psnrs) > 1 else 0.0, "min_psnr": min(psnrs),
            "max_psnr": max(psnrs), "median_train_seconds": statistics.median(secs), "min_train_seconds": min(secs),
            "max_train_seconds": max(secs)}


def serve_requests(make_official, handlers):
    """The worker's loop: one JSON request per stdin line, one JSON reply per stdout line; handlers maps a request's
    cmd to handler(official, request). A failure (importing the official code, or a request) is a reply with
    "error", its traceback on stderr."""
    try:
        off = make_official()
    except Exception as e:  # report the first failure to the orchestrator in one line
        import traceback
        traceback.print_exc()
        print(json.dumps({"error": f"importing the official code: {e!r}"}), flush=True)
        return
    for line in sys.stdin:
        req = json.loads(line)
        try:
            cmd = req.pop("cmd")
            handler = handlers.get(cmd)
            reply = handler(off, req) if handler else {"error": f"unknown request {cmd}"}
        except Exception as e:
            import traceback
            traceback.print_exc()
            reply = {"error": repr(e)}
        print(json.dumps(reply), flush=True)
