#!/usr/bin/env python3
"""Time to quality: test PSNR and SSIM against training seconds on a real capture, for wall-clock budgets.

Trains on flower (LLFF, `--set factor=8`, the held-out views every 8th image as the LLFF loader holds them out:
the test split, which is also the val split `train` scores at its end) for wall-clock budgets (default 1, 2, 5, 10,
15 and 30 minutes) and reports test PSNR/SSIM against training seconds for a list of named model configurations:

- by default mip-NeRF at the CLI's CPU presets `quick` and `small` (`mipnerf-cl train --help`: `tiny` is the test
  suite's 64x64 preset and `paper` a GPU one; add them with --extra);
- `--extra NAME='train args'` (repeatable) adds an entry without code changes, e.g.
  `--extra 'Zip-NeRF fast=--model zipnerf --preset fast'`;
- the official google/mipnerf code at the quick network, converted through its measured seconds per step: its
  quality per step is ours (bench/results/vs_official_llff: the two sides agree within seed noise at 300 and 600
  steps on this capture), so its point at a budget is our quick run's score at the step the official code reaches
  in that time (budget / its measured s/step, from the committed vs_official_llff results; named in the report).

One training per model, not one per budget: each entry trains once with `train --minutes LONGEST` (the step count
fixed by the CLI's timed warm-up and recorded in the run), keeping a checkpoint every K steps. Each shorter budget
is scored on the checkpoint at the last logged step whose training clock (train_log.csv's wall_seconds: the warm-up
included, val scoring excluded) is within the budget: the step count that budget's time corresponds to in that run.
K comes from a short probe run of the same entry (its s/step): about 2 % of the shortest budget, and at most
--max-checkpoints checkpoints per run. Caveat, stated in the report: a shorter budget's point is a prefix of the
longest run, whose learning rate has not decayed there as a run sized to that budget (`train --minutes b`) would
have decayed it, so it differs from what that run reaches, in either direction (early on the higher rate can even
be ahead: see the hand notes of the committed --quick report).

Duration of the default study on two CPU cores: about 2 hours (two 30-minute trainings, each held-out score of the
5 views at 504x378 about 2.5 minutes for quick and 5 for small, about 16 scores). `--quick` (budgets 0.5 and 1 minute,
the quick preset only, with the official conversion): about 12 minutes. Resumable: finished runs and scores in --work
are reused, an interrupted training is continued with --resume (its recorded step count). Needs matplotlib for the
PNG (bench/setup.sh installs Debian's python3-matplotlib: run the script with /usr/bin/python3 when another python3
comes first in PATH); without it the table is written and the plot skipped with a note.

  python3 bench/studies/time_to_quality.py [--flower ../shared/data/llff/flower] [--budgets 1,2,5,10,15,30]
      [--extra NAME='train args']... [--quick] [--work /tmp/mipnerf-time-to-quality] [--report-only]

Writes bench/results/time_to_quality/time_to_quality.{json,md,png} (--quick: time_to_quality_quick.*). The .md is
generated from the .json; hand-written notes go under "## Notes (by hand)" at its end, which regeneration keeps.
"""

import argparse
import datetime
import json
import math
import os
import re
import shlex
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import commit_of, read_json, read_train_log, run, warm_seconds_per_step  # noqa: E402
from lib.machine import load_average  # noqa: E402
from lib.provenance import REPO, cpu_model, tree_state  # noqa: E402

STUDY = "time_to_quality"
SCRIPT = "bench/studies/time_to_quality.py"
# "Zip-NeRF fast" is the fast preset as it stands: one footprint-weighted point per interval since 2026-11-28 (the
# committed results' "Zip-NeRF fast" row was measured before that, with the 6 multisamples: see its hand notes).
DEFAULT_MODELS = {"mip-NeRF quick": "--preset quick", "mip-NeRF small": "--preset small",
                  "Zip-NeRF fast": "--model zipnerf --preset fast",
                  "Zip-NeRF fast, 6 multisamples": "--model zipnerf --preset fast --set grid_multisample=true"}
QUICK_MODELS = {"mip-NeRF quick": "--preset quick"}
# The entry whose network the official code was timed with (vs_official_llff: "the quick network").
OFFICIAL_BASE = "mip-NeRF quick"
OFFICIAL_RESULTS = os.path.join(report_md.RESULTS, "vs_official_llff", "vs_official_llff_pocl_cpu.json")
PROBE_STEPS = 6


def parse_budgets(text):
    budgets = sorted({float(x) for x in text.split(",") if x.strip()})
    if not budgets or budgets[0] <= 0:
        raise argparse.ArgumentTypeError(f"--budgets {text!r}: give positive minutes, e.g. 1,2,5")
    return budgets


def parse_extra(text):
    name, sep, train_args = text.partition("=")
    if not sep or not name.strip() or not train_args.strip():
        raise argparse.ArgumentTypeError(f"--extra {text!r}: write NAME='train args', e.g. "
                                         "'Zip-NeRF fast=--model zipnerf --preset fast'")
    return name.strip(), train_args.strip()


def slug(name):
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_")


def base_command(exe, flower, factor, out, train_args):
    return [exe, "train", "--data", flower, "--out", out, *shlex.split(train_args), "--set", f"factor={factor}"]


def probe_seconds_per_step(exe, flower, factor, work, name, train_args, log):
    """The entry's warm s/step from a short run (PROBE_STEPS steps, one held-out view scored): sizes K only."""
    out = os.path.join(work, slug(name), "probe")
    if not os.path.exists(os.path.join(out, "summary.json")):
        run(["rm", "-rf", out], log)
        run(base_command(exe, flower, factor, out, train_args) +
            ["--set", f"steps={PROBE_STEPS}", "--set", "log_every=1", "--set", "val_views=1"], log)
    return warm_seconds_per_step(out)


def checkpoint_every(seconds_per_step, budgets_s, max_checkpoints):
    fine = math.floor(0.02 * budgets_s[0] / seconds_per_step)
    few = math.ceil(budgets_s[-1] / seconds_per_step / max_checkpoints)
    return max(1, fine, few)


def train_longest(exe, flower, factor, work, name, train_args, longest_minutes, every, log):
    """`train --minutes LONGEST` with a checkpoint every `every` steps, resumed when interrupted. Returns the run."""
    out = os.path.join(work, slug(name), "run")
    summary_path = os.path.join(out, "summary.json")
    finished = os.path.exists(summary_path) and not read_json(summary_path).get("interrupted", True)
    if not finished:
        if os.path.isdir(os.path.join(out, "checkpoints")) and os.listdir(os.path.join(out, "checkpoints")):
            run([exe, "train", "--out", out, "--resume"], log)  # the recorded steps and settings
        else:
            run(["rm", "-rf", out], log)
            run(base_command(exe, flower, factor, out, train_args) +
                ["--minutes", f"{longest_minutes:g}", "--set", f"checkpoint_every={every}",
                 "--set", "keep_checkpoints=1000000", "--set", f"log_every={every}", "--set", "val_views=0",
                 "--set", "val_every=0"], log)
    return out


def checkpoint_steps(run_dir):
    folder = os.path.join(run_dir, "checkpoints")
    return {int(re.search(r"(\d+)", f).group(1)): os.path.join(folder, f)
            for f in os.listdir(folder) if f.startswith("ckpt_") and f.endswith(".mnck")}


def step_within(run_dir, seconds):
    """The last step with a checkpoint whose logged training clock is within `seconds` (None: none is)."""
    have = checkpoint_steps(run_dir)
    within = [(step, wall) for step, wall in read_train_log(run_dir) if wall <= seconds and step in have]
    return max(within) if within else None


def step_at_most(run_dir, steps):
    """The last logged step with a checkpoint at or below `steps` (None: none is), with its training clock."""
    have = checkpoint_steps(run_dir)
    below = [(step, wall) for step, wall in read_train_log(run_dir) if step <= steps and step in have]
    return max(below) if below else None


def score(exe, run_dir, step, log):
    """Test PSNR/SSIM of the run at `step`: the final step from summary.json (train scored every held-out view),
    another from `eval --split test` of its checkpoint (cached in the run folder)."""
    summary = read_json(os.path.join(run_dir, "summary.json"))
    if step == summary["steps"] and "val" in summary:
        return {"psnr": summary["val"]["mean_psnr"], "ssim": summary["val"]["mean_ssim"],
                "views": summary["val"]["views"], "scored_by": "train's final val (every held-out view)"}
    out = os.path.join(run_dir, f"eval_test_step{step}")
    metrics_path = os.path.join(out, "metrics.json")
    if not os.path.exists(metrics_path):
        run([exe, "eval", "--checkpoint", checkpoint_steps(run_dir)[step], "--split", "test", "--no-images",
             "--out", out], log)
    metrics = read_json(metrics_path)
    return {"psnr": metrics["mean"]["psnr"], "ssim": metrics["mean"]["ssim"], "views": metrics["mean"]["images"],
            "scored_by": "eval --split test of the checkpoint"}


def official_seconds_per_step(path):
    """The official code's measured s/step at the quick network on flower: the median over its committed runs of
    train seconds / steps (its train seconds start after the jit compile), with where it came from."""
    record = read_json(path)
    per_step = [p["official"]["train_seconds"] / p["official"]["steps"] for p in record["pairs"]]
    ours = [p["ours"]["train_seconds"] / p["ours"]["steps"] for p in record["pairs"]]
    return {"seconds_per_step": statistics.median(per_step), "runs": len(per_step),
            "ours_then_seconds_per_step": statistics.median(ours),
            "source": os.path.relpath(path, REPO), "date": record.get("date"),
            "checkout": (record.get("checkout") or {}).get("commit", "unknown")[:10],
            "official_commit": record.get("official_commit"), "cpu": record.get("cpu"),
            "capture": record.get("capture"), "factor": record.get("factor")}


def measure_model(args, name, train_args, log):
    budgets_s = [60.0 * b for b in args.budgets]
    print(f"{STUDY}: {name}: probing its pace", flush=True)
    probe = probe_seconds_per_step(args.exe, args.flower, args.factor, args.work, name, train_args, log)
    every = checkpoint_every(probe, budgets_s, args.max_checkpoints)
    print(f"{STUDY}: {name}: {probe:.3f} s/step in the probe; training {args.budgets[-1]:g} min, a checkpoint every "
          f"{every} steps", flush=True)
    load_before = load_average()
    run_dir = train_longest(args.exe, args.flower, args.factor, args.work, name, train_args, args.budgets[-1], every,
                            log)
    load_after = load_average()
    summary = read_json(os.path.join(run_dir, "summary.json"))
    config = read_json(os.path.join(run_dir, "config.json"))
    points = []
    for minutes, seconds in zip(args.budgets, budgets_s):
        # The longest budget is the run's own: its last step, whatever the clock says (the run was sized to it).
        found = (summary["steps"], summary["train_seconds"]) if minutes == args.budgets[-1] \
            else step_within(run_dir, seconds)
        if found is None:
            points.append({"budget_minutes": minutes, "step": None})
            continue
        step, wall = found
        print(f"{STUDY}: {name}: {minutes:g} min -> step {step} ({wall:.0f} s)", flush=True)
        points.append({"budget_minutes": minutes, "step": step, "train_seconds": wall,
                       **score(args.exe, run_dir, step, log)})
    return {"name": name, "train_args": train_args, "run_dir": run_dir, "probe_seconds_per_step": probe,
            "checkpoint_every": every, "time_budget": read_json(os.path.join(run_dir, "time_budget.json")),
            "steps": summary["steps"], "train_seconds": summary["train_seconds"], "parameters": summary["parameters"],
            "device": summary["device"], "scene_effects": config.get("scene_effects"),
            "load_before": load_before, "load_after": load_after, "points": points}


def measure_official(args, base, official, log):
    """The official code's points: our base run's score at the step it reaches in each budget."""
    points = []
    for minutes in args.budgets:
        reached = int(60.0 * minutes / official["seconds_per_step"])
        found = step_at_most(base["run_dir"], reached)
        if found is None:
            points.append({"budget_minutes": minutes, "official_steps": reached, "step": None})
            continue
        step, _ = found
        points.append({"budget_minutes": minutes, "official_steps": reached, "step": step,
                       "train_seconds": step * official["seconds_per_step"],
                       **score(args.exe, base["run_dir"], step, log)})
    return {"name": "official mip-NeRF (quick network, converted)", "points": points, **official}


def measure(args):
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "study.log")
    models = [measure_model(args, name, train_args, log) for name, train_args in args.models.items()]
    record = {"what": "test PSNR/SSIM against training seconds for wall-clock budgets, one run per model",
              "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
              "commit": commit_of(), "tree": tree_state(), "cpu": cpu_model(), "device": models[0]["device"],
              "capture": args.flower, "factor": args.factor, "budgets_minutes": args.budgets, "quick": args.quick,
              "command": " ".join(shlex.quote(a) for a in sys.argv), "models": models}
    base = next((m for m in models if m["name"] == OFFICIAL_BASE), None)
    if base and os.path.exists(args.official_results):
        record["official"] = measure_official(args, base, official_seconds_per_step(args.official_results), log)
    return record


def fmt_point(p):
    if p.get("step") is None:
        return "-"
    return f"{p['psnr']:.2f} / {p['ssim']:.3f} ({p['step']:,} st, {p['train_seconds']:.0f} s)"


def plot(record, path):
    try:
        import matplotlib
    except ImportError:
        return "matplotlib is missing (bench/setup.sh installs it), so no plot was drawn"
    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot
    pyplot.rcParams.update({"font.size": 10})
    figure, axes = pyplot.subplots(1, 2, figsize=(11.0, 4.4))
    series = [(m["name"], m["points"], "o-") for m in record["models"]]
    if "official" in record:
        series.append((record["official"]["name"], record["official"]["points"], "s--"))
    for name, points, style in series:
        done = [p for p in points if p.get("step") is not None]
        for axis, key in zip(axes, ("psnr", "ssim")):
            axis.plot([p["train_seconds"] / 60.0 for p in done], [p[key] for p in done], style, label=name)
    from matplotlib.ticker import FixedLocator, FormatStrFormatter, NullLocator
    for axis, label in zip(axes, ("test PSNR (dB)", "test SSIM")):
        axis.set_xscale("log")
        axis.xaxis.set_major_locator(FixedLocator(record["budgets_minutes"]))  # the budgets, written as minutes
        axis.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        axis.xaxis.set_minor_locator(NullLocator())
        axis.set_xlabel("training minutes (log)")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    figure.suptitle(f"Time to quality on flower x{record['factor']} ({record['device']}, {record['date'][:10]}, "
                    f"{record['commit']})", fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=110, metadata={"Software": None})
    pyplot.close(figure)
    return None


def write_markdown(record):
    name = os.path.basename(record.get("results_name", STUDY))
    budgets = record["budgets_minutes"]
    lines = [
        "# Time to quality on flower: test PSNR / SSIM against training time",
        "",
        report_md.generated_banner(SCRIPT, name + ".json"),
        "",
        f"Device: {record['device']} ({record['cpu']}). Date {record['date']}, commit {record['commit']}. Capture "
        f"`{record['capture']}` at factor {record['factor']}, scored on its held-out views (every 8th image; "
        f"{next((p['views'] for m in record['models'] for p in m['points'] if p.get('views')), '?')} views). "
        f"Command: `{record['command']}`.",
        "",
        "Each cell: test PSNR (dB) / SSIM (step reached, training seconds at it). Each model trained once, with "
        f"`train --minutes {budgets[-1]:g}` (its steps fixed by the CLI's timed warm-up); a shorter budget is scored "
        "on the run's checkpoint at the last logged step within that budget's time (training clock: the warm-up "
        "included, checkpoints included, val scoring excluded). A shorter budget's point is a prefix of the longest "
        "run, whose learning rate has not decayed there as a run sized to that budget (`train --minutes` of it) "
        "would have decayed it: it differs from that run's score, in either direction. The machine is shared: when its load changes after a run's warm-up, the run's pace changes and "
        "it ends early or late (each run's ratio to its budget below); the points keep their real seconds.",
        "",
    ]
    header = ["model"] + [f"{b:g} min" for b in budgets]
    rows = [[m["name"]] + [fmt_point(p) for p in m["points"]] for m in record["models"]]
    official = record.get("official")
    if official:
        rows.append([official["name"]] + [fmt_point(p) for p in official["points"]])
    lines += report_md.table(header, "l" + "r" * len(budgets), rows)
    lines += ["", "![test PSNR and SSIM against training minutes](" + name + ".png)", "", "## The runs", ""]
    for m in record["models"]:
        tb = m["time_budget"]
        lines.append(f"- {m['name']} (`train {m['train_args']}`; {m['parameters']:,} parameters): warm-up "
                     f"{tb['warmup_seconds']:.1f} s measured {tb['seconds_per_step']:.4f} s/step -> {m['steps']:,} "
                     f"steps, trained {m['train_seconds']:.0f} s; probe {m['probe_seconds_per_step']:.4f} s/step; a "
                     f"checkpoint every {m['checkpoint_every']} steps; "
                     f"{m['train_seconds'] / tb['budget_seconds']:.2f}x its budget"
                     + (f", load average {m['load_before']} before and {m['load_after']} after training"
                        if m.get("load_before") else "") + f". Scene effects: {m['scene_effects']}.")
    if official:
        lines += [
            "",
            f"Official google/mipnerf (commit {official['official_commit']}): {official['seconds_per_step']:.4f} "
            f"s/step at the quick network on this capture, the median of {official['runs']} runs in "
            f"`{official['source']}` ({official['date']}, checkout {official['checkout']}, {official['cpu']}; its "
            f"train seconds start after the jit compile). Ours in those runs: {official['ours_then_seconds_per_step']:.4f}"
            f" s/step. Its point at a budget is our `{OFFICIAL_BASE}` run scored at the checkpoint at or below the "
            "steps the official code reaches in that time (budget / its s/step; the steps column is that "
            "checkpoint's, the seconds are steps x its s/step): the two sides give the same PSNR at equal steps "
            "within seed noise there. Not re-timed on this machine today: the ratio holds only as far as the "
            "machine and our code's pace are those of that date.",
        ]
    if record.get("plot_note"):
        lines += ["", record["plot_note"]]
    lines.append("")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="Default study: about 2 hours on two CPU cores; --quick: about 12 minutes.")
    parser.add_argument("--exe", default=os.path.join(REPO, "build", "mipnerf-cl"))
    parser.add_argument("--flower", default=os.path.normpath(os.path.join(REPO, "..", "shared", "data", "llff", "flower")))
    parser.add_argument("--factor", type=int, default=8)
    parser.add_argument("--budgets", type=parse_budgets, default=None,
                        help="wall-clock budgets in minutes, comma-separated (default 1,2,5,10,15,30)")
    parser.add_argument("--extra", type=parse_extra, action="append", default=[], metavar="NAME='train args'",
                        help="another model entry: a name, '=', then train's arguments (repeatable)")
    parser.add_argument("--quick", action="store_true",
                        help="budgets 0.5 and 1 minute, the quick preset only (and the official conversion): an "
                             "end-to-end check in about 12 minutes; results as time_to_quality_quick.*")
    parser.add_argument("--models", default="", metavar="NAME,NAME",
                        help="only these of the default models (by name, e.g. 'mip-NeRF quick,Zip-NeRF fast')")
    parser.add_argument("--max-checkpoints", type=int, default=200, help="at most this many checkpoints per run")
    parser.add_argument("--official-results", default=OFFICIAL_RESULTS,
                        help="the vs_official_llff results whose official s/step converts the official code")
    parser.add_argument("--work", default="/tmp/mipnerf-time-to-quality")
    parser.add_argument("--results", default=report_md.results_folder(STUDY))
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the .md from the .json, and the plot when matplotlib is there")
    args = parser.parse_args()
    args.exe = os.path.abspath(args.exe)
    args.flower = os.path.abspath(args.flower)
    name = STUDY + ("_quick" if args.quick else "")
    if args.budgets is None:
        args.budgets = [0.5, 1.0] if args.quick else [1.0, 2.0, 5.0, 10.0, 15.0, 30.0]
    only = args.models
    args.models = dict(QUICK_MODELS if args.quick else DEFAULT_MODELS)
    if only:
        wanted = [name.strip() for name in only.split(",") if name.strip()]
        unknown = [name for name in wanted if name not in DEFAULT_MODELS]
        if unknown:
            parser.error(f"--models: unknown {unknown}; the default models are {sorted(DEFAULT_MODELS)}")
        args.models = {name: DEFAULT_MODELS[name] for name in wanted}
    args.models.update(dict(args.extra))
    if args.quick:
        args.work = os.path.join(args.work, "quick")
    json_path = os.path.join(args.results, name + ".json")
    if args.report_only:
        record = read_json(json_path)
    else:
        if not os.path.exists(os.path.join(args.flower, "poses_bounds.npy")):
            parser.error(f"--flower {args.flower}: no LLFF capture there (poses_bounds.npy)")
        record = measure(args)
        record["results_name"] = name
    os.makedirs(args.results, exist_ok=True)
    note = plot(record, os.path.join(args.results, name + ".png"))
    if not args.report_only:  # the .json says whether the measurement drew its plot; --report-only changes no .json
        record["plot_note"] = note
        with open(json_path, "w") as f:
            json.dump(record, f, indent=1)
            f.write("\n")
    report_md.write_report(os.path.join(args.results, name + ".md"), write_markdown(record),
                           f"python3 {SCRIPT} --report-only" + (" --quick" if args.quick else ""))
    print(f"{STUDY}: wrote {args.results}/{name}.md" + ("" if args.report_only else ", .json")
          + (f" ({note})" if note else " and .png"))


if __name__ == "__main__":
    main()
