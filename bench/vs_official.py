#!/usr/bin/env python3
"""Side-by-side benchmark: mipnerf-cl against the official google/mipnerf (JAX) code.

What it does (issue 13, deliverable 4), in one run on one machine:
  * For each configuration -- `quick` (the quick preset's network at 512 rays) and `paper` (the
    paper's network at 1,024 rays) -- it times warm training steps of both implementations,
    ALTERNATING in rounds (ours, official, official, ours, ...), and reports medians, rays/s and
    the ratio. mipnerf-cl's configuration is read from its own `bench.json`; the official model is
    configured from it, and the two parameter counts must agree or the script stops.
  * mipnerf-cl's step: `mipnerf-cl bench --sections train --presets P --set batch_size=B
    --data LEGO --set factor=4`, warm steps from bench.json (`warm_step_seconds`: wall time between
    step returns, each ending with the device queue finished; the cold first step and the kernel
    builds are excluded by bench itself).
  * The official step: its `train.train_step` (model `internal/models.py` MipNerfModel built by
    `construct_mipnerf`, the loss of train.py with coarse_loss_mult and lossmult weighting, gradient
    statistics), pmapped over the one CPU device exactly as train.py does, with Adam from optax
    behind a small `flax.optim` stand-in (modern flax has no `flax.optim`). Each step is timed with
    `block_until_ready`; the XLA compile and a warm-up step are excluded. Batches are random rays
    over all training images of the scene, built before timing (data loading excluded; the official
    train.py prefetches in a thread).
  * Render time (quick configuration only): the first training camera at the scene's size after
    --factor (100x100 for lego at factor 4), warm, s/MP from the best render, for both.
  * Writes bench/results/vs_official_<device>.md and .json.

The official code runs in a worker process (this same file with --worker) inside a virtual
environment the script creates (--venv) and fills from PyPI with jax[cpu], flax, optax, gin-config,
numpy, pillow. The official checkout is only read (sys.path), never copied or patched on disk; the
import-time stand-ins are installed in the worker's memory and listed in the results (STUBS below).

Command used for the committed results (the checkout: `git archive` of google/mipnerf 84c969e, so
pass --official-commit next time; the commit was added to those results afterwards):
  python3 bench/vs_official.py --official /tmp/official --data /work/shared/data/nerf_synthetic/lego
A quick look at the training path: add --configs quick --train-steps 30 (hours of steps for real PSNRs).

Requirements: a built mipnerf-cl (--bin, default build/mipnerf-cl), a checkout of
github:google/mipnerf (--official), the Blender lego scene (--data), network access to PyPI the
first time (venv creation). The project's tests never import this file.
"""

import argparse
import datetime
import json
import os
import platform
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_VENV = os.path.join(os.path.expanduser("~"), ".cache", "mipnerf-cl", "vs-official-venv")
DEFAULT_DATA = os.path.normpath(os.path.join(REPO, "..", "shared", "data", "nerf_synthetic", "lego"))
PIP_PACKAGES = ["jax[cpu]", "flax", "optax", "gin-config", "numpy", "pillow"]

# The two configurations: our preset and the batch size; everything else comes from the preset.
CONFIGS = [("quick", "quick", 512), ("paper", "paper", 1024)]

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


# ----------------------------------------------------------------------------------------------
# Orchestrator side (standard library only)
# ----------------------------------------------------------------------------------------------

def our_gemm_label(config_result):
    """What ran our training products, as the bench's training record says (host BLAS, tuned or default CLBlast);
    results written before that record existed fall back to whether a CLBlast tuning file was loaded."""
    used = {run.get("gemm_in_training", "") for run in config_result.get("our_runs", [])} - {""}
    if used:
        return ", ".join(sorted(used))
    return "tuned" if config_result["gemm"].get("tuned") else "CLBlast defaults"


def fail(message):
    sys.exit(f"vs_official.py: {message}")


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--official", help="checkout of github:google/mipnerf (contains train.py and internal/)")
    p.add_argument("--official-commit", help="commit of --official when it is not a git work tree (e.g. a git archive)")
    p.add_argument("--data", default=DEFAULT_DATA, help="Blender scene folder (default: ../shared's lego)")
    p.add_argument("--factor", type=int, default=4, help="downsample factor of the scene (both sides)")
    p.add_argument("--bin", default=os.path.join(REPO, "build", "mipnerf-cl"), help="mipnerf-cl executable")
    p.add_argument("--venv", default=DEFAULT_VENV, help="virtual environment for the official code")
    p.add_argument("--python", default=sys.executable, help="python used to create the venv")
    p.add_argument("--configs", nargs="+", default=[c[0] for c in CONFIGS], help="quick and/or paper")
    p.add_argument("--rounds", type=int, default=2, help="alternating rounds per configuration")
    p.add_argument("--quick-steps", type=int, default=8, help="warm steps per side and round, quick")
    p.add_argument("--paper-steps", type=int, default=3, help="warm steps per side and round, paper")
    p.add_argument("--render-reps", type=int, default=2, help="timed renders per side (quick config)")
    p.add_argument("--train-steps", type=int, default=0,
                   help="also train both (quick config) for this many steps and score val PSNR (0: off; long)")
    p.add_argument("--device-name", default="pocl_cpu", help="suffix of the results files")
    p.add_argument("--out-dir", default=os.path.join(REPO, "bench", "results"))
    p.add_argument("--note", action="append", default=[], help="a line for the results' Notes (repeatable)")
    p.add_argument("--report-only", metavar="JSON", help="rewrite the .md from a results .json, measure nothing")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if not args.worker and not args.report_only:
        check_inputs(args)
    return args


def check_inputs(args):
    if not args.official:
        fail("pass --official DIR, a checkout of github:google/mipnerf (the folder holding train.py)")
    if not os.path.isfile(os.path.join(args.official, "internal", "models.py")):
        fail(f"--official {args.official}: no internal/models.py there; pass the google/mipnerf checkout")
    if not os.path.isfile(os.path.join(args.data, "transforms_train.json")):
        fail(f"--data {args.data}: no transforms_train.json; pass a Blender scene folder (e.g. lego)")
    if not os.access(args.bin, os.X_OK):
        fail(f"--bin {args.bin}: not an executable; build mipnerf-cl first (cmake --build build)")
    for c in args.configs:
        if c not in [n for n, _, _ in CONFIGS]:
            fail(f"--configs: unknown '{c}' (quick, paper)")


def ensure_venv(args):
    """Create the venv and install the official code's dependencies from PyPI (once)."""
    py = os.path.join(args.venv, "bin", "python")
    marker = os.path.join(args.venv, ".vs_official_ready")
    if os.path.exists(marker):
        return py
    print(f"creating {args.venv} and installing {' '.join(PIP_PACKAGES)} from PyPI", flush=True)
    subprocess.run([args.python, "-m", "venv", args.venv], check=True)
    subprocess.run([py, "-m", "pip", "install", "-q"] + PIP_PACKAGES, check=True)
    open(marker, "w").close()
    return py


def load_average():
    return [round(x, 2) for x in os.getloadavg()]


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def git_commit():
    r = subprocess.run(["git", "-C", REPO, "rev-parse", "HEAD"], capture_output=True, text=True)
    dirty = subprocess.run(["git", "-C", REPO, "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True).stdout.strip()
    return r.stdout.strip() + (" (with uncommitted changes)" if dirty else "")


def official_commit(official):
    r = subprocess.run(["git", "-C", official, "rev-parse", "HEAD"], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else "unknown (not a git work tree)"


class Worker:
    """The official code in the venv's python, driven by one JSON line per request."""

    def __init__(self, py, args):
        cmd = [py, os.path.abspath(__file__), "--worker", "--official", args.official,
               "--data", args.data, "--factor", str(args.factor)]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def call(self, **request):
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            fail(f"the official worker died during {request.get('cmd')} (see its stderr above)")
        reply = json.loads(line)
        if "error" in reply:
            fail(f"the official worker failed during {request.get('cmd')}: {reply['error']}")
        return reply

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def run_ours(args, preset, batch, steps, render_size, render_reps):
    """One `mipnerf-cl bench` run of one preset; returns its device record from bench.json."""
    with tempfile.TemporaryDirectory(prefix="vs_official_") as out:
        cmd = [args.bin, "bench", "--sections", "train", "--presets", preset, "--steps", str(steps),
               "--paper-steps", str(steps), "--time-box", "0", "--data", args.data,
               "--set", f"factor={args.factor}", "--set", f"batch_size={batch}",
               "--render-size", render_size, "--render-reps", str(render_reps), "--out", out]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            fail(f"{' '.join(cmd)} failed:\n{r.stderr[-2000:]}")
        with open(os.path.join(out, "bench.json")) as f:
            record = json.load(f)
    record["command_line"] = " ".join(cmd[1:]).replace(out, "TMP")
    return record


def official_settings(our_config):
    """The official model's and config's settings equal to our preset's (checked, not assumed)."""
    c = our_config
    depth, skip = c["mlp_depth"], c["mlp_skip"]
    # Official MLP: concat after layer i when i % skip_layer == 0 and i > 0; ours after layer mlp_skip.
    if [i for i in range(depth) if i > 0 and i % skip == 0] != [skip]:
        fail(f"mlp_depth {depth} with mlp_skip {skip} has no official equivalent")
    unsupported = {"single_mlp": True, "pos_identity": False, "multiscale": False, "resample_blur": True,
                   "density_activation": "softplus", "jitter_pixels": False, "variant": "mipnerf"}
    for key, want in unsupported.items():
        if c[key] != want:
            fail(f"our setting {key} = {c[key]} is not what the official MipNerfModel computes")
    model = dict(num_samples=c["num_samples"], num_levels=c["num_levels"],
                 resample_padding=c["resample_padding"], stop_level_grad=True,
                 use_viewdirs=c["view_dependence"], lindisp=c["lindisp"], ray_shape=c["ray_shape"],
                 min_deg_point=c["pos_min_deg"], max_deg_point=c["pos_max_deg"], deg_view=c["view_max_deg"],
                 density_noise=0.0, density_bias=c["density_bias"], rgb_padding=c["rgb_padding"],
                 disable_integration=not c["integrated_encoding"])
    mlp = dict(net_depth=depth, net_width=c["mlp_width"], net_depth_condition=1,
               net_width_condition=c["view_branch_width"], skip_layer=skip)
    config = dict(batch_size=c["batch_size"], coarse_loss_mult=c["coarse_loss_mult"],
                  randomized=c["randomized"], white_bkgd=c["background"] == "white",
                  near=c["near"] or 2.0, far=c["far"] or 6.0, lr_init=c["lr_init"], lr_final=c["lr_final"],
                  lr_delay_steps=c["lr_warmup_steps"], lr_delay_mult=c["lr_warmup_mult"],
                  grad_max_norm=c["grad_max_norm"], disable_multiscale_loss=not c["area_loss"],
                  batching="all_images", max_steps=1000000)
    return model, mlp, config


def summarize(times, batch):
    med = statistics.median(times)
    return {"steps": len(times), "median_s": med, "best_s": min(times), "rays_per_s": batch / med,
            "step_seconds": times}


def bench_config(args, worker, name, preset, batch):
    """Alternating rounds (ABBA...) of one configuration; returns its record."""
    steps = args.quick_steps if name == "quick" else args.paper_steps
    # Our render is measured in the first run of the quick config only; the other runs render a
    # tiny image (bench always renders) so their cost stays small.
    full = ("100x100" if args.factor == 4 else "64x64", args.render_reps) if name == "quick" else ("8x8", 1)
    load = [load_average()]
    first = run_ours(args, preset, batch, steps, *full)
    dev = first["devices"][0]
    train, = dev["training"]
    model, mlp, config = official_settings(train["config"])
    setup = worker.call(cmd="setup", model=model, mlp=mlp, config=config)
    if setup["parameters"] != train["parameters"]:
        fail(f"{name}: parameter counts differ: mipnerf-cl {train['parameters']}, official {setup['parameters']}")
    print(f"{name}: parameters mipnerf-cl {train['parameters']} = official {setup['parameters']}", flush=True)
    records, official_times = [first], []
    for r in range(args.rounds):
        ours_first = r % 2 == 0
        if ours_first and r > 0:
            records.append(run_ours(args, preset, batch, steps, "8x8", 1))
        official_times += worker.call(cmd="steps", n=steps)["seconds"]
        if not ours_first:
            records.append(run_ours(args, preset, batch, steps, "8x8", 1))
        load.append(load_average())
        print(f"{name}: round {r + 1}/{args.rounds} done, load {load[-1]}", flush=True)
    ours_times, our_runs = [], []
    for rec in records:
        t, = rec["devices"][0]["training"]
        ours_times += t["warm_step_seconds"]
        our_runs.append({"command": rec["command_line"], "first_step_s": t["first_step_seconds"],
                         "warm_step_seconds": t["warm_step_seconds"], "gemm": rec["devices"][0]["gemm"],
                         "gemm_in_training": t.get("gemm_parameters", "")})
    result = {"name": name, "batch_rays": batch, "our_config": train["config"],
              "official_model": model, "official_mlp": mlp, "official_config": config,
              "parameters": {"mipnerf-cl": train["parameters"], "official": setup["parameters"]},
              "official_compile_s": setup["compile_s"], "gemm": dev["gemm"],
              "device": {"opencl_device": dev["device"]["name"], "pocl": dev["device"]["driver_version"],
                         "clblast": dev["clblast_version"]},
              "ours": summarize(ours_times, batch), "official": summarize(official_times, batch),
              "our_runs": our_runs, "load_average_per_round": load}
    result["ratio_rays_per_s"] = result["ours"]["rays_per_s"] / result["official"]["rays_per_s"]
    if name == "quick":
        result["render"] = bench_render(args, worker, first)
    return result


def train_psnr(args, worker, quick):
    """Both trained from scratch on the scene for --train-steps (quick config), then val PSNR."""
    import re
    c = quick["our_config"]
    with tempfile.TemporaryDirectory(prefix="vs_official_train_") as out:
        cmd = [args.bin, "train", "--preset", "quick", "--data", args.data, "--set", f"factor={args.factor}",
               "--set", f"batch_size={quick['batch_rays']}", "--set", f"steps={args.train_steps}", "--out", out]
        t0 = time.time()
        r = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.time() - t0
    m = re.search(r"val PSNR ([0-9.]+) dB.*?over (\d+) images; trained (\d+) steps in ([0-9.]+) s", r.stdout)
    if r.returncode != 0 or not m:
        fail(f"{' '.join(cmd)} failed or printed no val PSNR:\n{r.stdout[-1000:]}\n{r.stderr[-1000:]}")
    ours = {"mean_psnr": float(m.group(1)), "val_views": int(m.group(2)), "steps": int(m.group(3)),
            "train_seconds": float(m.group(4)), "command_wall_seconds": wall,
            "command": " ".join(cmd[1:]).replace(out, "TMP")}
    off = worker.call(cmd="train", model=quick["official_model"], mlp=quick["official_mlp"],
                      config=quick["official_config"], steps=args.train_steps, val_views=c["val_views"],
                      chunk=c["render_chunk_rays"])
    return {"steps": args.train_steps, "ours": ours, "official": off}


def bench_render(args, worker, record):
    ours = record["devices"][0]["render"]
    our_best = min(r["render_seconds_best"] for r in ours)
    mp = ours[0]["width"] * ours[0]["height"] / 1e6
    off = worker.call(cmd="render", reps=args.render_reps, chunk=ours[0]["chunk_rays"])
    if abs(off["megapixels"] - mp) > 1e-9:
        fail(f"render sizes differ: ours {mp} MP, official {off['megapixels']} MP")
    return {"view": "first training camera", "width": ours[0]["width"], "height": ours[0]["height"],
            "chunk_rays": ours[0]["chunk_rays"],
            "ours_seconds": [s for r in ours for s in r.get("render_seconds", [r["render_seconds_best"]])], "ours_s_per_mp": our_best / mp,
            "official_seconds": off["seconds"], "official_first_call_s": off["first_call_s"],
            "official_s_per_mp": min(off["seconds"]) / mp,
            "ratio": (our_best / mp) / (min(off["seconds"]) / mp)}


def write_results(args, results, training, versions, load_before, load_after, started, seconds):
    os.makedirs(args.out_dir, exist_ok=True)
    base = os.path.join(args.out_dir, f"vs_official_{args.device_name}")
    doc = {"tool": "bench/vs_official.py", "date": started, "seconds": seconds,
           "command": "python3 bench/vs_official.py " + shlex.join(sys.argv[1:]),
           "versions": versions, "stubs": [{"name": n, "what": w} for n, w in STUBS],
           "load_average_before": load_before, "load_average_after": load_after, "configs": results,
           "training": training, "notes": args.note}
    with open(base + ".json", "w") as f:
        json.dump(doc, f, indent=1)
    with open(base + ".md", "w") as f:
        f.write(markdown(doc))
    print(f"wrote {base}.md and {base}.json")


def markdown(doc):
    v = doc["versions"]
    lines = ["# mipnerf-cl against the official mip-NeRF code (JAX), same machine", "",
             f"Measured {doc['date']} by `{doc['command']}` ({doc['seconds'] / 60:.1f} min).", "",
             "## Training steps (warm, alternating)", "",
             "| config | mipnerf-cl s/step (median), rays/s | official s/step (median), rays/s | ratio (rays/s) | steps each | parameters (both) |",
             "|---|---:|---:|---:|---:|---:|"]
    for r in doc["configs"]:
        o, j = r["ours"], r["official"]
        c = r["our_config"]
        label = (f"{r['name']}: {r['batch_rays']} rays × {c['num_samples']} samples/level, "
                 f"{c['mlp_depth']}×{c['mlp_width']} (skip after {c['mlp_skip']}), view {c['view_branch_width']}, "
                 f"L = {c['pos_max_deg']}")
        lines.append(f"| {label} | {o['median_s']:.3f}, {o['rays_per_s']:.0f} | {j['median_s']:.3f}, "
                     f"{j['rays_per_s']:.0f} | {r['ratio_rays_per_s']:.2f}× | {o['steps']} / {j['steps']} | "
                     f"{r['parameters']['mipnerf-cl']} |")
    lines += [""]
    for r in doc["configs"]:
        if "render" in r:
            x = r["render"]
            lines += ["## Render (warm)", "",
                      f"{x['view']}, {x['width']}×{x['height']}, {x['chunk_rays']} rays per chunk, networks of "
                      f"the `{r['name']}` configuration after each side's timed steps, s/MP from the best render "
                      "(ours: `mipnerf-cl bench`'s render of the same camera, its first chunk timed apart; "
                      "official: models.render_image after one untimed render).", "",
                      "| | mipnerf-cl | official |", "|---|---:|---:|",
                      f"| render s | {', '.join(f'{s:.2f}' for s in x['ours_seconds'])} | "
                      f"{', '.join(f'{s:.2f}' for s in x['official_seconds'])} |",
                      f"| s/MP (best) | {x['ours_s_per_mp']:.0f} | {x['official_s_per_mp']:.0f} |",
                      f"| ratio (time, lower is faster for us) | {x['ratio']:.2f}× | |", ""]
    if doc.get("notes"):
        lines += ["## Notes", ""] + [f"- {n}" for n in doc["notes"]] + [""]
    t = doc.get("training")
    if t:
        o, j = t["ours"], t["official"]
        lines += [f"## Training on the scene for {t['steps']} steps (quick configuration), then val PSNR", "",
                  "| | mipnerf-cl | official |", "|---|---:|---:|",
                  f"| val PSNR (mean of the first {o['val_views']} val views) | {o['mean_psnr']:.2f} dB | "
                  f"{j['mean_psnr']:.2f} dB |",
                  f"| training wall time | {o['train_seconds']:.1f} s (whole command {o['command_wall_seconds']:.1f} s) "
                  f"| {j['train_seconds']:.1f} s (+ {j['compile_s']:.1f} s XLA compile and 2 warm-up steps) |", "",
                  f"Ours: `mipnerf-cl {o['command']}`; official: fresh parameters, its learning_rate_decay with "
                  "our preset's schedule, a new batch of random rays over all images each step (made in the loop).",
                  ""]
    else:
        lines += ["Training both to a val PSNR (`--train-steps N`) was not run.", ""]
    lines += ["## Every step time (s)", ""]
    for r in doc["configs"]:
        lines.append(f"- {r['name']}: mipnerf-cl {', '.join(f'{s:.3f}' for s in r['ours']['step_seconds'])}; "
                     f"official {', '.join(f'{s:.3f}' for s in r['official']['step_seconds'])}; load averages "
                     f"(1/5/15 min) before and after each round {r['load_average_per_round']}; "
                     f"official XLA compile + 2 warm-up steps {r['official_compile_s']:.1f} s; "
                     f"our GEMM in training: {our_gemm_label(r)}")
    lines += ["", "## Machine and versions", "",
              f"- CPU: {v['machine']['cpu']}, {v['machine']['hardware_threads']} hardware threads; "
              f"{v['machine']['platform']}",
              f"- load average (1/5/15 min): before {doc['load_average_before']}, after {doc['load_average_after']}"
              " (the machine is shared; other work was running, see per-round figures)",
              f"- mipnerf-cl: commit {v['mipnerf-cl']}; OpenCL device {v['machine']['opencl_device']}, "
              f"PoCL {v['machine']['pocl']}, CLBlast {v['machine']['clblast']}",
              f"- official: google/mipnerf {v['official_commit']}; python {v['python']}, jax {v['jax']}, "
              f"jaxlib {v['jaxlib']}, flax {v['flax']}, optax {v['optax']}, numpy {v['numpy']}, "
              f"gin-config {v['gin']}; XLA CPU devices {v['jax_devices']}", "",
              "## Configurations", ""]
    for r in doc["configs"]:
        lines += [f"### {r['name']}", "",
                  f"- mipnerf-cl (`bench.json` config): `{json.dumps(r['our_config'], sort_keys=True)}`",
                  f"- our runs: `mipnerf-cl {r['our_runs'][0]['command']}`",
                  f"- official MipNerfModel: `{json.dumps(r['official_model'], sort_keys=True)}`",
                  f"- official MLP: `{json.dumps(r['official_mlp'], sort_keys=True)}`",
                  f"- official Config (train_step): `{json.dumps(r['official_config'], sort_keys=True)}`", ""]
    lines += ["## Stand-ins for the official code's imports (in the worker's memory; its files are unchanged)", ""]
    lines += [f"- `{s['name']}`: {s['what']}" for s in doc["stubs"]]
    lines += ["", "## What is identical and what is not", "", IDENTICAL, ""]
    return "\n".join(lines)


IDENTICAL = """\
Identical: the network (same layer shapes; the parameter counts are compared and printed), samples
per level, two levels through one shared MLP, IPE degrees, view encoding (degrees 0..3 + identity),
softplus density with bias -1, padded sigmoid colour, resample padding 0.01 with blur-pool, stratified
randomized sampling, near 2 / far 6, white background, the loss (coarse_loss_mult x coarse MSE + fine
MSE, lossmult-weighted, lossmult = 1 at one scale), Adam (b1 0.9, b2 0.999, eps 1e-8), float32, the
scene (lego at the same factor, box-downsampled on both sides), the batch size, the 2 CPU cores.

Not identical:
- Batches: ours draws its rays on the device inside the step (part of our timed step); the official
  step gets one of 8 batches of random rays over all images prepared beforehand, copied to the device
  before its timer starts (train_step donates it), so data loading is excluded on its side (train.py
  prefetches batches in a thread, so this is close to what it does in training). Random numbers differ.
- The official train_step also computes gradient statistics (norm, max) and a pmean over one device,
  as train.py does; it is pmapped over the single CPU device like train.py. Weight decay is 0 (skipped
  at trace time in neither: it is multiplied by 0 as in train.py).
- Adam: optax.adam inside a flax.optim stand-in instead of the removed flax.optim.Adam (same update).
- Our step times come from `mipnerf-cl bench` (a fresh process per round; the cold first step and
  kernel builds excluded); the official steps from one long-lived process (XLA compile excluded).
- Rendering: the official render goes through models.render_image with a pmapped eval function as in
  train.py, randomized = False, with the chunk size set to ours; both networks are the ones after
  each side's few timed steps (the cost of a render does not depend on the weights).
- XLA and PoCL choose their own threading on the 2 cores; neither is pinned.
"""


def orchestrate(args):
    started = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    t0 = time.time()
    py = ensure_venv(args)
    load_before = load_average()
    worker = Worker(py, args)
    versions = worker.call(cmd="versions")
    results = [bench_config(args, worker, name, preset, batch)
               for name, preset, batch in CONFIGS if name in args.configs]
    versions["machine"] = {"cpu": cpu_model(), "hardware_threads": os.cpu_count(),
                           "platform": platform.platform(), **results[0]["device"]}
    versions["mipnerf-cl"] = git_commit()
    versions["official_commit"] = args.official_commit or official_commit(args.official)
    write_results(args, results, None, versions, load_before, load_average(), started, time.time() - t0)
    if args.train_steps > 0:  # long: the timing results above are written first
        quick = [r for r in results if r["name"] == "quick"]
        if not quick:
            fail("--train-steps needs the quick configuration in --configs")
        training = train_psnr(args, worker, quick[0])
        write_results(args, results, training, versions, load_before, load_average(), started, time.time() - t0)
    worker.close()


# ----------------------------------------------------------------------------------------------
# Worker side (runs in the venv; imports jax and the official code)
# ----------------------------------------------------------------------------------------------

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
        gin.clear_config()
        bindings = [f"MipNerfModel.{k} = {gin_value(v)}" for k, v in model.items()]
        bindings += [f"MLP.{k} = {gin_value(v)}" for k, v in mlp.items()]
        gin.parse_config(bindings)
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


def worker_main(args):
    try:
        off = Official(args.official, args.data, args.factor)
    except Exception as e:  # report the first failure to the orchestrator in one line
        import traceback
        traceback.print_exc()
        print(json.dumps({"error": f"importing the official code: {e!r}"}), flush=True)
        return
    for line in sys.stdin:
        req = json.loads(line)
        try:
            cmd = req.pop("cmd")
            if cmd == "versions":
                reply = off.versions()
            elif cmd == "setup":
                reply = off.setup(**req)
            elif cmd == "steps":
                reply = {"seconds": off.steps(req["n"])}
            elif cmd == "render":
                reply = off.render(req["reps"], req["chunk"])
            elif cmd == "train":
                reply = off.train_and_score(**req)
            else:
                reply = {"error": f"unknown request {cmd}"}
        except Exception as e:
            import traceback
            traceback.print_exc()
            reply = {"error": repr(e)}
        print(json.dumps(reply), flush=True)


def main(argv):
    args = parse_args(argv)
    if args.worker:
        worker_main(args)
    elif args.report_only:
        with open(args.report_only) as f:
            doc = json.load(f)
        with open(os.path.splitext(args.report_only)[0] + ".md", "w") as f:
            f.write(markdown(doc))
    else:
        orchestrate(args)


if __name__ == "__main__":
    main(sys.argv[1:])
