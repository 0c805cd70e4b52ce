#!/usr/bin/env python3
"""What accuracy costs in time: train and evaluate a matrix of settings at equal step budgets.

Trains mip-NeRF with 16, 32, 64 and 128 samples per level, the NeRF baseline, and NeRF with 4x jittered
supersampling (trained on rays through random points of their pixels, evaluated with 4 jittered rays per
pixel, supplement section 6) on multiscale scenes, then evaluates each on every scale. Writes, per scene, a
table like the supplement's table 1 (PSNR per scale, SSIM, train time, render s/MP, parameter count) and a
plot of mean PSNR against training time (SVG, drawn with matplotlib), plus everything measured as JSON.

Needs matplotlib: bench/setup.sh installs it (Debian's python3-matplotlib; run the script with /usr/bin/python3
when another python3 comes first in PATH). --plot-only redraws the plot from the JSON in --results alone.

Every run goes through the real command-line tool (mipnerf-cl train / eval), so the figures are what a user
gets. Runs that already finished (their summary.json / metrics.json exist) are reused, so an interrupted
study continues where it stopped.

Example (the committed results were made with this):
  python3 bench/studies/accuracy_time.py --build build --work /tmp/study --results bench/results/accuracy_time \
      --steps 400 --lego-views 2 --lego ../shared/data/nerf_synthetic/lego      (about 95 minutes on 2 CPU cores)
  python3 bench/studies/accuracy_time.py --results bench/results/accuracy_time --plot-only                 (the plot again, seconds)
  python3 bench/studies/accuracy_time.py --results bench/results/accuracy_time --report-only               (the .md again from the JSON)

The .md is generated from the JSON (write_markdown); hand-written notes go under "## Notes (by hand)" at its end,
which regeneration keeps.
"""

import argparse
import datetime
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import device_line, procedural_scene, read_json, run  # noqa: E402

# (key, label, variant, settings, supersample at evaluation)
CONFIGS = [
    ("mip16", "mip-NeRF, 16 samples", "mipnerf", {"num_samples": 16}, 1),
    ("mip32", "mip-NeRF, 32 samples", "mipnerf", {"num_samples": 32}, 1),
    ("mip64", "mip-NeRF, 64 samples", "mipnerf", {"num_samples": 64}, 1),
    ("mip128", "mip-NeRF, 128 samples", "mipnerf", {"num_samples": 128}, 1),
    ("nerf", "NeRF (32 + 64 samples)", "nerf", {"num_samples": 64}, 1),
    ("nerf_ss4", "NeRF + 4x jittered supersampling", "nerf", {"num_samples": 64, "jitter_pixels": "true"}, 4),
]

SCALE_NAMES = {1: "full", 2: "1/2", 4: "1/4", 8: "1/8"}


def scenes(args):
    """(name, data path, extra train settings, eval split, eval views) of each scene of the study."""
    out = []
    procedural = procedural_scene(args.exe, args.work)
    out.append(("procedural", os.path.join(procedural, "multiscale"), {}, "test", args.procedural_views))
    if args.lego:
        # Lego at 200x200 (x2 box-downsampled), with x2 x4 x8 copies built on the fly: 200/100/50/25 pixels.
        out.append(("lego", os.path.abspath(args.lego), {"factor": "2", "multiscale": "true"}, "val",
                    args.lego_views))
    return out


def train_and_eval(args, scene, config):
    name, data, scene_settings, split, views = scene
    key, label, variant, settings, supersample = config
    run_dir = os.path.join(args.work, name, key)
    log = os.path.join(args.work, name, key + ".log")
    os.makedirs(os.path.dirname(log), exist_ok=True)
    summary = os.path.join(run_dir, "summary.json")
    if not os.path.exists(summary):
        command = [args.exe, "train", "--data", data, "--out", run_dir, "--preset", args.preset,
                   "--variant", variant, "--resume", "--steps", str(args.steps), "--batch_size", str(args.batch_size),
                   "--val_views", "1"]
        for k, v in {**args.base_settings, **scene_settings, **settings}.items():
            command += ["--set", f"{k}={v}"]
        run(command, log)
    metrics_dir = os.path.join(run_dir, "eval_" + split)
    metrics = os.path.join(metrics_dir, "metrics.json")
    if not os.path.exists(metrics):
        run([args.exe, "eval", "--checkpoint", run_dir, "--split", split, "--views", str(views), "--out", metrics_dir,
             "--supersample", str(supersample), "--no-images"], log)
    s = read_json(summary)
    m = read_json(metrics)
    return {
        "key": key, "label": label, "variant": variant, "settings": settings, "eval_supersample": supersample,
        "train_seconds": s["train_seconds"], "steps": s["steps"], "parameters": s["parameters"],
        "psnr_by_scale": {str(x["downsampling"]): x["psnr"] for x in m["scales"]},
        "ssim_by_scale": {str(x["downsampling"]): x["ssim"] for x in m["scales"]},
        "mean_psnr": m["mean"]["psnr"], "mean_ssim": m["mean"]["ssim"],
        "render_seconds_per_megapixel": m["render"]["seconds_per_megapixel"],
        "eval_views": views, "eval_split": split, "device": m["device"],
    }


def markdown(scene_name, rows, meta):
    scales = sorted({int(k) for r in rows for k in r["psnr_by_scale"]})
    header = (["setting"] + [f"PSNR {SCALE_NAMES.get(s, '1/' + str(s))}" for s in scales]
              + ["mean PSNR", "mean SSIM", "train s", "render s/MP", "parameters"])
    body = [[r["label"]] + [f"{r['psnr_by_scale'].get(str(s), float('nan')):.2f}" for s in scales]
            + [f"{r['mean_psnr']:.2f}", f"{r['mean_ssim']:.4f}", f"{r['train_seconds']:.0f}",
               f"{r['render_seconds_per_megapixel']:.1f}", str(r["parameters"])] for r in rows]
    table = report_md.table(header, "l" + "r" * (len(header) - 1), body)
    return f"### {scene_name}\n\n{meta}\n\n" + "\n".join(table) + "\n\n"


def import_pyplot():
    """matplotlib's pyplot on the Agg backend (no display needed), or an error that says how to install it."""
    try:
        import matplotlib
    except ImportError:
        sys.exit("accuracy_time: matplotlib is missing: run bench/setup.sh (Debian package python3-matplotlib); if "
                 "another python3 comes first in PATH (pyenv, a venv), run this script with /usr/bin/python3")
    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot
    return pyplot


def plot(title, series_by_scene, path):
    """Mean PSNR against training seconds (log axis), one colour per scene, one labelled point per setting:
    mip-NeRF's sample counts as filled circles joined in time order, the NeRF settings as open squares."""
    pyplot = import_pyplot()
    # Text stays text in the SVG, and no date or random ids, so redrawing the same results gives the same file.
    pyplot.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "accuracy_time", "font.size": 10})
    figure, axes = pyplot.subplots(figsize=(8.0, 4.8))
    colours = pyplot.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (scene, rows) in enumerate(series_by_scene.items()):
        colour = colours[i % len(colours)]
        mip = sorted([r for r in rows if r["variant"] == "mipnerf"], key=lambda r: r["train_seconds"])
        nerf = [r for r in rows if r["variant"] != "mipnerf"]
        axes.plot([max(r["train_seconds"], 1.0) for r in mip], [r["mean_psnr"] for r in mip], "o-", color=colour,
                  label=f"{scene}: mip-NeRF")
        axes.plot([max(r["train_seconds"], 1.0) for r in nerf], [r["mean_psnr"] for r in nerf], "s", color=colour,
                  markerfacecolor="none", markeredgewidth=1.5, label=f"{scene}: NeRF")
        for r in rows:
            axes.annotate(r["key"], (max(r["train_seconds"], 1.0), r["mean_psnr"]), xytext=(5, 4),
                          textcoords="offset points", fontsize=8)
    axes.set_xscale("log")
    # Plain seconds at 1, 2, 3 and 5 × 10^n (the default "2×10²" labels read badly), unlabelled ticks between.
    ticker = pyplot.matplotlib.ticker
    axes.xaxis.set_major_locator(ticker.LogLocator(base=10.0, subs=(1.0, 2.0, 3.0, 5.0)))
    axes.xaxis.set_major_formatter(ticker.FuncFormatter(lambda seconds, _: f"{seconds:g}"))
    axes.xaxis.set_minor_locator(ticker.LogLocator(base=10.0, subs=(4.0, 6.0, 7.0, 8.0, 9.0)))
    axes.xaxis.set_minor_formatter(ticker.NullFormatter())
    axes.margins(x=0.08, y=0.08)  # room for the point labels inside the frame
    axes.set_xlabel("training time (s, log scale)")
    axes.set_ylabel("mean PSNR over scales (dB)")
    axes.set_title(title)
    axes.grid(True, which="major", color="#e4e4e4", linewidth=0.8)
    axes.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    figure.tight_layout()
    figure.savefig(path, format="svg", metadata={"Date": None})
    pyplot.close(figure)


def plot_title(device, date):
    return f"mean PSNR vs training time ({device.get('name')}, {date})"


def plot_only(results_folder):
    """Redraws the plot from the committed results (accuracy_time.json) without running the study."""
    results = read_json(os.path.join(results_folder, "accuracy_time.json"))
    path = os.path.join(results_folder, "accuracy_time.svg")
    plot(plot_title(results["device"], results["date"]), results["scenes"], path)
    print(f"accuracy_time: wrote {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default="build", help="build folder holding mipnerf-cl")
    parser.add_argument("--work", default="/tmp/mipnerf-accuracy-time", help="scenes, runs and logs")
    parser.add_argument("--results", default=report_md.results_folder("accuracy_time"), help="where the table, plot and JSON go")
    parser.add_argument("--lego", help="Blender lego folder (e.g. ../shared/data/nerf_synthetic/lego); omitted: "
                                       "procedural scene only")
    parser.add_argument("--preset", default="quick", help="network and schedule the settings start from")
    parser.add_argument("--steps", type=int, default=500, help="training steps of every run (equal budgets)")
    parser.add_argument("--batch-size", type=int, default=512)
    parser.add_argument("--procedural-views", type=int, default=8, help="test views evaluated (every scale)")
    parser.add_argument("--lego-views", type=int, default=4, help="val views evaluated (every scale)")
    parser.add_argument("--only", help="comma-separated config keys to run (default: all)")
    parser.add_argument("--set", action="append", default=[], help="extra setting for every run, name=value")
    parser.add_argument("--plot-only", action="store_true",
                        help="only redraw accuracy_time.svg from accuracy_time.json in --results (no runs)")
    parser.add_argument("--report-only", action="store_true",
                        help="only regenerate accuracy_time.md from accuracy_time.json in --results (no runs; its "
                             "'## Notes (by hand)' section is kept)")
    args = parser.parse_args()
    if args.report_only:
        return report_only(args.results)
    if args.plot_only:
        return plot_only(args.results)
    import_pyplot()  # before the runs: a missing matplotlib should not be found after an hour and a half
    args.exe = os.path.abspath(os.path.join(args.build, "mipnerf-cl"))
    args.work = os.path.abspath(args.work)
    args.base_settings = dict(s.split("=", 1) for s in args.set)
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(args.results, exist_ok=True)
    configs = [c for c in CONFIGS if not args.only or c[0] in args.only.split(",")]

    started = time.time()
    results = {}
    for scene in scenes(args):
        rows = []
        for config in configs:
            print(f"[{datetime.datetime.now():%H:%M:%S}] {scene[0]}: {config[1]}", flush=True)
            rows.append(train_and_eval(args, scene, config))
        results[scene[0]] = rows

    device = next(iter(results.values()))[0]["device"]
    date = datetime.date.today().isoformat()
    record = {"date": date, "device": device, "preset": args.preset, "steps": args.steps,
              "batch_size": args.batch_size, "settings": args.base_settings, "scenes": results,
              "study_seconds": time.time() - started}
    with open(os.path.join(args.results, "accuracy_time.json"), "w") as f:
        json.dump(record, f, indent=2)
    print(write_report(record, args.results))
    plot(plot_title(device, date), results, os.path.join(args.results, "accuracy_time.svg"))


def write_markdown(record):
    """accuracy_time.md, generated from accuracy_time.json alone."""
    device = record["device"]
    meta = (f"Device: {device_line(device)}; {record['date']}. "
            f"Preset `{record['preset']}` with {record['steps']} steps of {record['batch_size']} rays for every setting"
            + (f", plus {', '.join(f'{k}={v}' for k, v in record['settings'].items())}" if record["settings"] else "")
            + ". Train s: wall time of `mipnerf-cl train` (GEMM tuning file loaded). Render s/MP: `mipnerf-cl eval`, "
              "after its warm-up. PSNR per scale: mean over the evaluated views of that scale.")
    text = ("# What accuracy costs in time\n\n"
            + report_md.generated_banner("bench/studies/accuracy_time.py", "accuracy_time.json") + "\n\n"
            "Made by `bench/studies/accuracy_time.py` (see its header for the command). mip-NeRF is trained with the area loss "
            "on all scales; the NeRF baseline is the paper's: point samples, PE, two MLPs, no area loss. NeRF + 4x "
            "supersampling trains on rays through random points of their pixels and averages 4 jittered rays per "
            "pixel when evaluated. Every setting has the same step budget.\n\n")
    for scene, rows in record["scenes"].items():
        split, views = rows[0]["eval_split"], rows[0]["eval_views"]
        text += markdown(scene, rows, meta + f" Evaluated on {views} {split} views at every scale.")
    if record.get("study_seconds") is not None:
        text += (f"Study wall time: {record['study_seconds']:.0f} s (runs reused from an earlier invocation count "
                 "as 0).\n")
    return text


def write_report(record, results):
    return report_md.write_report(os.path.join(results, "accuracy_time.md"), write_markdown(record),
                                  f"python3 bench/studies/accuracy_time.py --results {results} --report-only")


def report_only(results_folder):
    """Regenerates accuracy_time.md from the committed results (accuracy_time.json) without running the study."""
    write_report(read_json(os.path.join(results_folder, "accuracy_time.json")), results_folder)
    print(f"accuracy_time: wrote {results_folder}/accuracy_time.md from accuracy_time.json")


if __name__ == "__main__":
    sys.exit(main())
