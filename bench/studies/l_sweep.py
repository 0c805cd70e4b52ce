#!/usr/bin/env python3
"""The L sweep of the mip-NeRF supplement (§2, Figure 1): NeRF's positional encoding against mip-NeRF's integrated
one as the highest frequency L grows, at equal steps on lego.

NeRF (the `nerf` variant: points with PE, identity appended) and mip-NeRF (IPE) are trained with pos_max_deg = L for
each L of --degrees on lego box-downsampled by --factor (4: 100x100), each for --steps steps of --preset, and scored
on the first --val-views val views. The paper expects NeRF to peak at some L and fall beyond it (aliasing of the
high frequencies it cannot attenuate) while mip-NeRF stays flat (IPE attenuates the frequencies a frustum cannot
resolve). Writes bench/results/l_sweep/l_sweep.{md,json,svg}: val PSNR against L, with train seconds and render s/MP.

  python3 bench/studies/l_sweep.py --lego ../shared/data/nerf_synthetic/lego [--steps 600] [--preset quick]
      [--degrees 4,8,12,16,20,24] [--val-views 4] [--work /tmp/mipnerf-l-sweep] [--plot-only]

Resumable: runs whose summary.json is complete are reused, interrupted ones continue (train --resume). Needs
matplotlib for the plot (bench/setup.sh). Every run goes through the real CLI; the record names device, date,
commit and every command. The .md is generated from the .json (write_markdown): `--report-only` regenerates it
alone, `--plot-only` the .md and the plot; hand-written notes go under "## Notes (by hand)" at the end of the .md,
which regeneration keeps.
"""

import argparse
import datetime
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import commit_of, train_resumable  # noqa: E402

MODELS = [("nerf", "NeRF (PE of points)"), ("mipnerf", "mip-NeRF (IPE of frustums)")]


def measure(args):
    exe = os.path.abspath(args.exe)
    lego = os.path.abspath(args.lego)
    log = os.path.join(args.work, "study.log")
    runs = []
    for degree in args.degrees:
        for variant, _ in MODELS:
            out = os.path.join(args.work, f"{variant}_L{degree}")
            settings = {"factor": args.factor, "steps": args.steps, "pos_max_deg": degree, "val_views": args.val_views}
            print(f"l_sweep: {variant} L = {degree} ({args.steps} steps)", flush=True)
            summary, command = train_resumable(exe, lego, out, args.preset, variant, settings, log)
            runs.append({"variant": variant, "L": degree, "steps": summary["steps"],
                         "train_seconds": summary["train_seconds"], "psnr": summary["val"]["mean_psnr"],
                         "ssim": summary["val"]["mean_ssim"], "views": summary["val"]["views"],
                         "render_s_per_mp": summary["val"]["render_seconds_per_megapixel"],
                         "parameters": summary["parameters"], "device": summary["device"],
                         "command": " ".join(command)})
    return {"date": datetime.date.today().isoformat(), "commit": commit_of(), "preset": args.preset,
            "steps": args.steps, "factor": args.factor, "val_views": args.val_views, "degrees": args.degrees,
            "scene": "lego (nerf_synthetic, 400x400 in ../shared) box-downsampled by the factor", "runs": runs}


def write_markdown(record):
    """The report, generated from l_sweep.json alone."""
    by = {(r["variant"], r["L"]): r for r in record["runs"]}
    device = record["runs"][0]["device"] if record["runs"] else "?"
    lines = [
        "# L sweep: NeRF's PE against mip-NeRF's IPE as the highest frequency grows (supplement §2, Figure 1)",
        "",
        report_md.generated_banner("bench/studies/l_sweep.py", "l_sweep.json"),
        "",
        f"Device: {device}. Date {record['date']}, commit {record['commit']}. Scene: {record['scene']} "
        f"(factor {record['factor']}); val PSNR/SSIM on the first {record['val_views']} val views. Preset "
        f"`{record['preset']}`, {record['steps']} steps per run, equal for every run. Positional degrees 0..L-1 "
        "(pos_max_deg = L); NeRF appends the identity. Commands: l_sweep.json.",
        "",
    ]
    rows = []
    for degree in record["degrees"]:
        n, m = by.get(("nerf", degree)), by.get(("mipnerf", degree))
        if not n or not m:
            continue
        rows.append([str(degree), f"{n['psnr']:.2f}", f"{n['ssim']:.4f}", f"{n['train_seconds']:.0f}", f"{m['psnr']:.2f}",
                     f"{m['ssim']:.4f}", f"{m['train_seconds']:.0f}",
                     f"{n['render_s_per_mp']:.0f} / {m['render_s_per_mp']:.0f}"])
    lines += report_md.table(["L", "NeRF PSNR", "NeRF SSIM", "NeRF train s", "mip-NeRF PSNR", "mip-NeRF SSIM",
                              "mip-NeRF train s", "render s/MP (NeRF / mip-NeRF)"], "rrrrrrrr", rows)
    for note in record.get("notes", []):  # notes recorded in the JSON (new ones go in the .md's hand section)
        lines += ["", note]
    lines += ["", "![val PSNR against L](l_sweep.svg)", ""]
    return "\n".join(lines)


def write_report(record, results):
    path = os.path.join(results, "l_sweep.md")
    report_md.write_report(path, write_markdown(record),
                           f"python3 bench/studies/l_sweep.py --report-only --results {results}")


def write_plot(record, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for variant, label in MODELS:
        points = sorted((r["L"], r["psnr"]) for r in record["runs"] if r["variant"] == variant)
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=label)
    ax.set_xlabel("L (positional degrees 0..L-1)")
    ax.set_ylabel("val PSNR (dB)")
    ax.set_title(f"lego x{record['factor']}, {record['steps']} {record['preset']} steps")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, metadata={"Date": None})
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exe", default="build/mipnerf-cl")
    parser.add_argument("--lego", help="the lego scene folder (../shared/data/nerf_synthetic/lego)")
    parser.add_argument("--steps", type=int, default=600, help="the budget: steps per run (default 600)")
    parser.add_argument("--preset", default="quick")
    parser.add_argument("--factor", type=int, default=4)
    parser.add_argument("--degrees", default="4,8,12,16,20,24")
    parser.add_argument("--val-views", type=int, default=4)
    parser.add_argument("--work", default="/tmp/mipnerf-l-sweep")
    parser.add_argument("--results", default=report_md.results_folder("l_sweep"))
    parser.add_argument("--plot-only", action="store_true", help="redraw the table and plot from l_sweep.json")
    parser.add_argument("--report-only", action="store_true",
                        help="regenerate l_sweep.md from l_sweep.json (no runs, no plot; its '## Notes (by hand)' "
                             "section is kept)")
    args = parser.parse_args()
    args.degrees = [int(d) for d in args.degrees.split(",")]
    record_path = os.path.join(args.results, "l_sweep.json")
    if args.report_only:
        with open(record_path) as f:
            write_report(json.load(f), args.results)
        print(f"l_sweep: wrote {args.results}/l_sweep.md from l_sweep.json")
        return
    if args.plot_only:
        with open(record_path) as f:
            record = json.load(f)
    else:
        if not args.lego:
            parser.error("--lego is needed (the lego scene folder), unless --plot-only")
        record = measure(args)
        os.makedirs(args.results, exist_ok=True)
        with open(record_path, "w") as f:
            json.dump(record, f, indent=2)
            f.write("\n")
    write_report(record, args.results)
    write_plot(record, os.path.join(args.results, "l_sweep.svg"))
    print(f"l_sweep: wrote {args.results}/l_sweep.md, .json, .svg")


if __name__ == "__main__":
    main()
