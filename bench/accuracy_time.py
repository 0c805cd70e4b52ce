#!/usr/bin/env python3
"""What accuracy costs in time: train and evaluate a matrix of settings at equal step budgets.

Trains mip-NeRF with 16, 32, 64 and 128 samples per level, the NeRF baseline, and NeRF with 4x jittered
supersampling (trained on rays through random points of their pixels, evaluated with 4 jittered rays per
pixel, supplement section 6) on multiscale scenes, then evaluates each on every scale. Writes, per scene, a
table like the supplement's table 1 (PSNR per scale, SSIM, train time, render s/MP, parameter count) and a
plot of mean PSNR against training time (SVG), plus everything measured as JSON.

Every run goes through the real command-line tool (mipnerf-cl train / eval), so the figures are what a user
gets. Runs that already finished (their summary.json / metrics.json exist) are reused, so an interrupted
study continues where it stopped.

Example (the committed results were made with this):
  python3 bench/accuracy_time.py --build build --work /tmp/study --results bench/results \
      --steps 400 --lego-views 2 --lego ../shared/data/nerf_synthetic/lego      (about 95 minutes on 2 CPU cores)
"""

import argparse
import datetime
import json
import os
import sys
import time

from study_common import device_line, procedural_scene, read_json, run

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
    head = "| setting | " + " | ".join(f"PSNR {SCALE_NAMES.get(s, '1/' + str(s))}" for s in scales)
    head += " | mean PSNR | mean SSIM | train s | render s/MP | parameters |\n"
    head += "|---|" + "---:|" * (len(scales) + 5) + "\n"
    body = ""
    for r in rows:
        cells = [f"{r['psnr_by_scale'].get(str(s), float('nan')):.2f}" for s in scales]
        body += (f"| {r['label']} | " + " | ".join(cells) +
                 f" | {r['mean_psnr']:.2f} | {r['mean_ssim']:.4f} | {r['train_seconds']:.0f} | "
                 f"{r['render_seconds_per_megapixel']:.1f} | {r['parameters']} |\n")
    return (f"### {scene_name}\n\n{meta}\n\n" + head + body + "\n")


def svg_plot(title, series_by_scene, path):
    """Mean PSNR against training seconds (log axis), one colour per scene, one labelled point per setting."""
    width, height, left, right, top, bottom = 760, 460, 70, 230, 40, 60
    points = [p for rows in series_by_scene.values() for p in rows]
    xs = [max(p["train_seconds"], 1.0) for p in points]
    ys = [p["mean_psnr"] for p in points]
    import math
    x_lo, x_hi = math.log10(min(xs)) - 0.1, math.log10(max(xs)) + 0.1
    y_lo, y_hi = math.floor(min(ys) - 1), math.ceil(max(ys) + 1)

    def px(x):
        return left + (math.log10(max(x, 1.0)) - x_lo) / (x_hi - x_lo) * (width - left - right)

    def py(y):
        return height - bottom - (y - y_lo) / (y_hi - y_lo) * (height - top - bottom)

    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" '
           f'font-size="12">', f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{left}" y="22" font-size="15">{title}</text>']
    # Axes and grid.
    out.append(f'<line x1="{left}" y1="{height - bottom}" x2="{width - right}" y2="{height - bottom}" stroke="black"/>')
    out.append(f'<line x1="{left}" y1="{top}" x2="{left}" y2="{height - bottom}" stroke="black"/>')
    for e in range(int(math.floor(x_lo)), int(math.ceil(x_hi)) + 1):
        for mult in (1, 2, 5):
            v = mult * 10 ** e
            if x_lo <= math.log10(v) <= x_hi:
                x = px(v)
                out.append(f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{height - bottom}" stroke="#ddd"/>')
                out.append(f'<text x="{x:.1f}" y="{height - bottom + 16}" text-anchor="middle">{v:g}</text>')
    for y in range(int(y_lo), int(y_hi) + 1):
        out.append(f'<line x1="{left}" y1="{py(y):.1f}" x2="{width - right}" y2="{py(y):.1f}" stroke="#eee"/>')
        out.append(f'<text x="{left - 8}" y="{py(y) + 4:.1f}" text-anchor="end">{y}</text>')
    out.append(f'<text x="{(left + width - right) / 2}" y="{height - 18}" text-anchor="middle">training time (s, log '
               f'scale)</text>')
    out.append(f'<text x="18" y="{(top + height - bottom) / 2}" text-anchor="middle" '
               f'transform="rotate(-90 18 {(top + height - bottom) / 2})">mean PSNR over scales (dB)</text>')
    for i, (scene, rows) in enumerate(series_by_scene.items()):
        c = colours[i % len(colours)]
        mip = sorted([r for r in rows if r["variant"] == "mipnerf"], key=lambda r: r["train_seconds"])
        if len(mip) > 1:
            pts = " ".join(f"{px(r['train_seconds']):.1f},{py(r['mean_psnr']):.1f}" for r in mip)
            out.append(f'<polyline points="{pts}" fill="none" stroke="{c}" stroke-width="1.5"/>')
        for r in rows:
            x, y = px(r["train_seconds"]), py(r["mean_psnr"])
            shape = (f'<circle cx="{x:.1f}" cy="{y:.1f}" r="4" fill="{c}"/>' if r["variant"] == "mipnerf" else
                     f'<rect x="{x - 4:.1f}" y="{y - 4:.1f}" width="8" height="8" fill="none" stroke="{c}" '
                     f'stroke-width="1.5"/>')
            out.append(shape)
            out.append(f'<text x="{x + 7:.1f}" y="{y - 5:.1f}" font-size="10">{r["key"]}</text>')
        ly = top + 20 + 40 * i
        out.append(f'<circle cx="{width - right + 20}" cy="{ly}" r="4" fill="{c}"/>')
        out.append(f'<text x="{width - right + 30}" y="{ly + 4}">{scene}: mip-NeRF</text>')
        out.append(f'<rect x="{width - right + 16}" y="{ly + 14}" width="8" height="8" fill="none" stroke="{c}"/>')
        out.append(f'<text x="{width - right + 30}" y="{ly + 22}">{scene}: NeRF</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default="build", help="build folder holding mipnerf-cl")
    parser.add_argument("--work", default="/tmp/mipnerf-accuracy-time", help="scenes, runs and logs")
    parser.add_argument("--results", default="bench/results", help="where the table, plot and JSON go")
    parser.add_argument("--lego", help="Blender lego folder (e.g. ../shared/data/nerf_synthetic/lego); omitted: "
                                       "procedural scene only")
    parser.add_argument("--preset", default="quick", help="network and schedule the settings start from")
    parser.add_argument("--steps", type=int, default=500, help="training steps of every run (equal budgets)")
    parser.add_argument("--batch-size", type=int, default=512)
    parser.add_argument("--procedural-views", type=int, default=8, help="test views evaluated (every scale)")
    parser.add_argument("--lego-views", type=int, default=4, help="val views evaluated (every scale)")
    parser.add_argument("--only", help="comma-separated config keys to run (default: all)")
    parser.add_argument("--set", action="append", default=[], help="extra setting for every run, name=value")
    args = parser.parse_args()
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
    meta = (f"Device: {device_line(device)}; {date}. "
            f"Preset `{args.preset}` with {args.steps} steps of {args.batch_size} rays for every setting"
            + (f", plus {', '.join(f'{k}={v}' for k, v in args.base_settings.items())}" if args.base_settings else "")
            + ". Train s: wall time of `mipnerf-cl train` (GEMM tuning file loaded). Render s/MP: `mipnerf-cl eval`, "
              "after its warm-up. PSNR per scale: mean over the evaluated views of that scale.")
    text = ("# What accuracy costs in time\n\n"
            "Made by `bench/accuracy_time.py` (see its header for the command). mip-NeRF is trained with the area loss "
            "on all scales; the NeRF baseline is the paper's: point samples, PE, two MLPs, no area loss. NeRF + 4x "
            "supersampling trains on rays through random points of their pixels and averages 4 jittered rays per "
            "pixel when evaluated. Every setting has the same step budget.\n\n")
    for scene, rows in results.items():
        split, views = rows[0]["eval_split"], rows[0]["eval_views"]
        text += markdown(scene, rows, meta + f" Evaluated on {views} {split} views at every scale.")
    text += f"Study wall time: {time.time() - started:.0f} s (runs reused from an earlier invocation count as 0).\n"
    with open(os.path.join(args.results, "accuracy_time.md"), "w") as f:
        f.write(text)
    with open(os.path.join(args.results, "accuracy_time.json"), "w") as f:
        json.dump({"date": date, "device": device, "preset": args.preset, "steps": args.steps,
                   "batch_size": args.batch_size, "settings": args.base_settings, "scenes": results}, f, indent=2)
    svg_plot(f"mean PSNR vs training time ({device.get('name')}, {date})", results,
             os.path.join(args.results, "accuracy_time.svg"))
    print(text)


if __name__ == "__main__":
    sys.exit(main())
