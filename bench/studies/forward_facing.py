#!/usr/bin/env python3
"""The supplement's §4 experiment at CPU budget: mip-NeRF (cylinders in NDC) beside the NeRF baseline (points in
NDC) on the forward-facing built-in scene (`make-scene --forward-facing`, trained from images_4/), at equal steps
and at equal training time. Writes bench/results/forward_facing/forward_facing.{md,json}.

  python3 bench/studies/forward_facing.py [--exe build/mipnerf-cl] [--steps 1000] [--preset quick] [--work /tmp/ff-bench]

Equal time (aimed at, not guaranteed): the variant that trained faster is resumed (`train --resume --steps M`,
M = steps x the slower one's seconds / its own) and scored again on the same held-out views; the report labels
each run with the seconds it actually trained, which differ from the aim when the pace changes (a shared machine).

The .md is generated from the .json (write_markdown); `--report-only` regenerates it without runs. Hand-written
notes go under "## Notes (by hand)" at the end of the .md, which regeneration keeps.
"""

import argparse
import datetime
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import commit_of, read_json, run  # noqa: E402

from lib.provenance import REPO  # noqa: E402


def train(exe, scene, out, variant, preset, steps, log, resume=False):
    command = [exe, "train", "--data", scene, "--out", out, "--preset", preset, "--variant", variant,
               "--factor", "4", "--steps", str(steps), "--val_views", "0"]
    if resume:
        command.append("--resume")
    run(command, log)
    summary = read_json(os.path.join(out, "summary.json"))
    return {"variant": variant, "steps": summary["steps"], "train_seconds": summary["train_seconds"],
            "psnr": summary["val"]["mean_psnr"], "ssim": summary["val"]["mean_ssim"],
            "render_s_per_mp": summary["val"]["render_seconds_per_megapixel"], "views": summary["val"]["views"],
            "device": summary["device"], "scene_effects": read_json(os.path.join(out, "config.json")).get("scene_effects")}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exe", default="build/mipnerf-cl")
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--preset", default="quick")
    parser.add_argument("--work", default="/tmp/mipnerf-forward-facing")
    parser.add_argument("--results", default=report_md.results_folder("forward_facing"))
    parser.add_argument("--report-only", action="store_true",
                        help="regenerate forward_facing.md from forward_facing.json in --results (no runs); the "
                             "section '## Notes (by hand)' of the .md is kept")
    args = parser.parse_args()
    if args.report_only:
        return report_only(args.results)
    exe = os.path.abspath(args.exe)
    log = os.path.join(args.work, "bench.log")
    scene = os.path.join(args.work, "scene")
    if not os.path.exists(os.path.join(scene, "poses_bounds.npy")):
        run([exe, "make-scene", scene, "--forward-facing", "--size", "256"], log)

    equal_steps = {}
    for variant in ("mipnerf", "nerf"):
        out = os.path.join(args.work, variant)
        if os.path.exists(out):
            run(["rm", "-rf", out], log)
        equal_steps[variant] = train(exe, scene, out, variant, args.preset, args.steps, log)
    slower = max(equal_steps.values(), key=lambda r: r["train_seconds"])
    faster = min(equal_steps.values(), key=lambda r: r["train_seconds"])
    more_steps = int(round(args.steps * slower["train_seconds"] / faster["train_seconds"]))
    extended = faster
    if more_steps > args.steps:
        extended = train(exe, scene, os.path.join(args.work, faster["variant"]), faster["variant"], args.preset,
                         more_steps, log, resume=True)
    equal_time = {"slower": slower, "faster_extended": extended}

    record = {"date": datetime.date.today().isoformat(), "commit": commit_of(REPO), "preset": args.preset,
              "steps": args.steps,
              "scene": "make-scene --forward-facing --size 256 (20 views, 5x4 grid; trained on images_4/, 64x48)",
              "equal_steps": equal_steps, "equal_time": equal_time}
    os.makedirs(args.results, exist_ok=True)
    with open(os.path.join(args.results, "forward_facing.json"), "w") as f:
        json.dump(record, f, indent=2)
        f.write("\n")
    print(write_report(record, args.results))


def write_markdown(record):
    """The report, generated from forward_facing.json alone."""
    equal_steps, equal_time = record["equal_steps"], record["equal_time"]
    slower, extended = equal_time["slower"], equal_time["faster_extended"]
    names = {"mipnerf": "mip-NeRF", "nerf": "NeRF"}

    def row(r, label):
        return [label, f"{r['steps']:,}", f"{r['train_seconds']:,.0f}", f"{r['psnr']:.2f}", f"{r['ssim']:.4f}",
                f"{r['render_s_per_mp']:.1f}"]

    lines = [
        "# Forward-facing: mip-NeRF (cylinders, NDC) beside NeRF (NDC), supplement §4 at CPU budget",
        "",
        report_md.generated_banner("bench/studies/forward_facing.py", "forward_facing.json"),
        "",
        f"Device: {equal_steps['mipnerf']['device']}. Date {record['date']}"
        + (f", commit {record['commit']}" if record.get("commit") else "") + f". Scene: {record['scene']}; "
        f"held-out views: every 8th ({equal_steps['mipnerf']['views']} views). Preset `{record['preset']}` "
        f"(its network, batch and samples; the schedule spans the steps trained).",
        f"Scene effects chosen from the data: `{equal_steps['mipnerf']['scene_effects']}`.",
        "",
        f"Command: `python3 bench/studies/forward_facing.py --steps {record['steps']} --preset {record['preset']}`",
        "",
    ]
    rows = [row(equal_steps["mipnerf"], f"mip-NeRF, {equal_steps['mipnerf']['steps']:,} steps "
                                        f"({equal_steps['mipnerf']['train_seconds']:,.0f} s)"),
            row(equal_steps["nerf"], f"NeRF, {equal_steps['nerf']['steps']:,} steps "
                                     f"({equal_steps['nerf']['train_seconds']:,.0f} s)")]
    resumed = extended is not slower and extended["steps"] != record["steps"]
    if resumed:
        rows.append(row(extended, f"{names.get(extended['variant'], extended['variant'])}, resumed to "
                                  f"{extended['steps']:,} steps ({extended['train_seconds']:,.0f} s; aimed at "
                                  f"{names.get(slower['variant'], slower['variant'])}'s "
                                  f"{slower['train_seconds']:,.0f} s)"))
    lines += report_md.table(["run", "steps", "train s", "test PSNR (dB)", "test SSIM", "render s/MP"], "lrrrrr", rows)
    lines.append("")
    if resumed:
        first = equal_steps[extended["variant"]]
        gap = extended["train_seconds"] / slower["train_seconds"] - 1
        lines += [
            f"The resumed run: the faster variant ({names.get(extended['variant'])}) was resumed from its "
            f"{first['steps']:,}-step checkpoint for steps × (slower's seconds / its seconds) = "
            f"{record['steps']:,} × {slower['train_seconds']:,.0f} / {first['train_seconds']:,.0f} → "
            f"{extended['steps']:,} steps in all; its training seconds count both parts (the checkpoint carries "
            f"the seconds before it): {extended['train_seconds']:,.0f} s, of which "
            f"{extended['train_seconds'] - first['train_seconds']:,.0f} s for the last "
            f"{extended['steps'] - first['steps']:,} steps. "
            + (f"That is {abs(gap) * 100:.0f} % {'less' if gap < 0 else 'more'} than the "
               f"{slower['train_seconds']:,.0f} s it aimed at, so it is not an equal-time comparison; the "
               "steps were chosen from the first part's pace and the pace changed."
               if abs(gap) > 0.05 else
               f"That is within 5 % of the {slower['train_seconds']:,.0f} s it aimed at."),
            "",
        ]
    lines += [
        "The paper (supplement §4, the LLFF scenes at full budget) reports 26.838 dB for mip-NeRF and 26.843 dB for "
        "NeRF: about equal.",
    ]
    return "\n".join(lines) + "\n"


def write_report(record, results):
    path = os.path.join(results, "forward_facing.md")
    return report_md.write_report(path, write_markdown(record),
                                  f"python3 bench/studies/forward_facing.py --report-only --results {results}")


def report_only(results):
    with open(os.path.join(results, "forward_facing.json")) as f:
        record = json.load(f)
    write_report(record, results)
    print(f"forward_facing: wrote {results}/forward_facing.md from forward_facing.json")


if __name__ == "__main__":
    main()
