"""`bench/studies/vs_official_llff.py --official OFFICIAL --llff DIR`: both sides train the quick network on one forward-facing LLFF capture, then
score the held-out views (every 8th image, llffhold 8) — mipnerf-cl through its own LLFF loader and scene effects,
google/mipnerf through its own LLFF loader (internal/datasets.py, class LLFF) with configs/llff.gin's settings
(NDC rays, cylinders, black background, near 0 / far 1, density noise 1, un-normalised view directions).

For each seed (0..--seeds-1) and each step count (--llff-steps, default 300,600), each side trains from scratch for
exactly that many steps (the learning-rate schedule's max_steps = those steps, as train.py's --max_steps), then
renders the held-out views with randomized=False; the figure per side is the mean of the per-view PSNRs (peak 1), as
the official eval.py reports it. Sides alternate who goes first. Train seconds: ours as `train` reports them (its
steps with their log lines and checkpoints; the OpenCL programs are built before step 1); the official code's over
its steps after the jit compile (done on a throw-away step before the fresh state). The network settings of the official side are derived from our quick preset's config.json and checked
(parameter counts must match).

Every finished run is kept in --work (ours: the run folder; official: a JSON record), so an interrupted bench
resumes where it stopped. Results: bench/results/vs_official_llff/vs_official_llff_<device>.json and .md.
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
from lib.official import (Official, OfficialError, Worker, add_official_arguments,  # noqa: E402
                          bind_gin, check_official_checkout, ensure_venv, install_stubs, llff_split,
                          official_commit, official_settings, serve_requests, side_summary, train_once)
from lib.provenance import REPO, cpu_model, tree_state  # noqa: E402

NAME = "vs_official_llff"


# ---------------------------------------------------------------------------------------------- orchestrator side

def fail(message):
    sys.exit(f"vs_official_llff.py: {message}")


def llff_factor(args):
    factor = args.factor if args.factor is not None else 8
    if not os.path.isdir(os.path.join(args.llff, f"images_{factor}")):
        fail(f"--llff {args.llff}: no images_{factor}/ (the official loader reads images_<factor>; give --factor)")
    return factor


def train_ours(args, factor, steps, seed, log):
    """Our quick preset on the capture: train (resumed if interrupted), the final val = all held-out views."""
    out = os.path.join(args.work, "ours", f"steps{steps}_seed{seed}")
    settings = {"factor": factor, "steps": steps, "seed": seed, "val_every": 0, "val_views": args.llff_views}
    before = time.time()
    summary, command = train_resumable(args.bin, args.llff, out, "quick", "mipnerf", settings, log)
    config = read_json(os.path.join(out, "config.json"))
    val = summary["val"]
    return {"steps": summary["steps"], "seed": seed, "train_seconds": summary["train_seconds"],
            "mean_psnr": val["mean_psnr"], "views": val["views"], "mean_ssim": val.get("mean_ssim"),
            "render_s_per_mp": val.get("render_seconds_per_megapixel"), "device": summary.get("device"),
            "parameters": summary.get("parameters"), "scene_effects": config.get("scene_effects"),
            "command": " ".join(command[1:]), "this_call": {"wall_seconds": time.time() - before}}, config


def official_llff_settings(config, steps):
    """The official model/MLP/config for our LLFF run's config: the Blender mapping of vs_official.py, then
    configs/llff.gin's LLFF settings, each checked against what our scene effects chose."""
    expect = {"ray_shape": "cylinder", "background": "black", "unit_viewdirs": False, "lindisp": False}
    for key, want in expect.items():
        if config.get(key) != want:
            fail(f"our LLFF run chose {key} = {config.get(key)}; configs/llff.gin has {want}")
    model, mlp, cfg = official_settings(config)
    model["density_noise"] = float(config["density_noise"])
    cfg.update(dataset_loader="llff", near=0.0, far=1.0, white_bkgd=False, llffhold=8, spherify=False,
               max_steps=steps)
    return model, mlp, cfg


def llff_worker(py, args, factor):
    """The official LLFF worker: this file with --worker in the venv's python (worker_main_llff below)."""
    return Worker([py, os.path.abspath(__file__), "--worker",
                   "--official", args.official, "--llff", args.llff, "--factor", str(factor)])


def official_run(args, worker, config, factor, steps, seed):
    model, mlp, cfg = official_llff_settings(config, steps)
    return train_once(worker, os.path.join(args.work, "official", f"steps{steps}_seed{seed}.json"),
                      {"cmd": "train_llff", "model": model, "mlp": mlp, "config": cfg, "steps": steps, "seed": seed,
                       "views": args.llff_views},
                      {"steps": steps, "seed": seed, "official_model": model, "official_mlp": mlp,
                       "official_config": cfg})


def orchestrate_llff(args):
    factor = llff_factor(args)
    steps_list = [int(s) for s in args.llff_steps.split(",")]
    state = tree_state()
    if state["dirty"] and not args.allow_dirty:
        fail("the checkout has uncommitted changes (figures must name a commit): commit, or --allow-dirty")
    state["allow_dirty"] = args.allow_dirty
    py = ensure_venv(args.venv, args.python)
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "ours.log")
    worker = llff_worker(py, args, factor)
    versions = worker.call(cmd="versions")
    pairs = []
    for seed in range(args.seeds):
        for i, steps in enumerate(steps_list):
            order = ["ours", "official"] if (seed + i) % 2 == 0 else ["official", "ours"]
            snap = snapshot(worker)
            entry = {"seed": seed, "steps": steps, "order": order}
            for side in order:
                if side == "ours":
                    entry["ours"], config = train_ours(args, factor, steps, seed, log)
                else:  # the official settings come from our run's config (or, before it, our preset's)
                    config = config if "ours" in entry else our_config(args, factor, steps, seed, log)
                    entry["official"] = official_run(args, worker, config, factor, steps, seed)
            entry["conditions"] = between(snap, snapshot(worker))
            if entry["ours"]["parameters"] != entry["official"]["parameters"]:
                fail(f"parameter counts differ: ours {entry['ours']['parameters']}, "
                        f"official {entry['official']['parameters']}")
            pairs.append(entry)
            print(f"llff: seed {seed}, {steps} steps: ours {entry['ours']['mean_psnr']:.2f} dB in "
                  f"{entry['ours']['train_seconds']:.1f} s, official {entry['official']['mean_psnr']:.2f} dB in "
                  f"{entry['official']['train_seconds']:.1f} s", flush=True)
            write(args, factor, steps_list, versions, state, pairs)
    worker.close()


def our_config(args, factor, steps, seed, log):
    """Our run's config.json when it has run; before it, our quick preset's for this capture (a 1-step probe run,
    once): the network, schedule and scene effects do not depend on the seed or the step count."""
    run_config = os.path.join(args.work, "ours", f"steps{steps}_seed{seed}", "config.json")
    if os.path.exists(run_config):
        return read_json(run_config)
    out = os.path.join(args.work, "ours", "config_probe")
    if not os.path.exists(os.path.join(out, "config.json")):
        run([args.bin, "train", "--data", args.llff, "--out", out, "--preset", "quick", "--set", f"factor={factor}",
             "--set", "steps=1", "--set", "val_views=1"], log)
    return read_json(os.path.join(out, "config.json"))


def report_only(json_path):
    doc = read_json(json_path)
    md = os.path.splitext(json_path)[0] + ".md"
    report_md.write_report(md, markdown(doc), f"python3 bench/studies/vs_official_llff.py --report-only {json_path}")
    print(f"wrote {md}")


def write(args, factor, steps_list, versions, state, pairs):
    summary = {}
    for steps in steps_list:
        at = [p for p in pairs if p["steps"] == steps]
        if at:
            summary[str(steps)] = {"ours": side_summary([p["ours"] for p in at]),
                                   "official": side_summary([p["official"] for p in at]),
                                   "psnr_difference_per_seed": [p["ours"]["mean_psnr"] - p["official"]["mean_psnr"]
                                                                for p in at],
                                   "train_seconds_ratio_per_seed": [p["official"]["train_seconds"] /
                                                                    p["ours"]["train_seconds"] for p in at]}
    doc = {"what": "quick network trained on one forward-facing LLFF capture by both sides, test PSNR at equal steps",
           "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "capture": os.path.abspath(args.llff), "factor": factor, "views": args.llff_views or "all", "steps": steps_list, "seeds": args.seeds,
           "checkout": state, "official_commit": args.official_commit or official_commit(args.official),
           "cpu": cpu_model(), "versions": versions, "notes": args.note, "pairs": pairs, "summary": summary}
    os.makedirs(args.out_dir, exist_ok=True)
    base = os.path.join(args.out_dir, f"{NAME}_{args.device_name}")
    with open(base + ".json", "w") as f:
        json.dump(doc, f, indent=2)
    report_md.write_report(base + ".md", markdown(doc), f"python3 bench/studies/vs_official_llff.py --report-only {base}.json")


def fmt_range(s, key):
    return f"{s['mean_' + key]:.2f} ({s['min_' + key]:.2f}–{s['max_' + key]:.2f})"


def markdown(doc):
    first = doc["pairs"][0]
    lines = [f"# mipnerf-cl against google/mipnerf on a forward-facing LLFF capture", "",
             f"Capture `{doc['capture']}` at factor {doc['factor']} (images_{doc['factor']}/), the quick network, "
             f"{doc['seeds']} seed(s) per step count; checkout {doc['checkout']['commit'][:10]}"
             f"{' (dirty)' if doc['checkout']['dirty'] else ''}, official commit {doc['official_commit']}, "
             f"{doc['cpu']}, {doc['date']}.", "",
             f"Ours: `{first['ours']['command'].replace(doc['capture'], 'DIR')}` on {first['ours']['device']} "
             f"(scene effects: {first['ours']['scene_effects']}); official: its LLFF loader and train_step with "
             "configs/llff.gin's settings and our preset's network and schedule (below). Test PSNR: mean over "
             "the held-out views (llffhold 8) of each view's PSNR, randomized=False, as eval.py reports it. Train "
             "seconds: ours as `train` reports them (steps, log lines, checkpoints; programs built before step 1), "
             "the official code's after its jit compile.", ""]

    def train_range(side):
        return (f"{side['median_train_seconds']:.1f} ({side['min_train_seconds']:.1f}–"
                f"{side['max_train_seconds']:.1f})")
    lines += report_md.table(
        ["steps", "ours: test PSNR mean (range), dB", "official", "ours − official per seed, dB",
         "ours: train s, median (range)", "official", "official s / ours s per seed"], "lllllll",
        [[str(steps), fmt_range(s["ours"], "psnr"), fmt_range(s["official"], "psnr"),
          ", ".join(f"{d:+.2f}" for d in s["psnr_difference_per_seed"]), train_range(s["ours"]),
          train_range(s["official"]), ", ".join(f"{r:.2f}" for r in s["train_seconds_ratio_per_seed"])]
         for steps, s in doc["summary"].items()])
    lines += ["", "## Every run", ""]
    rows = []
    for p in doc["pairs"]:
        c = p["conditions"]
        other = "–" if c["other_cpu_cores"] is None else f"{c['other_cpu_cores']:.2f}"
        rows.append([str(p["seed"]), str(p["steps"]), " then ".join(p["order"]), f"{p['ours']['mean_psnr']:.2f}",
                     f"{p['official']['mean_psnr']:.2f}", f"{p['ours']['train_seconds']:.1f}",
                     f"{p['official']['train_seconds']:.1f}", f"{p['ours']['render_s_per_mp']:.0f}",
                     f"{p['official']['render_seconds']:.0f}", other, f"{c['load_before']} → {c['load_after']}"])
    lines += report_md.table(
        ["seed", "steps", "order", "ours dB", "official dB", "ours train s", "official train s", "ours render s/MP",
         "official render s (all test views)", "other processes' CPU, cores", "load before → after"],
        "l" * 11, rows)
    off = first["official"]
    lines += ["", "## The official side's settings", "",
              f"- MipNerfModel: `{json.dumps(off['official_model'])}`", f"- MLP: `{json.dumps(off['official_mlp'])}`",
              f"- Config: `{json.dumps(off['official_config'])}`", f"- Versions: `{json.dumps(doc['versions'])}`",
              "- Per view (official, first run): " + ", ".join(f"{x:.2f}" for x in off["psnrs"]), ""]
    if doc["notes"]:
        lines += ["## Notes", ""] + [f"- {n}" for n in doc["notes"]] + [""]
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------- worker side (venv)

class OfficialLlff:
    """The official LLFF loader, model and train_step in this process."""

    def __init__(self, official, data, factor):
        sys.path.insert(0, os.path.abspath(official))
        self.Optimizer = install_stubs()
        from absl import flags
        import train  # the official train.py: its flags and train_step
        from internal import datasets, models, utils
        flags.FLAGS(["train"])
        self.train, self.datasets, self.models, self.utils = train, datasets, models, utils
        self.data, self.factor, self.loaded = data, factor, None

    def versions(self):
        return Official.versions(self)

    def load(self, cfg):
        if self.loaded == self.factor:
            return
        import numpy as np
        train = llff_split(self.datasets, self.data, cfg, "train")
        self.train_rays = self.utils.namedtuple_map(lambda r: r.reshape(-1, r.shape[-1]), train.rays)
        self.train_pixels = train.images.reshape(-1, 3)
        test = llff_split(self.datasets, self.data, cfg, "test")
        self.test_rays, self.test_images = test.rays, test.images
        self.loaded = self.factor
        self.np = np

    def batch(self, rng, n):
        idx = rng.randint(0, self.train_pixels.shape[0], (n,))  # as Dataset._next_train, batching all_images
        return self.utils.shard({"pixels": self.train_pixels[idx],
                                 "rays": self.utils.namedtuple_map(lambda r: r[idx], self.train_rays)})

    def train_llff(self, model, mlp, config, steps, seed, views):
        import functools
        import jax
        import numpy as np
        from jax import random
        bind_gin(model, mlp)
        cfg = self.utils.Config(factor=self.factor, **config)
        self.config = cfg
        self.load(cfg)
        rng = np.random.RandomState(20201473 + seed)  # train.py's numpy seed, shifted by the seed
        key = random.PRNGKey(20200823 + seed)
        key, init_key = random.split(key)
        net, variables = self.models.construct_mipnerf(init_key, jax.device_put(self.batch(rng, cfg.batch_size)))
        params = sum(int(x.size) for x in jax.tree_util.tree_leaves(variables))
        fresh = self.utils.TrainState(optimizer=self.Optimizer.create(variables))
        pstep = jax.pmap(functools.partial(self.train.train_step, net, cfg), axis_name="batch",
                         in_axes=(0, 0, 0, None), donate_argnums=(2,))
        lr = functools.partial(self.train.math.learning_rate_decay, lr_init=cfg.lr_init, lr_final=cfg.lr_final,
                               max_steps=cfg.max_steps, lr_delay_steps=cfg.lr_delay_steps,
                               lr_delay_mult=cfg.lr_delay_mult)
        replicate = lambda s: jax.tree_util.tree_map(lambda x: jax.numpy.asarray(x)[None], s)  # noqa: E731
        # compile on a throw-away copy of the state, then train the fresh state from step 1
        t0 = time.time()
        scratch, _, _ = pstep(random.split(key, 1), replicate(fresh), jax.device_put(self.batch(rng, cfg.batch_size)),
                              lr(1))
        jax.block_until_ready(scratch)
        compile_s = time.time() - t0
        rng = np.random.RandomState(20201473 + seed)
        state, keys = replicate(fresh), random.split(key, jax.local_device_count())
        t0 = time.time()
        for step in range(1, steps + 1):
            state, stats, keys = pstep(keys, state, jax.device_put(self.batch(rng, cfg.batch_size)), lr(step))
        jax.block_until_ready(state)
        train_s = time.time() - t0
        t0 = time.time()
        psnrs = self.score(net, state, keys, views)
        return {"train_seconds": train_s, "compile_s": compile_s, "parameters": params, "psnrs": psnrs,
                "mean_psnr": sum(psnrs) / len(psnrs), "views": len(psnrs), "render_seconds": time.time() - t0}

    def score(self, net, state, keys, views):
        """Each held-out view rendered as eval.py does (vs_official's Official.render_view: randomized=False,
        models.render_image in FLAGS.chunk rays), its PSNR against the loader's image by math.mse_to_psnr."""
        import jax
        import numpy as np
        from absl import flags
        self.model, self.state, self.keys, self.render_pfn = net, state, keys, None  # what render_view reads
        psnrs = []
        for i in range(views or self.test_images.shape[0]):
            rays = self.utils.namedtuple_map(lambda r: jax.numpy.asarray(r[i]), self.test_rays)
            rgb = Official.render_view(self, rays, flags.FLAGS.chunk)
            mse = float(((np.asarray(rgb) - self.test_images[i]) ** 2).mean())
            psnrs.append(float(self.train.math.mse_to_psnr(mse)))
        return psnrs


def worker_main_llff(args):
    serve_requests(lambda: OfficialLlff(args.official, args.llff, args.factor), {
        "versions": lambda off, req: off.versions(),
        "train_llff": lambda off, req: off.train_llff(**req)})


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_official_arguments(p, REPO, report_md.results_folder("vs_official_llff"))
    p.add_argument("--llff", metavar="DIR", help="the forward-facing LLFF capture (poses_bounds.npy, images_<factor>/)")
    p.add_argument("--factor", type=int, default=None, help="downsample factor of the capture, both sides (default 8)")
    p.add_argument("--llff-steps", default="300,600", help="the step counts, each trained from scratch")
    p.add_argument("--llff-views", type=int, default=0,
                   help="score the first N held-out views only (0: all; N > 0 for a quick try)")
    p.add_argument("--seeds", type=int, default=3, help="trainings per step count and side")
    p.add_argument("--work", default="/tmp/vs_official_llff", help="runs kept here, so an interrupted bench resumes")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    return p.parse_args(argv)


def check_inputs(args):
    check_official_checkout(args.official)  # OfficialError: main says it in one line
    if not os.access(args.bin, os.X_OK):
        fail(f"--bin {args.bin}: not an executable; build mipnerf-cl first (cmake --build build)")
    if not args.llff or not os.path.isfile(os.path.join(args.llff, "poses_bounds.npy")):
        fail(f"--llff {args.llff}: no poses_bounds.npy; pass an LLFF capture folder (e.g. flower)")
    if args.seeds < 1:
        fail("--seeds must be at least 1")


def main(argv):
    args = parse_args(argv)
    try:
        if args.report_only:
            report_only(args.report_only)
        elif args.worker:
            worker_main_llff(args)
        else:
            check_inputs(args)
            orchestrate_llff(args)
    except OfficialError as e:  # the official side's one-line reasons (lib/official.py)
        fail(str(e))


if __name__ == "__main__":
    main(sys.argv[1:])
