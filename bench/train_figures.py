#!/usr/bin/env python3
"""Training figures: val PSNR after fixed step counts, with wall time and rays/s, for mip-NeRF and the NeRF
baseline, on the built-in procedural scene (64x64) and on lego at 100x100 (x4 box-downsampled).

Each run trains once with a checkpoint every --every steps (all kept); each checkpoint is then evaluated on
val views. Wall time and rays/s at a step come from the run's train_log.csv. Everything goes through the
command-line tool, as a user would run it; finished runs and evaluations are reused.

Example (the committed results were made with this):
  python3 bench/train_figures.py --build build --work /tmp/figures --results bench/results \
      --steps 600 --every 200 --views 4 --lego ../shared/data/nerf_synthetic/lego      (about 22 minutes)
"""

import argparse
import csv
import datetime
import glob
import os
import sys

from study_common import device_line, procedural_scene, read_json, run


def checkpoints(run_dir):
    found = []
    for path in glob.glob(os.path.join(run_dir, "checkpoints", "ckpt_*.mnck")):
        found.append((int(os.path.basename(path)[5:14]), path))
    return sorted(found)


def log_rows(run_dir):
    with open(os.path.join(run_dir, "train_log.csv")) as f:
        return {int(r["step"]): r for r in csv.DictReader(f)}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default="build")
    parser.add_argument("--work", default="/tmp/mipnerf-train-figures")
    parser.add_argument("--results", default="bench/results")
    parser.add_argument("--lego", help="Blender lego folder; omitted: procedural scene only")
    parser.add_argument("--preset", default="quick")
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--every", type=int, default=250, help="steps between evaluated checkpoints")
    parser.add_argument("--views", type=int, default=4, help="val views evaluated per checkpoint")
    args = parser.parse_args()
    exe = os.path.abspath(os.path.join(args.build, "mipnerf-cl"))
    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    os.makedirs(args.results, exist_ok=True)

    scenes = [("procedural 64x64", procedural_scene(exe, work), {})]
    if args.lego:
        scenes.append(("lego 100x100", os.path.abspath(args.lego), {"factor": "4"}))
    rows, device = [], None
    for scene, data, settings in scenes:
        for variant in ("mipnerf", "nerf"):
            run_dir = os.path.join(work, scene.split()[0], variant)
            log = run_dir + ".log"
            if not os.path.exists(os.path.join(run_dir, "summary.json")):
                command = [exe, "train", "--data", data, "--out", run_dir, "--preset", args.preset, "--variant",
                           variant, "--resume", "--steps", str(args.steps), "--checkpoint_every", str(args.every),
                           "--log_every", str(args.every), "--keep_checkpoints", "1000", "--val_views", "1"]
                for k, v in settings.items():
                    command += ["--set", f"{k}={v}"]
                print(f"[{datetime.datetime.now():%H:%M:%S}] train {scene} {variant}", flush=True)
                run(command, log)
            summary = read_json(os.path.join(run_dir, "summary.json"))
            logged = log_rows(run_dir)
            for step, path in checkpoints(run_dir):
                out = os.path.join(run_dir, f"eval_val_{step}")
                if not os.path.exists(os.path.join(out, "metrics.json")):
                    print(f"[{datetime.datetime.now():%H:%M:%S}] eval {scene} {variant} step {step}", flush=True)
                    run([exe, "eval", "--checkpoint", path, "--data", data, "--split", "val", "--views",
                         str(args.views), "--out", out, "--no-images"], log)
                m = read_json(os.path.join(out, "metrics.json"))
                device = device or m["device"]
                r = logged.get(step, {})
                rows.append({"scene": scene, "variant": variant, "step": step, "parameters": summary["parameters"],
                             "wall_seconds": float(r.get("wall_seconds", "nan")),
                             "rays_per_second": float(r.get("rays_per_second", "nan")),
                             "val_psnr": m["mean"]["psnr"], "val_ssim": m["mean"]["ssim"],
                             "render_seconds_per_megapixel": m["render"]["seconds_per_megapixel"]})

    date = datetime.date.today().isoformat()
    text = ("# Training figures\n\n"
            f"Made by `bench/train_figures.py` on {device_line(device)}, {date}. Preset `{args.preset}` "
            f"(batch and network in README, Presets), {args.steps} steps, evaluated every {args.every} steps on "
            f"{args.views} val views. Wall s: training time up to that step (`train_log.csv`, compile time included); "
            "rays/s: over the last logging window.\n\n"
            "| scene | variant | step | wall s | rays/s | val PSNR | val SSIM | render s/MP | parameters |\n"
            "|---|---|---:|---:|---:|---:|---:|---:|---:|\n")
    for r in rows:
        text += (f"| {r['scene']} | {r['variant']} | {r['step']} | {r['wall_seconds']:.0f} | {r['rays_per_second']:.0f} "
                 f"| {r['val_psnr']:.2f} | {r['val_ssim']:.4f} | {r['render_seconds_per_megapixel']:.1f} | "
                 f"{r['parameters']} |\n")
    with open(os.path.join(args.results, "train_figures.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    sys.exit(main())
