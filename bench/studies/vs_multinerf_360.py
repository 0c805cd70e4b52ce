#!/usr/bin/env python3
"""mipnerf-cl's mip-NeRF 360 against the official google-research/multinerf (JAX) on one 360-degree capture, at equal
steps: test PSNR and training time of each (issue 45, deliverable 4).

THE MEASUREMENT (about an hour on 2 CPU cores at the defaults):

  python3 bench/studies/vs_multinerf_360.py --multinerf /tmp/multinerf --multinerf-commit 5b4d4f6 --steps 500 --seeds 3

What it does, in one run on one machine:
  * The capture: `make-scene --unbounded` (40 views all around a textured object on a ground, with a backdrop; 5 held
    out, every 8th) at its images_4/ size (64x48), written once as a transforms.json folder (WORK/capture: the poses in
    OpenGL axes from poses_bounds.npy, the intrinsics at that size, images/ = images_4/) that both sides read.
  * Ours: `train --preset mipnerf360` (multinerf's configs/360.gin exactly) with the sizes scaled down for two cores
    (--set overrides, SIZES below: the NeRF MLP 4x128 with a 128 bottleneck and a 64-wide view branch, one shared
    proposal MLP 4x64, rounds of 32, 512 rays a step, a 50-step warm-up), `steps` = --steps (the schedule's length
    too), every held-out view scored at the end (`val_views=0`). The parameter counts must agree but for our proposal
    network's colour head, which multinerf's PropMLP (disable_rgb) does not create and ours never trains.
  * Official: multinerf's own Model (internal/models.py, gin-configured with the same sizes, derived from our run's
    config.json and checked: the parameter counts must agree), its train_step (internal/train_utils.py: its loss,
    clipping, Adam, learning-rate schedule, train_frac), its Dataset (internal/datasets.py LLFF, which reads a
    transforms.json when there is no COLMAP model; its batches), its render_image and mse_to_psnr for the held-out
    views (llffhold 8: the same 5 views), as train.py and eval.py run them.
  * The one change on the official side: camera_utils.transform_poses_pca, multinerf's normalisation of a 360-degree
    capture (rotate to the principal axes, scale the cameras into [-1, 1]^3), is replaced by ours (data::
    world_around_cameras: centre where the optical axes meet, cameras at RMS distance 1, no rotation) so that both
    models see the same world: the contraction and near = 0.2 depend on its scale. Recorded in the results.
  * Sides alternate who goes first; seeds 0..--seeds-1; every finished run is kept in --work (an interrupted study
    resumes). Train seconds: ours as `train` reports them; the official's over its steps after the jit compile.

The official code runs in a worker (this file with --worker) in the venv of bench/lib/official.py (jax[cpu], flax,
optax, gin-config, numpy, pillow; plus scipy, which multinerf's camera_utils imports), with import-time stand-ins for
the modules multinerf imports but this path never calls (STUBS). The checkout is only read.
"""

import argparse
import datetime
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import read_json, run, train_resumable  # noqa: E402
from lib.machine import between, snapshot  # noqa: E402
from lib.official import (DEFAULT_VENV, OfficialError, Worker, ensure_venv, serve_requests, side_summary,  # noqa: E402
                          train_once)
from lib.provenance import REPO, cpu_model, tree_state  # noqa: E402

NAME = "vs_multinerf_360"
EXTRA_PACKAGES = ["scipy"]

# mip-NeRF 360 (the mipnerf360 preset) at a size two cores train in minutes; everything else is 360.gin's.
# The warm-up scaled with the run: 360.gin's 512 steps of 250,000 would span a whole 500-step run.
SIZES = {"mlp_depth": 4, "mlp_width": 128, "mlp_skip": 4, "bottleneck_width": 128, "view_branch_width": 64,
         "proposal_mlp_width": 64, "proposal_samples": 32, "num_samples": 32, "batch_size": 512,
         "lr_warmup_steps": 50}

STUBS = [
    ("cv2", "empty module (internal/datasets.py imports it; only its unused loaders call it)"),
    ("dm_pix", "empty module (internal/image.py imports it for SSIM, not computed here)"),
    ("rawpy", "empty module (internal/raw_utils.py imports it; RawNeRF only)"),
    ("pycolmap", "module with an empty SceneManager class (datasets.py subclasses it; the capture has no COLMAP "
                 "model, so the loader reads transforms.json)"),
    ("jax.host_id", "= jax.process_index (removed from jax)"),
    ("camera_utils.transform_poses_pca", "replaced by data::world_around_cameras' normalisation (see the docstring)"),
]


def fail(message):
    sys.exit(f"vs_multinerf_360.py: {message}")


# ---------------------------------------------------------------------------------------------- orchestrator side

def make_capture(args, worker, log):
    scene = os.path.join(args.work, "scene")
    if not os.path.exists(os.path.join(scene, "poses_bounds.npy")):
        run([args.bin, "make-scene", scene, "--unbounded"], log)
    capture = os.path.join(args.work, "capture")
    if not os.path.exists(os.path.join(capture, "transforms.json")):
        worker.call(cmd="prepare", scene=scene, factor=4, out=capture)
    return capture


def our_settings(steps, seed):
    settings = dict(SIZES)
    # near and far as 360.gin's (the preset's defaults for an unbounded run), given so the official side reads them
    settings.update(factor=1, near=0.2, far=1e6, steps=steps, seed=seed, val_every=0, val_views=0,
                    checkpoint_every=steps)
    return settings


def train_ours(args, capture, steps, seed, log):
    out = os.path.join(args.work, "ours", f"steps{steps}_seed{seed}")
    summary, command = train_resumable(args.bin, capture, out, "mipnerf360", "mipnerf", our_settings(steps, seed), log)
    config = read_json(os.path.join(out, "config.json"))
    val = summary["val"]
    return {"steps": summary["steps"], "seed": seed, "train_seconds": summary["train_seconds"],
            "mean_psnr": val["mean_psnr"], "views": val["views"], "mean_ssim": val.get("mean_ssim"),
            "render_s_per_mp": val.get("render_seconds_per_megapixel"), "device": summary.get("device"),
            "parameters": summary.get("parameters"), "scene_effects": config.get("scene_effects"),
            "command": " ".join(command[1:])}, config


def official_settings(config, steps):
    """multinerf's gin bindings and Config for our run's config.json, each value read from it (or refused)."""
    expect = {"sampler": "proposal", "unbounded": True, "opaque_background": True, "proposal_mlp_shared": True,
              "weight_init": "he_uniform", "data_loss": "charbonnier", "loss_channel_mean": True,
              "view_dependence": True, "proposal_rounds": 2, "basis_subdivisions": 2}
    for key, want in expect.items():
        if config.get(key) != want:
            fail(f"our run's {key} = {config.get(key)}; the official mip-NeRF 360 has {want}")
    mlp = {"warp_fn": "@coord.contract", "disable_density_normals": True, "basis_subdivisions": 2,
           "max_deg_point": config["pos_max_deg"], "skip_layer": config["mlp_skip"]}
    bindings = {
        "Model": {"num_prop_samples": config["proposal_samples"], "num_nerf_samples": config["num_samples"],
                  "num_levels": config["proposal_rounds"] + 1, "raydist_fn": "@jnp.reciprocal",
                  "opaque_background": True, "anneal_slope": config["anneal_slope"]},
        "PropMLP": dict(mlp, net_depth=config["proposal_mlp_depth"], net_width=config["proposal_mlp_width"],
                        disable_rgb=True),
        "NerfMLP": dict(mlp, net_depth=config["mlp_depth"], net_width=config["mlp_width"],
                        bottleneck_width=config["bottleneck_width"], net_width_viewdirs=config["view_branch_width"],
                        deg_view=config["view_max_deg"]),
    }
    cfg = {"dataset_loader": "llff", "factor": 0, "llffhold": 8, "forward_facing": False,
           "near": config["near"], "far": config["far"], "batch_size": config["batch_size"], "max_steps": steps,
           "lr_init": config["lr_init"], "lr_final": config["lr_final"], "lr_delay_steps": config["lr_warmup_steps"],
           "lr_delay_mult": config["lr_warmup_mult"], "adam_beta1": 0.9, "adam_beta2": config["adam_beta2"],
           "adam_eps": config["adam_epsilon"], "grad_max_norm": config["grad_max_norm"], "data_loss_type": "charb",
           "charb_padding": config["charb_padding"], "distortion_loss_mult": config["distortion_mult"],
           "interlevel_loss_mult": 1.0}
    return bindings, cfg


def official_run(args, worker, capture, config, steps, seed):
    bindings, cfg = official_settings(config, steps)
    return train_once(worker, os.path.join(args.work, "official", f"steps{steps}_seed{seed}.json"),
                      {"cmd": "train", "capture": capture, "bindings": bindings, "config": cfg, "steps": steps,
                       "seed": seed},
                      {"steps": steps, "seed": seed, "bindings": bindings, "config": cfg})


def orchestrate(args):
    state = tree_state()
    if state["dirty"] and not args.allow_dirty:
        fail("the checkout has uncommitted changes (figures must name a commit): commit, or --allow-dirty")
    state["allow_dirty"] = args.allow_dirty
    py = ensure_venv(args.venv, args.python)
    run([py, "-m", "pip", "install", "-q"] + EXTRA_PACKAGES, os.path.join(args.work, "pip.log"))
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "ours.log")
    worker = Worker([py, os.path.abspath(__file__), "--worker", "--multinerf", args.multinerf])
    versions = worker.call(cmd="versions")
    capture = make_capture(args, worker, log)
    pairs = []
    for seed in range(args.seeds):
        order = ["ours", "official"] if seed % 2 == 0 else ["official", "ours"]
        snap = snapshot(worker)
        entry = {"seed": seed, "steps": args.steps, "order": order}
        config = None
        for side in order:
            if side == "ours":
                entry["ours"], config = train_ours(args, capture, args.steps, seed, log)
            else:
                config = config or our_config(args, capture, log)
                entry["official"] = official_run(args, worker, capture, config, args.steps, seed)
        entry["conditions"] = between(snap, snapshot(worker))
        extra = unused_colour_head(config)
        if entry["ours"]["parameters"] != entry["official"]["parameters"] + extra:
            fail(f"parameter counts differ: ours {entry['ours']['parameters']}, official "
                 f"{entry['official']['parameters']} (+ {extra} in our proposal network's unused colour head)")
        entry["unused_colour_head_parameters"] = extra
        pairs.append(entry)
        print(f"seed {seed}: ours {entry['ours']['mean_psnr']:.2f} dB in {entry['ours']['train_seconds']:.0f} s, "
              f"official {entry['official']['mean_psnr']:.2f} dB in {entry['official']['train_seconds']:.0f} s",
              flush=True)
        write(args, versions, state, pairs)
    worker.close()


def unused_colour_head(config):
    """Parameters our proposal network holds that multinerf's PropMLP (disable_rgb) does not create: its colour head
    (width x 3 weights + 3 biases), which nothing reads and whose gradient is zero (graph/graph.cpp forward_level), so
    it never changes and trains nothing. One head for the shared network."""
    networks = 1 if config["proposal_mlp_shared"] else config["proposal_rounds"]
    return networks * (config["proposal_mlp_width"] * 3 + 3)


def our_config(args, capture, log):
    """Our configuration for the capture before our first run: a 1-step probe (the network, schedule and scene
    effects do not depend on the seed; the step count is set by the official side's max_steps)."""
    out = os.path.join(args.work, "ours", "config_probe")
    if not os.path.exists(os.path.join(out, "config.json")):
        settings = our_settings(1, 0)
        settings["val_views"] = 1
        train_resumable(args.bin, capture, out, "mipnerf360", "mipnerf", settings, log)
    return read_json(os.path.join(out, "config.json"))


def write(args, versions, state, pairs):
    ours, official = side_summary([p["ours"] for p in pairs]), side_summary([p["official"] for p in pairs])
    doc = {"what": "mip-NeRF 360 (360.gin at reduced sizes) trained by mipnerf-cl and by multinerf on one 360-degree "
                   "capture, test PSNR at equal steps",
           "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "capture": "make-scene --unbounded, images_4 (64x48), 35 train / 5 test views (llffhold 8)",
           "steps": args.steps, "seeds": args.seeds, "sizes": SIZES, "checkout": state,
           "multinerf_commit": args.multinerf_commit, "cpu": cpu_model(), "versions": versions, "stubs": STUBS,
           "pairs": pairs,
           "summary": {"ours": ours, "official": official,
                       "psnr_difference_per_seed": [p["ours"]["mean_psnr"] - p["official"]["mean_psnr"]
                                                    for p in pairs],
                       "train_seconds_ratio_per_seed": [p["official"]["train_seconds"] / p["ours"]["train_seconds"]
                                                        for p in pairs]}}
    os.makedirs(args.out_dir, exist_ok=True)
    base = os.path.join(args.out_dir, args.name)
    with open(base + ".json", "w") as f:
        json.dump(doc, f, indent=2)
    report_md.write_report(base + ".md", markdown(doc, args.name),
                           f"python3 bench/studies/{NAME}.py --report-only {os.path.relpath(base, REPO)}.json")


def markdown(doc, name=NAME):
    s = doc["summary"]
    first = doc["pairs"][0]
    lines = [report_md.generated_banner(f"bench/studies/{NAME}.py", f"{name}.json"), "",
             "# mipnerf-cl's mip-NeRF 360 against multinerf on a 360-degree capture, at equal steps", "",
             f"{doc['capture']}; {doc['steps']} steps, {doc['seeds']} seed(s); checkout "
             f"{doc['checkout']['commit'][:10]}{' (dirty)' if doc['checkout']['dirty'] else ''}, multinerf "
             f"{doc['multinerf_commit']}, {doc['cpu']}, {doc['date']}.", "",
             f"Ours: `{first['ours']['command']}` on {first['ours']['device']}; official: multinerf's Model, "
             "train_step, Dataset and render_image with the same settings (below). Test PSNR: the mean over the 5 "
             "held-out views of each view's PSNR. Train seconds: ours as `train` reports them, the official's after "
             "its jit compile.", ""]
    lines += report_md.table(
        ["side", "test PSNR mean ± sd, dB", "range", "train s (median)", "s/step"], "lllll",
        [[name, f"{x['mean_psnr']:.2f} ± {x['sd_psnr']:.2f}", f"{x['min_psnr']:.2f}–{x['max_psnr']:.2f}",
          f"{x['median_train_seconds']:.1f}", f"{x['median_train_seconds'] / doc['steps']:.3f}"]
         for name, x in (("mipnerf-cl", s["ours"]), ("multinerf", s["official"]))])
    lines += ["", "ours − official per seed: " + ", ".join(f"{d:+.2f} dB" for d in s["psnr_difference_per_seed"]) +
              "; official s / ours s per seed: " + ", ".join(f"{r:.2f}" for r in s["train_seconds_ratio_per_seed"]),
              "", "## Every run", ""]
    rows = []
    for p in doc["pairs"]:
        c = p["conditions"]
        other = "–" if c["other_cpu_cores"] is None else f"{c['other_cpu_cores']:.2f}"
        rows.append([str(p["seed"]), " then ".join(p["order"]), f"{p['ours']['mean_psnr']:.2f}",
                     f"{p['official']['mean_psnr']:.2f}", f"{p['ours']['train_seconds']:.1f}",
                     f"{p['official']['train_seconds']:.1f}",
                     f"{p['ours']['parameters']} / {p['official']['parameters']}", other,
                     f"{c['load_before']} → {c['load_after']}"])
    lines += report_md.table(["seed", "order", "ours dB", "official dB", "ours train s", "official train s",
                              "parameters, ours / official", "other processes' CPU, cores",
                              "load before → after"],
                             "l" * 9, rows)
    off = first["official"]
    lines += ["", "## The official side", "",
              f"- gin: `{json.dumps(off['bindings'])}`", f"- Config: `{json.dumps(off['config'])}`",
              f"- Versions: `{json.dumps(doc['versions'])}`",
              "- Stand-ins: " + "; ".join(f"`{name}`: {why}" for name, why in doc["stubs"]),
              "- Per view (official, first run): " + ", ".join(f"{x:.2f}" for x in off["psnrs"]), ""]
    return "\n".join(lines)


def report_only(path):
    doc = read_json(path)
    md = os.path.splitext(path)[0] + ".md"
    name = os.path.splitext(os.path.basename(path))[0]
    report_md.write_report(md, markdown(doc, name), f"python3 bench/studies/{NAME}.py --report-only "
                                              f"{os.path.relpath(os.path.abspath(path), REPO)}")
    print(f"wrote {md}")


# ---------------------------------------------------------------------------------------------- worker side (venv)

def install_stubs():
    import types
    import jax
    for name in ("cv2", "dm_pix", "rawpy"):
        sys.modules.setdefault(name, types.ModuleType(name))
    pycolmap = types.ModuleType("pycolmap")
    pycolmap.SceneManager = type("SceneManager", (), {})
    sys.modules["pycolmap"] = pycolmap
    if not hasattr(jax, "host_id"):
        jax.host_id = jax.process_index


def world_around_cameras(poses):
    """Our data::world_around_cameras for multinerf's (N, 3, 4) camera-to-world poses: the centre is the least-squares
    point closest to every optical axis (−z), the scale puts the cameras at root-mean-square distance 1 from it; no
    rotation. Returns (poses, the 4x4 transform) as transform_poses_pca does."""
    import numpy as np
    origins, dirs = poses[:, :3, 3], -poses[:, :3, 2]
    dirs = dirs / np.linalg.norm(dirs, axis=-1, keepdims=True)
    m = np.eye(3)[None] - dirs[:, :, None] * dirs[:, None, :]
    centre = np.linalg.solve(m.sum(0), (m @ origins[:, :, None]).sum(0))[:, 0]
    scale = 1.0 / np.sqrt(np.mean(np.sum((origins - centre) ** 2, axis=-1)))
    out = poses.copy()
    out[:, :3, 3] = (origins - centre) * scale
    transform = np.diag([scale, scale, scale, 1.0])
    transform[:3, 3] = -centre * scale
    return out, transform


class Multinerf:
    def __init__(self, checkout):
        sys.path.insert(0, os.path.abspath(checkout))
        install_stubs()
        from internal import camera_utils, configs, datasets, image, models, train_utils, utils
        camera_utils.transform_poses_pca = world_around_cameras
        self.configs, self.datasets, self.image, self.models = configs, datasets, image, models
        self.train_utils, self.utils = train_utils, utils

    def versions(self):
        import jax
        import flax
        import numpy
        import optax
        return {"python": sys.version.split()[0], "jax": jax.__version__, "flax": flax.__version__,
                "optax": optax.__version__, "numpy": numpy.__version__, "jax_devices": str(jax.devices())}

    @staticmethod
    def prepare(scene, factor, out):
        """The LLFF capture as a transforms.json folder at its images_<factor> size (both sides read it)."""
        import shutil
        import numpy as np
        rows = np.load(os.path.join(scene, "poses_bounds.npy"))
        names = sorted(os.listdir(os.path.join(scene, f"images_{factor}")))
        h, w, focal = rows[0, :15].reshape(3, 5)[:, 4] / factor
        os.makedirs(os.path.join(out, "images"), exist_ok=True)
        frames = []
        for row, name in zip(rows, names):
            m = row[:15].reshape(3, 5)
            # LLFF's columns are [down, right, back]; OpenGL's [right, up, back]
            rot = np.stack([m[:, 1], -m[:, 0], m[:, 2]], axis=1)
            c2w = np.concatenate([np.concatenate([rot, m[:, 3:4]], 1), [[0, 0, 0, 1]]], 0)
            shutil.copy(os.path.join(scene, f"images_{factor}", name), os.path.join(out, "images", name))
            frames.append({"file_path": f"images/{name}", "transform_matrix": c2w.tolist()})
        meta = {"w": int(round(w)), "h": int(round(h)), "fl_x": float(focal), "fl_y": float(focal),
                "cx": float(w) / 2, "cy": float(h) / 2, "frames": frames}
        with open(os.path.join(out, "transforms.json"), "w") as f:
            json.dump(meta, f, indent=1)
        return {"views": len(frames), "w": meta["w"], "h": meta["h"]}

    def train(self, capture, bindings, config, steps, seed):
        import functools
        import gin
        import jax
        import numpy as np
        from jax import random
        gin.clear_config()
        lines = []
        for scope, values in bindings.items():
            for key, value in values.items():
                lines.append(f"{scope}.{key} = {value if isinstance(value, str) else json.dumps(value)}")
        gin.parse_config("\n".join(lines).replace("true", "True").replace("false", "False"))
        cfg = self.configs.Config(data_dir=capture, checkpoint_dir="/tmp/unused", **config)
        np.random.seed(20201473 + seed)  # train.py's numpy seed, shifted by the seed
        dataset = self.datasets.load_dataset("train", capture, cfg)
        test = self.datasets.load_dataset("test", capture, cfg)
        cameras = tuple(jax.numpy.array(x) if isinstance(x, np.ndarray) else x for x in dataset.cameras)
        rng = random.PRNGKey(20200823 + seed)
        rng, key = random.split(rng)
        model, state, render_eval_pfn, train_pstep, lr_fn = self.train_utils.setup_model(cfg, key, dataset=dataset)
        params = int(sum(x.size for x in jax.tree_util.tree_leaves(state.params)))
        import flax
        state = flax.jax_utils.replicate(state)
        rngs = random.split(rng, jax.local_device_count())
        batches = flax.jax_utils.prefetch_to_device(dataset, 3)
        # train.py compiles on its first step; here the first step is timed apart (compile + one step) and
        # the rest are the train seconds, as vs_official_llff's.
        t0 = time.time()
        compile_s = None
        for step, batch in zip(range(1, steps + 1), batches):
            train_frac = jax.numpy.clip((step - 1) / (cfg.max_steps - 1), 0, 1)
            state, stats, rngs = train_pstep(rngs, state, batch, cameras, train_frac, 1.0)
            if step == 1:
                jax.block_until_ready(state)
                compile_s = time.time() - t0
                t0 = time.time()
        jax.block_until_ready(state)
        train_s = time.time() - t0
        # eval.py: each test view rendered deterministically (rng None) at train_frac = step / max_steps = 1
        psnrs = []
        t0 = time.time()
        eval_params = flax.jax_utils.unreplicate(state).params  # as train.py's eval: the params unreplicated
        for i in range(test.size):
            rays = test.generate_ray_batch(i).rays
            rendering = self.models.render_image(functools.partial(render_eval_pfn, eval_params, 1.0), rays, None,
                                                 cfg)
            mse = float(((np.asarray(rendering["rgb"]) - test.images[i]) ** 2).mean())
            psnrs.append(float(self.image.mse_to_psnr(mse)))
        return {"train_seconds": train_s * steps / max(1, steps - 1), "first_step_seconds": compile_s,
                "parameters": params, "psnrs": psnrs, "mean_psnr": sum(psnrs) / len(psnrs), "views": len(psnrs),
                "render_seconds": time.time() - t0, "last_loss": float(np.asarray(stats["loss"]).mean())}


def quietly(handler):
    """The handler with multinerf's prints sent to stderr: stdout carries the JSON replies."""
    import contextlib

    def wrapped(m, req):
        with contextlib.redirect_stdout(sys.stderr):
            return handler(m, req)
    return wrapped


def worker_main(args):
    def make():
        import contextlib
        with contextlib.redirect_stdout(sys.stderr):
            return Multinerf(args.multinerf)
    serve_requests(make, {
        "versions": quietly(lambda m, req: m.versions()),
        "prepare": quietly(lambda m, req: m.prepare(req["scene"], req["factor"], req["out"])),
        "train": quietly(lambda m, req: m.train(req["capture"], req["bindings"], req["config"], req["steps"],
                                                req["seed"]))})


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--multinerf", help="checkout of github:google-research/multinerf (internal/, configs/)")
    p.add_argument("--multinerf-commit", default="unknown", help="its commit, recorded")
    p.add_argument("--bin", default=os.path.join(REPO, "build", "mipnerf-cl"), help="mipnerf-cl executable")
    p.add_argument("--venv", default=DEFAULT_VENV, help="virtual environment for the official code")
    p.add_argument("--python", default=sys.executable, help="python used to create the venv")
    p.add_argument("--steps", type=int, default=500, help="training steps, both sides (the schedule's length)")
    p.add_argument("--seeds", type=int, default=3, help="trainings per side")
    p.add_argument("--work", default="/tmp/vs_multinerf_360", help="runs kept here (per step count and seed), so an "
                                                                 "interrupted study resumes")
    p.add_argument("--out-dir", default=report_md.results_folder(NAME), help="where the .json and .md go")
    p.add_argument("--name", default=NAME, help="the results' file name (NAME.json, NAME.md)")
    p.add_argument("--allow-dirty", action="store_true", help="run on a tree with uncommitted changes")
    p.add_argument("--report-only", metavar="JSON", help="regenerate the .md from a results .json and stop")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    return p.parse_args(argv)


def main(argv):
    args = parse_args(argv)
    try:
        if args.report_only:
            report_only(args.report_only)
        elif args.worker:
            worker_main(args)
        else:
            if not args.multinerf or not os.path.isfile(os.path.join(args.multinerf, "internal", "models.py")):
                fail(f"--multinerf {args.multinerf}: not a multinerf checkout (no internal/models.py)")
            if not os.access(args.bin, os.X_OK):
                fail(f"--bin {args.bin}: not an executable; build mipnerf-cl first (cmake --build build)")
            if args.steps < 2 or args.seeds < 1:
                fail("--steps must be at least 2 and --seeds at least 1")
            orchestrate(args)
    except OfficialError as e:
        fail(str(e))


if __name__ == "__main__":
    main(sys.argv[1:])
