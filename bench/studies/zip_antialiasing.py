#!/usr/bin/env python3
"""Does Zip-NeRF's anti-aliasing hold? PSNR per scale on multiscale Blender at equal training time.

Issue 46 asks that Zip-NeRF's multisampling and footprint downweighting be visible in the numbers: trained on
multiscale lego (the paper's box-downsampled x1 x2 x4 x8 copies, trained together with the area-weighted loss), the
model is scored at every scale beside
  - a plain hash grid: the same grid and MLP, one point per interval at the frustum's mean, no footprint weights, no
    scale feature (`grid_multisample=false grid_downweight=false grid_append_scale=false`): instant-ngp's lookup;
  - mip-NeRF at its quick preset (IPE: the paper's anti-aliasing, a large MLP).
The bar (issue 46, "done when"): Zip-NeRF >= the plain grid + 1 dB at the x4 and x8 scales.

Equal time, robust to a shared machine: each model's warm s/step is probed first, the probes interleaved (A B C A B C,
the lower of each model's two medians kept), and each model then trains for steps = budget / its s/step (the
learning-rate schedule spans them, as `train --minutes` does). The wall time each run actually took is recorded
beside its budget. Every run goes through the command-line tool; finished runs and evaluations are reused.

  /usr/bin/python3 bench/studies/zip_antialiasing.py --lego ../shared/data/nerf_synthetic/lego --minutes 6
  /usr/bin/python3 bench/studies/zip_antialiasing.py --lego ../shared/data/nerf_synthetic/lego --minutes 15 \
      --only zip,plain --name zip_antialiasing_15min --work /tmp/mipnerf-zip-antialiasing-15
  /usr/bin/python3 bench/studies/zip_antialiasing.py --lego ../shared/data/nerf_synthetic/lego --minutes 15 \
      --only zip,plain,wide --name zip_antialiasing_footprint --work /tmp/mipnerf-zip-antialiasing-footprint
  python3 bench/studies/zip_antialiasing.py --report-only [--name NAME]   (the .md again from the .json)
"""

import os
import shlex
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import commit_of, device_line, read_json, run, warm_seconds_per_step  # noqa: E402
from lib.machine import load_average  # noqa: E402

RESULTS = report_md.results_folder("zip_antialiasing")
SCRIPT = "bench/studies/zip_antialiasing.py"
PROBE_STEPS = 12
SCALE_NAMES = {1: "full", 2: "1/2", 4: "1/4", 8: "1/8"}

PLAIN = "--set grid_multisample=false --set grid_downweight=false --set grid_append_scale=false"
# (key, label, train arguments, how its steps are set): "budget" = budget / its own probed s/step (the three probed
# together); ("paired", K) = model K's steps × K's s/step / its own, from probes interleaved with K's (run later);
# ("steps_of", K) = model K's step count (equal steps, not equal time).
# "zip" is the fast preset as it stands: one footprint-weighted point per interval since 2026-11-28 (the committed 6-minute
# record's "zip" row was the preset before, with six multisamples: "zip6" now).
MODELS = [
    ("zip", "Zip-NeRF fast (one footprint-weighted point)", "--model zipnerf", "budget"),
    ("zip6", "Zip-NeRF fast, 6 multisamples", "--model zipnerf --set grid_multisample=true", "budget"),
    ("plain", "plain hash grid (fast, one point, no downweighting)", "--model zipnerf " + PLAIN, "budget"),
    ("mip", "mip-NeRF quick", "--preset quick", "budget"),
    ("point", "one point per interval, footprint-weighted (fast)", "--model zipnerf --set grid_multisample=false",
     ("paired", "plain")),
    ("plain_steps", "plain hash grid at Zip-NeRF's steps (equal steps)", "--model zipnerf " + PLAIN,
     ("steps_of", "zip")),
    # The fast preset's one point stands for six multisamples; their average blurs by each point's own footprint
    # (0.5 · ρ, ρ = √½·r·t their distance from the axis) and by the hexagon's spread (variance ρ²/2 per axis): together
    # √3 times the point's own. grid_scale_mult 0.866 = √3 · 0.5 gives the one point that whole footprint.
    ("wide", "fast, one point with the six's whole footprint (grid_scale_mult 0.866)",
     "--model zipnerf --set grid_scale_mult=0.866", "budget"),
]


def add_arguments(parser):
    parser.add_argument("--build", default="build", help="build folder holding mipnerf-cl")
    parser.add_argument("--work", default="/tmp/mipnerf-zip-antialiasing", help="runs and logs")
    parser.add_argument("--lego", required=False, help="Blender lego (e.g. ../shared/data/nerf_synthetic/lego)")
    parser.add_argument("--factor", type=int, default=1, help="the full scale's downsampling (1: 400x400 lego)")
    parser.add_argument("--minutes", type=float, default=6.0, help="training budget of every model")
    parser.add_argument("--views", type=int, default=4, help="val views scored at every scale")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only", help="comma-separated model keys (zip, zip6, plain, mip, point, plain_steps, wide)")
    parser.add_argument("--name", default="zip_antialiasing",
                        help="the record's name: bench/results/zip_antialiasing/NAME.json and .md (one per budget)")


def train_base(args, out, model_args):
    return [args.exe, "train", "--data", args.lego, "--out", out, *shlex.split(model_args),
            "--set", f"factor={args.factor}", "--set", "multiscale=true", "--set", f"seed={args.seed}"]


def probe(args, key, model_args, round_index, log):
    out = os.path.join(args.work, key, f"probe{round_index}")
    if not os.path.exists(os.path.join(out, "summary.json")):
        run(["rm", "-rf", out], log)
        run(train_base(args, out, model_args) + ["--set", f"steps={PROBE_STEPS}", "--set", "log_every=1",
                                                 "--set", "val_views=1", "--set", "val_every=0"], log)
    return warm_seconds_per_step(out)


def train(args, key, model_args, steps, log):
    out = os.path.join(args.work, key, "run")
    summary = os.path.join(out, "summary.json")
    if not (os.path.exists(summary) and not read_json(summary).get("interrupted", True)):
        resume = os.path.isdir(os.path.join(out, "checkpoints")) and os.listdir(os.path.join(out, "checkpoints"))
        command = train_base(args, out, model_args) + ["--set", f"steps={steps}", "--set", "val_views=1",
                                                       "--set", "val_every=0"]
        load_before = load_average()
        run(command + (["--resume"] if resume else []), log)
        with open(os.path.join(out, "load.txt"), "w") as f:
            f.write(f"{load_before} {load_average()}\n")
    return out


def evaluate(args, run_dir, log):
    out = os.path.join(run_dir, "eval_val")
    if not os.path.exists(os.path.join(out, "metrics.json")):
        run([args.exe, "eval", "--checkpoint", run_dir, "--split", "val", "--views", str(args.views), "--out", out,
             "--no-images"], log)
    return read_json(os.path.join(out, "metrics.json"))


def steps_of(args, models, probes, rows_by_key, key, rule, log):
    """The step count of model `key` by its rule (MODELS), probing what the rule needs."""
    budget_s = 60.0 * args.minutes
    if rule == "budget":
        return max(1, int(budget_s // min(probes[key]))), "budget / its probed s/step"
    kind, other = rule
    if kind == "steps_of":
        return rows_by_key[other]["steps"], f"{other}'s steps"
    other_args = next(m[2] for m in models if m[0] == other)
    own_args = next(m[2] for m in models if m[0] == key)
    pair, own = [], []
    for round_index in range(2):  # interleaved with the other model's fresh probes
        pair.append(probe(args, other, other_args, 2 + round_index, log))
        own.append(probe(args, key, own_args, round_index, log))
    probes[key] = own
    rows_by_key[other]["paired_probe_seconds_per_step"] = pair
    steps = max(1, int(rows_by_key[other]["steps"] * min(pair) / min(own)))
    return steps, f"{other}'s steps × {other}'s s/step / its own (probes interleaved)"


def measure(args):
    if not args.lego:
        sys.exit("zip_antialiasing: --lego FOLDER is needed to measure (or --report-only)")
    args.exe = os.path.abspath(os.path.join(args.build, "mipnerf-cl"))
    args.lego = os.path.abspath(args.lego)
    args.work = os.path.abspath(args.work)
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "study.log")
    models = [m for m in MODELS if not args.only or m[0] in args.only.split(",")]
    started = time.time()
    probes = {key: [] for key, _, _, rule in models if rule == "budget"}
    for round_index in range(2):
        for key, _, model_args, rule in models:
            if rule == "budget":
                probes[key].append(probe(args, key, model_args, round_index, log))
    rows_by_key = {}
    for key, label, model_args, rule in models:
        steps, steps_rule = steps_of(args, models, probes, rows_by_key, key, rule, log)
        run_dir = train(args, key, model_args, steps, log)
        summary = read_json(os.path.join(run_dir, "summary.json"))
        metrics = evaluate(args, run_dir, log)
        rows_by_key[key] = {
            "key": key, "label": label, "arguments": model_args, "steps_rule": steps_rule,
            "probe_seconds_per_step": probes.get(key, []),
            "steps": summary["steps"], "train_seconds": summary["train_seconds"], "parameters": summary["parameters"],
            "psnr_by_scale": {str(x["downsampling"]): x["psnr"] for x in metrics["scales"]},
            "ssim_by_scale": {str(x["downsampling"]): x["ssim"] for x in metrics["scales"]},
            "mean_psnr": metrics["mean"]["psnr"], "mean_ssim": metrics["mean"]["ssim"],
            "render_seconds_per_megapixel": metrics["render"]["seconds_per_megapixel"],
            "device": metrics["device"],
        }
    return {
        "study": "zip_antialiasing", "name": args.name, "date": time.strftime("%Y-%m-%d", time.gmtime()), "commit": commit_of(),
        "scene": f"lego (nerf_synthetic), factor {args.factor}, multiscale x1 x2 x4 x8, {args.views} val views",
        "budget_minutes": args.minutes, "seed": args.seed, "probe_steps": PROBE_STEPS,
        "wall_seconds": round(time.time() - started, 1), "rows": list(rows_by_key.values()),
    }


def write_markdown(record):
    rows = record["rows"]
    scales = sorted({int(k) for r in rows for k in r["psnr_by_scale"]})
    header = (["model"] + [f"PSNR {SCALE_NAMES.get(s, '1/' + str(s))}" for s in scales]
              + ["mean PSNR", "mean SSIM", "steps", "steps set by", "train s", "render s/MP", "parameters"])
    body = [[r["label"]] + [f"{r['psnr_by_scale'][str(s)]:.2f}" for s in scales]
            + [f"{r['mean_psnr']:.2f}", f"{r['mean_ssim']:.4f}", str(r["steps"]),
               r.get("steps_rule", "budget / its probed s/step"), f"{r['train_seconds']:.0f}",
               f"{r['render_seconds_per_megapixel']:.1f}", str(r["parameters"])] for r in rows]
    lines = [report_md.generated_banner(SCRIPT, record.get("name", "zip_antialiasing") + ".json"), "",
             "# Zip-NeRF's anti-aliasing on multiscale Blender, at equal training time", "",
             f"{record['scene']}; a budget of {record['budget_minutes']:g} minutes per model (steps = budget / the "
             f"model's probed warm s/step, probes interleaved), seed {record['seed']}; device "
             f"{device_line(rows[0]['device'])}; commit {record['commit']}; {record['date']}.", ""]
    lines += report_md.table(header, "l" + "r" * (len(header) - 1), body)
    by_key = {r["key"]: r for r in rows}
    against = [k for k in ("zip", "zip6", "point", "wide", "plain_steps") if k in by_key]
    if "plain" in by_key and against:
        lines += ["", "Each minus the plain grid at equal time, per scale (issue 46's bar for Zip-NeRF: >= +1 dB at 1/4 "
                  "and 1/8):", ""]
        gains = [[SCALE_NAMES.get(s, str(s))]
                 + [f"{by_key[k]['psnr_by_scale'][str(s)] - by_key['plain']['psnr_by_scale'][str(s)]:+.2f} dB"
                    for k in against] for s in scales]
        lines += report_md.table(["scale"] + [f"{by_key[k]['label']} - plain" for k in against],
                                 "l" + "r" * len(against), gains)
    probes = ", ".join(f"{r['key']} {min(r['probe_seconds_per_step']):.3f}" for r in rows if r["probe_seconds_per_step"])
    paired = ", ".join(f"{r['key']} {min(r['paired_probe_seconds_per_step']):.3f}" for r in rows
                       if r.get("paired_probe_seconds_per_step"))
    lines += ["", f"Probed warm s/step (the lower of two interleaved {record['probe_steps']}-step probes): {probes}"
              + (f"; probed again beside the paired model: {paired}" if paired else "") + ".",
              f"Study wall time {record['wall_seconds'] / 60:.1f} minutes."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "zip_antialiasing", SCRIPT, add_arguments, measure, write_markdown)
