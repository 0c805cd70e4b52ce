#!/usr/bin/env python3
"""What flushing denormals in the host MLP buys: the same training run with the flush (the default) and without it
(MIPNERF_KEEP_DENORMALS=1), alternating, in one run on one machine.

    python3 bench/studies/denormals.py [--rounds 2] [--preset quick] [--data SCENE] [--bin build/mipnerf-cl] [--report-only]

Each round trains the preset from scratch on the built-in procedural scene (or --data) once each way (round 1 flush
first, round 2 keep first, ...), and reads the run's train_log.csv (wall seconds every 50 steps) and summary.json
(training seconds, val PSNR). The report gives, per run, the seconds per step in each 100-step window, so a slowdown
that grows with training shows as it grows, and the training time and val PSNR. Writes bench/results/denormals/denormals.json
and .md (the .md from the .json; hand notes kept). Why the flush: host/core/flush_denormals.hpp.
"""

import csv
import datetime
import os
import platform
import statistics
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib import cli_runs  # noqa: E402

from lib.provenance import REPO as ROOT  # noqa: E402  (the repository root)
RESULTS = report_md.results_folder("denormals")
MODES = {"flush": {}, "keep": {"MIPNERF_KEEP_DENORMALS": "1"}}
WINDOW = 100


def step_windows(log_path):
    """[(first step, last step, seconds per step)] over WINDOW-step windows of train_log.csv, from its first row."""
    with open(log_path) as f:
        rows = [(int(r["step"]), float(r["wall_seconds"])) for r in csv.DictReader(f)]
    windows = []
    start = rows[0]
    for step, wall in rows[1:]:
        if step - start[0] >= WINDOW:
            windows.append((start[0], step, (wall - start[1]) / (step - start[0])))
            start = (step, wall)
    return windows


def train_once(args, scene, mode, work, index):
    out = os.path.join(work, f"run_{index}_{mode}")
    env_before = dict(os.environ)
    os.environ.pop("MIPNERF_KEEP_DENORMALS", None)
    os.environ.update(MODES[mode])
    try:
        cli_runs.run([args.bin, "train", "--data", scene, "--out", out, "--preset", args.preset],
                         os.path.join(work, f"train_{index}_{mode}.log"))
    finally:
        os.environ.clear()
        os.environ.update(env_before)
    summary = cli_runs.read_json(os.path.join(out, "summary.json"))
    return {"mode": mode, "train_seconds": summary["train_seconds"], "steps": summary["steps"],
            "val_psnr": summary["val"].get("mean_psnr") if isinstance(summary.get("val"), dict) else None,
            "device": summary.get("device"), "windows": step_windows(os.path.join(out, "train_log.csv"))}


def measure(args):
    work = tempfile.mkdtemp(prefix="mipnerf-denormals-")
    scene = args.data or cli_runs.procedural_scene(args.bin, work)
    runs = []
    for round_index in range(args.rounds):
        order = ["flush", "keep"] if round_index % 2 == 0 else ["keep", "flush"]
        for mode in order:
            load = os.getloadavg()[0]
            run = train_once(args, scene, mode, work, len(runs))
            run.update({"round": round_index, "load_1min": load})
            runs.append(run)
            print(f"round {round_index + 1}/{args.rounds} {mode}: {run['train_seconds']:.1f} s, "
                  f"val PSNR {run['val_psnr']}", file=sys.stderr)
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "commit": cli_runs.commit_of(ROOT), "command": "python3 bench/studies/denormals.py " + " ".join(sys.argv[1:]),
            "preset": args.preset, "scene": args.data or "procedural (64x64, make-scene)", "rounds": args.rounds,
            "cpu": platform.processor() or platform.machine(), "runs": runs}


def psnr_text(run):
    return "-" if run["val_psnr"] is None else f"{run['val_psnr']:.2f}"


def write_markdown(record):
    runs = record["runs"]
    device = runs[0].get("device") or "not recorded"
    lines = [report_md.generated_banner("bench/studies/denormals.py", "denormals.json"), "",
             "# Denormals flushed in the host MLP, or kept", "",
             f"Date: {record['date']} (UTC), commit {record['commit']}. Command: `{record['command']}`. Device: "
             f"`{device}` ({record['cpu']}). Preset `{record['preset']}` on "
             f"{record['scene']}, trained from scratch each run; {record['rounds']} alternating rounds (round 1 flush "
             "first). `keep` = MIPNERF_KEEP_DENORMALS=1.", "",
             "## Training time and val PSNR", ""]
    rows = []
    for mode in MODES:
        of_mode = [r for r in runs if r["mode"] == mode]
        seconds = [r["train_seconds"] for r in of_mode]
        rows.append([mode, str(len(of_mode)),
                     f"{statistics.median(seconds):.1f} ({', '.join(f'{s:.1f}' for s in seconds)})",
                     ", ".join(psnr_text(r) for r in of_mode)])
    lines += report_md.table(["mode", "runs", "training s, median (each)", "val PSNR dB (each)"], "lrrl", rows)
    lines += ["", f"## Seconds per step, {WINDOW}-step windows", "",
              "Each cell: the window's wall seconds per step (train_log.csv rows, every 50 steps). A step that slows as "
              "training goes on shows as a growing row.", ""]
    windows = runs[0]["windows"]
    header = ["run", "mode"] + [f"{a}-{b}" for a, b, _ in windows] + ["last / first"]
    rows = []
    for i, r in enumerate(runs):
        per_step = [w[2] for w in r["windows"]]
        ratio = per_step[-1] / per_step[0] if per_step and per_step[0] > 0 else float("nan")
        rows.append([str(i + 1), r["mode"]] + [f"{1e3 * s:.1f} ms" for s in per_step] + [f"{ratio:.2f}"])
    lines += report_md.table(header, "ll" + "r" * (len(windows) + 1), rows)
    return "\n".join(lines) + "\n"


def add_arguments(parser):
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--preset", default="quick")
    parser.add_argument("--data", default=None, help="scene folder (default: the built-in procedural scene)")
    parser.add_argument("--bin", default=os.path.join(ROOT, "build", "mipnerf-cl"))


def main():
    report_md.study_main(__doc__, RESULTS, "denormals", "bench/studies/denormals.py", add_arguments, measure, write_markdown)


if __name__ == "__main__":
    main()
