#!/usr/bin/env python3
"""Training figures: val PSNR after fixed step counts, with wall time and rays/s, for mip-NeRF and the NeRF
baseline, on the built-in procedural scene (64x64) and on lego at 100x100 (x4 box-downsampled).

Each run trains once with a checkpoint every --every steps (all kept); each checkpoint is then evaluated on
val views. Wall time and rays/s at a step come from the run's train_log.csv. Everything goes through the
command-line tool, as a user would run it; finished runs and evaluations are reused.

Example (the committed results were made with this):
  python3 bench/studies/train_figures.py --build build --work /tmp/figures --results bench/results/train_figures \
      --steps 600 --every 200 --views 4 --lego ../shared/data/nerf_synthetic/lego      (about 22 minutes)

Writes bench/results/train_figures/train_figures.json (every row) and train_figures.md generated from it (write_markdown);
`--report-only` regenerates the .md from the .json; hand-written notes go under "## Notes (by hand)" at the end of
the .md, which regeneration keeps. (The committed train_figures.md predates the .json: it has no raw data.)
"""

import argparse
import csv
import datetime
import glob
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import device_line, procedural_scene, read_json, run  # noqa: E402


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
    parser.add_argument("--results", default=report_md.results_folder("train_figures"))
    parser.add_argument("--lego", help="Blender lego folder; omitted: procedural scene only")
    parser.add_argument("--preset", default="quick")
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--every", type=int, default=250, help="steps between evaluated checkpoints")
    parser.add_argument("--views", type=int, default=4, help="val views evaluated per checkpoint")
    parser.add_argument("--report-only", action="store_true",
                        help="only regenerate train_figures.md from train_figures.json in --results (no runs; its "
                             "'## Notes (by hand)' section is kept)")
    args = parser.parse_args()
    if args.report_only:
        path = os.path.join(args.results, "train_figures.json")
        if not os.path.exists(path):
            sys.exit(f"train_figures: no {path}: results made before 2026-11-26 have no .json; run the study again")
        write_report(read_json(path), args.results)
        print(f"train_figures: wrote {args.results}/train_figures.md from train_figures.json")
        return
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

    record = {"date": datetime.date.today().isoformat(), "device": device, "preset": args.preset,
              "steps": args.steps, "every": args.every, "views": args.views, "rows": rows}
    with open(os.path.join(args.results, "train_figures.json"), "w") as f:
        json.dump(record, f, indent=2)
        f.write("\n")
    print(write_report(record, args.results))


def write_markdown(record):
    """train_figures.md, generated from train_figures.json alone."""
    text = ("# Training figures\n\n"
            + report_md.generated_banner("bench/studies/train_figures.py", "train_figures.json") + "\n\n"
            f"Made by `bench/studies/train_figures.py` on {device_line(record['device'])}, {record['date']}. Preset "
            f"`{record['preset']}` (batch and network in README, Presets), {record['steps']} steps, evaluated every "
            f"{record['every']} steps on {record['views']} val views. Wall s: training time up to that step "
            "(`train_log.csv`, compile time included); rays/s: over the last logging window.\n\n")
    table = report_md.table(
        ["scene", "variant", "step", "wall s", "rays/s", "val PSNR", "val SSIM", "render s/MP", "parameters"],
        "llrrrrrrr",
        [[r["scene"], r["variant"], str(r["step"]), f"{r['wall_seconds']:.0f}", f"{r['rays_per_second']:.0f}",
          f"{r['val_psnr']:.2f}", f"{r['val_ssim']:.4f}", f"{r['render_seconds_per_megapixel']:.1f}",
          str(r["parameters"])] for r in record["rows"]])
    return text + "\n".join(table) + "\n"


def write_report(record, results):
    return report_md.write_report(os.path.join(results, "train_figures.md"), write_markdown(record),
                                  f"python3 bench/studies/train_figures.py --results {results} --report-only")


if __name__ == "__main__":
    sys.exit(main())
