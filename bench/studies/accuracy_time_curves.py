#!/usr/bin/env python3
"""Accuracy against time as curves: val PSNR at regular points of training, against training seconds, for every
preset and for the variants of the paper's Table 3 and supplement §7, on lego.

Every run trains with `val_every` (steps between val scores, timed apart from training: val_log.csv) so that each
run is a curve of val PSNR against training seconds; `mipnerf-cl plot` draws them. Two scenes:

- lego box-downsampled by --factor (4: 100x100): the presets tiny, quick and small (mip-NeRF) and, at --preset
  (quick), the NeRF baseline, Table 3's NeRF rows (nerf-area, nerf-area-center, nerf-area-center-misc) and the
  concatenated-PE variant (mipnerf-concat-pe);
- the multiscale copy of the same (train --multiscale, --scales scales: 100/50/25 at factor 4): mip-NeRF, the NeRF
  rows and the concatenated PE at --preset, every run for the same steps: Table 3's rows and §7's alternative at
  equal steps, scored per scale like Table 3.

Writes bench/results/accuracy_time_curves/accuracy_time_curves.{md,json,svg} (+ accuracy_time_curves_multiscale.svg) and
bench/results/accuracy_time_curves/table3_concat_pe.md. Budget: --steps-scale multiplies every preset's steps (1 = each preset's own
schedule); --presets chooses which presets run. Resumable (finished runs are reused, interrupted ones resumed).
The .md reports are generated from the .json (write_markdown, table3_markdown); `--report-only` regenerates them
without training; hand-written notes go under "## Notes (by hand)" at the end of each .md, which regeneration keeps.

  python3 bench/studies/accuracy_time_curves.py --lego ../shared/data/nerf_synthetic/lego [--presets tiny,quick,small]
      [--steps-scale 1] [--points 10] [--val-views 2] [--work /tmp/mipnerf-curves] [--report-only]
"""

import argparse
import datetime
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import commit_of, read_json, read_val_log, train_resumable  # noqa: E402

PRESET_STEPS = {"tiny": 300, "quick": 600, "small": 2000}  # host/train/config.cpp presets()
TABLE3 = ["nerf", "nerf-area", "nerf-area-center", "nerf-area-center-misc", "mipnerf", "mipnerf-concat-pe"]


def plan(args):
    """(scene key, run name, preset, variant, settings) of every run."""
    runs = []
    single = {"factor": args.factor}
    multi = {"factor": args.factor, "multiscale": "true", "multiscale_scales": args.scales}
    for preset in args.presets:
        runs.append(("lego", f"{preset}-mipnerf", preset, "mipnerf", single))
    for variant in TABLE3:
        if variant != "mipnerf" or args.preset not in args.presets:
            runs.append(("lego", f"{args.preset}-{variant}", args.preset, variant, single))
    for variant in TABLE3:
        runs.append(("multiscale", f"{args.preset}-{variant}", args.preset, variant, multi))
    return runs


def measure(args):
    exe = os.path.abspath(args.exe)
    lego = os.path.abspath(args.lego)
    log = os.path.join(args.work, "study.log")
    out = []
    for scene, name, preset, variant, scene_settings in plan(args):
        steps = max(1, int(round(PRESET_STEPS[preset] * args.steps_scale)))
        settings = dict(scene_settings, steps=steps, val_every=max(1, steps // args.points),
                        val_views=args.val_views)
        run_dir = os.path.join(args.work, scene, name)
        print(f"curves: {scene} {name} ({steps} steps)", flush=True)
        summary, command = train_resumable(exe, lego, run_dir, preset, variant, settings, log)
        out.append({"scene": scene, "name": name, "preset": preset, "variant": variant, "steps": summary["steps"],
                    "train_seconds": summary["train_seconds"], "psnr": summary["val"]["mean_psnr"],
                    "ssim": summary["val"]["mean_ssim"], "scales": summary["val"].get("scales", []),
                    "render_s_per_mp": summary["val"]["render_seconds_per_megapixel"],
                    "parameters": summary["parameters"], "device": summary["device"],
                    "curve": read_val_log(run_dir), "run_dir": run_dir, "command": " ".join(command)})
    return out


def plot(exe, runs, scene, path, title):
    dirs = [r["run_dir"] for r in runs if r["scene"] == scene]
    subprocess.run([exe, "plot", *dirs, "--out", path, "--title", title, "--log-x"], check=True)


def write_markdown(record):
    """accuracy_time_curves.md, generated from accuracy_time_curves.json alone."""
    lines = [
        "# Accuracy against time as curves: presets and variants on lego",
        "",
        report_md.generated_banner("bench/studies/accuracy_time_curves.py", "accuracy_time_curves.json"),
        "",
        f"Device: {record['device']}. Date {record['date']}, commit {record['commit']}. Lego (400x400 in ../shared) "
        f"box-downsampled by {record['factor']} (100x100) and its multiscale copy ({record['scales']} scales, "
        f"train --multiscale). Every run scores its first {record['val_views']} val views (all their scales on the "
        f"multiscale scene) every steps/{record['points']} steps; the scoring is timed apart and not counted in the "
        "training seconds (val_log.csv of each run). Budget: each preset's own steps "
        f"x {record['steps_scale']}. Commands: accuracy_time_curves.json. The plots are drawn by "
        "`mipnerf-cl plot RUN... --out FILE.svg` from the runs' folders.",
        "",
        "Few val views make each point noisy (a few tenths of a dB); the machine is shared, so seconds carry that "
        "noise too.",
    ]
    for note in record.get("notes", []):  # notes recorded in the JSON (new ones go in the .md's hand section)
        lines += ["", note]
    lines += [
        "",
        "![lego x4: val PSNR against training seconds](accuracy_time_curves.svg)",
        "",
    ]
    lines += report_md.table(
        ["scene", "run", "preset", "variant", "steps", "train s", "final val PSNR", "SSIM", "render s/MP", "parameters"],
        "llllrrrrrr",
        [[r["scene"], r["name"], r["preset"], r["variant"], str(r["steps"]), f"{r['train_seconds']:.0f}",
          f"{r['psnr']:.2f}", f"{r['ssim']:.4f}", f"{r['render_s_per_mp']:.0f}", str(r["parameters"])]
         for r in record["runs"]])
    lines += ["", "Val PSNR at each scored point (training seconds: dB):", ""]
    for r in record["runs"]:
        points = ", ".join(f"{p['train_seconds']:.0f}: {p['val_psnr']:.2f}" for p in r["curve"])
        lines.append(f"- {r['scene']} {r['name']}: {points}")
    lines += ["", "![multiscale lego: val PSNR against training seconds](accuracy_time_curves_multiscale.svg)", ""]
    return "\n".join(lines)


def table3_markdown(record):
    """table3_concat_pe.md, generated from accuracy_time_curves.json alone."""
    runs = [r for r in record["runs"] if r["scene"] == "multiscale"]
    names = {0: "full", 1: "1/2", 2: "1/4", 3: "1/8"}
    levels = sorted({s["scale_level"] for r in runs for s in r["scales"]})
    lines = [
        "# Table 3's NeRF rows and supplement §7's concatenated PE, at equal steps on multiscale lego",
        "",
        report_md.generated_banner("bench/studies/accuracy_time_curves.py", "accuracy_time_curves.json"),
        "",
        f"Device: {record['device']}. Date {record['date']}, commit {record['commit']}. Lego box-downsampled by "
        f"{record['factor']} with its multiscale copy ({record['scales']} scales), preset `{record['preset']}` "
        f"({runs[0]['steps'] if runs else '?'} steps for every row), val PSNR per scale on the first "
        f"{record['val_views']} val views. The same runs as accuracy_time_curves.md's multiscale curves.",
        "",
        "Rows as the paper's Table 3 builds them, each one change more than the row above: `nerf` (the baseline: "
        "points, PE of degrees 0..9 + identity, two MLPs, ReLU density, plain sigmoid, corner pixels, no area loss), "
        "+ the area loss, + pixel centres at +0.5, + misc (softplus(x-1) density, widened sigmoid); then mip-NeRF, "
        "and §7's alternative: PE (L = 12) of the frustum Gaussian's mean concatenated with PE (L = 2) of the signed "
        "square roots of its full covariance's upper triangle (the off-diagonal lifted as the official lift_gaussian "
        "with diag=False does: all six entries are non-zero for a ray off the axes), 72 + 24 = 96 features like IPE.",
        "",
    ]
    header = ["row"] + [f"PSNR {names.get(l, l)}" for l in levels] + ["mean PSNR", "SSIM", "train s", "render s/MP"]
    rows = []
    for r in runs:
        by_level = {s["scale_level"]: s["mean_psnr"] for s in r["scales"]}
        rows.append([r["variant"]] + [f"{by_level[l]:.2f}" if l in by_level else "-" for l in levels]
                    + [f"{r['psnr']:.2f}", f"{r['ssim']:.4f}", f"{r['train_seconds']:.0f}", f"{r['render_s_per_mp']:.0f}"])
    lines += report_md.table(header, "l" + "r" * (len(header) - 1), rows)
    for note in record.get("table3_notes", []):
        lines += ["", note]
    lines.append("")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exe", default="build/mipnerf-cl")
    parser.add_argument("--lego", help="the lego scene folder (../shared/data/nerf_synthetic/lego)")
    parser.add_argument("--presets", default="tiny,quick,small")
    parser.add_argument("--preset", default="quick", help="the preset of the variants' runs")
    parser.add_argument("--steps-scale", type=float, default=1.0, help="the budget: x each preset's own steps")
    parser.add_argument("--points", type=int, default=10, help="val scores per run")
    parser.add_argument("--val-views", type=int, default=2)
    parser.add_argument("--factor", type=int, default=4)
    parser.add_argument("--scales", type=int, default=3)
    parser.add_argument("--work", default="/tmp/mipnerf-curves")
    parser.add_argument("--results", default=report_md.results_folder("accuracy_time_curves"))
    parser.add_argument("--report-only", action="store_true",
                        help="the .md reports again from the JSON (their '## Notes (by hand)' sections kept), and the "
                             "plots when the runs' folders still exist; no training")
    args = parser.parse_args()
    args.presets = args.presets.split(",")
    exe = os.path.abspath(args.exe)
    record_path = os.path.join(args.results, "accuracy_time_curves.json")
    if args.report_only:
        record = read_json(record_path)
    else:
        if not args.lego:
            parser.error("--lego is needed (the lego scene folder), unless --report-only")
        runs = measure(args)
        record = {"date": datetime.date.today().isoformat(), "commit": commit_of(), "device": runs[0]["device"],
                  "factor": args.factor, "scales": args.scales, "preset": args.preset, "presets": args.presets,
                  "steps_scale": args.steps_scale, "points": args.points, "val_views": args.val_views, "runs": runs}
        os.makedirs(args.results, exist_ok=True)
        with open(record_path, "w") as f:
            json.dump(record, f, indent=2)
            f.write("\n")
    runs_present = all(os.path.isdir(r["run_dir"]) for r in record["runs"])
    if runs_present:
        plot(exe, record["runs"], "lego", os.path.join(args.results, "accuracy_time_curves.svg"),
             f"lego x{record['factor']}: presets and variants")
        plot(exe, record["runs"], "multiscale", os.path.join(args.results, "accuracy_time_curves_multiscale.svg"),
             f"multiscale lego x{record['factor']}, {record['scales']} scales: {record['preset']} preset")
    else:
        print("curves: the runs' folders are gone, so the plots were not redrawn (mipnerf-cl plot reads them)")
    write_reports(record, args.results)
    print(f"curves: wrote {args.results}/accuracy_time_curves.md and table3_concat_pe.md"
          + (" and the plots" if runs_present else ""))


def write_reports(record, results):
    regen = f"python3 bench/studies/accuracy_time_curves.py --report-only --results {results}"
    report_md.write_report(os.path.join(results, "accuracy_time_curves.md"), write_markdown(record), regen)
    report_md.write_report(os.path.join(results, "table3_concat_pe.md"), table3_markdown(record), regen)


if __name__ == "__main__":
    main()
