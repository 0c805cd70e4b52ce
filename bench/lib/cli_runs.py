"""What the studies share about mipnerf-cl's runs: the procedural scene, a resumable training, reading a run's outputs
(run() itself is lib/run.py)."""

import json
import os
import shlex
import statistics
import time

from lib import report_md
from lib.provenance import commit_of  # noqa: F401  (the studies import it from here)
from lib.machine import load_average
from lib.run import run  # noqa: F401  (the studies import it from here)


def read_json(path):
    with open(path) as f:
        return json.load(f)


def procedural_scene(exe, work):
    """Makes the built-in procedural scene (64x64, with its multiscale copy) in work/procedural once."""
    folder = os.path.join(work, "procedural")
    if not os.path.exists(os.path.join(folder, "multiscale", "metadata.json")):
        run([exe, "make-scene", folder, "--size", "64"], os.path.join(work, "make-scene.log"))
    return folder


def device_line(device):
    return f"{device.get('name')} ({device.get('platform')}, driver {device.get('driver_version')})"


def train_resumable(exe, data, out, preset, variant, settings, log):
    """`mipnerf-cl train` into `out`, resumable: a finished run (summary.json at its step count) is reused, an
    interrupted one (checkpoints, no summary) continues with --resume. Returns (summary, the command)."""
    command = [exe, "train", "--data", data, "--out", out, "--preset", preset, "--variant", variant]
    for name, value in settings.items():
        command += ["--set", f"{name}={value}"]
    summary_path = os.path.join(out, "summary.json")
    steps = settings.get("steps")
    if os.path.exists(summary_path):
        summary = read_json(summary_path)
        if not summary.get("interrupted") and (steps is None or summary.get("steps") == int(steps)) \
                and "val" in summary:
            return summary, command
    if os.path.isdir(os.path.join(out, "checkpoints")) and os.listdir(os.path.join(out, "checkpoints")):
        command.append("--resume")
    run(command, log)
    return read_json(summary_path), command


def read_val_log(run_dir):
    """The rows of a run's val_log.csv (val_every): dicts of floats keyed by the header."""
    path = os.path.join(run_dir, "val_log.csv")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        header = f.readline().strip().split(",")
        return [dict(zip(header, map(float, line.strip().split(",")))) for line in f if line.strip()]


def read_train_log(run_dir):
    """(step, wall_seconds) of each row of the run's train_log.csv."""
    rows = []
    with open(os.path.join(run_dir, "train_log.csv")) as f:
        header = f.readline().strip().split(",")
        step, wall = header.index("step"), header.index("wall_seconds")
        for line in f:
            fields = line.strip().split(",")
            if len(fields) == len(header):
                rows.append((int(fields[step]), float(fields[wall])))
    return rows


def warm_seconds_per_step(run_dir):
    """The median step time of a run logged every step, from its second step on (the first is cold)."""
    rows = read_train_log(run_dir)
    return statistics.median(b[1] - a[1] for a, b in zip(rows[1:], rows[2:]))


def train_for_minutes(exe, data, out, model_args, seed, minutes, factor, log):
    """`mipnerf-cl train --minutes` into `out` with `model_args` (a string) at `seed` and `--set factor`, resumable:
    a finished run (summary.json, not interrupted) is reused, an interrupted one continues with --resume. The load
    average before and after goes to out/load.txt. Returns `out`."""
    summary = os.path.join(out, "summary.json")
    if not (os.path.exists(summary) and not read_json(summary).get("interrupted", True)):
        resume = os.path.isdir(os.path.join(out, "checkpoints")) and os.listdir(os.path.join(out, "checkpoints"))
        command = [exe, "train", "--data", data, "--out", out, *shlex.split(model_args),
                   "--set", f"factor={factor}", "--set", f"seed={seed}", "--minutes", f"{minutes:g}",
                   "--set", "val_views=1", "--set", "val_every=0"]
        load_before = load_average()
        run(command + (["--resume"] if resume else []), log)
        with open(os.path.join(out, "load.txt"), "w") as f:
            f.write(f"{load_before} {load_average()}\n")
    return out


def evaluate_val(exe, data, run_dir, views, log):
    """`mipnerf-cl eval` of a run on `views` val views of `data` (no images), once; returns its metrics.json."""
    out = os.path.join(run_dir, "eval_val")
    if not os.path.exists(os.path.join(out, "metrics.json")):
        run([exe, "eval", "--checkpoint", run_dir, "--data", data, "--split", "val", "--views", str(views),
             "--out", out, "--no-images"], log)
    return read_json(os.path.join(out, "metrics.json"))


def run_record(seed, run_dir, metrics):
    """One trained and scored run as a study's JSON keeps it."""
    summary = read_json(os.path.join(run_dir, "summary.json"))
    return {"seed": seed, "steps": summary["steps"], "train_seconds": summary["train_seconds"],
            "parameters": summary["parameters"], "psnr": metrics["mean"]["psnr"], "ssim": metrics["mean"]["ssim"],
            "render_seconds_per_megapixel": metrics["render"]["seconds_per_megapixel"], "device": metrics["device"]}


def mean_sd(values):
    """Mean and sample standard deviation (0 for one value)."""
    mean = statistics.mean(values)
    return mean, (statistics.stdev(values) if len(values) > 1 else 0.0)


SEED_TABLE_HEADER = ["PSNR (mean ± sd)", "SSIM (mean ± sd)", "PSNR per seed", "steps (mean)", "s/step", "train s (mean)"]


def seed_table_cells(runs):
    """A model's cells under SEED_TABLE_HEADER from its runs (run_record dicts, one per seed)."""
    psnr, psnr_sd = mean_sd([x["psnr"] for x in runs])
    ssim, ssim_sd = mean_sd([x["ssim"] for x in runs])
    steps = statistics.mean(x["steps"] for x in runs)
    train_s = statistics.mean(x["train_seconds"] for x in runs)
    return [f"{psnr:.2f} ± {psnr_sd:.2f}", f"{ssim:.3f} ± {ssim_sd:.3f}", " / ".join(f"{x['psnr']:.2f}" for x in runs),
            f"{steps:.0f}", f"{train_s / steps:.3f}", f"{train_s:.0f}"]


def models_seed_by_seed(args, data, models, log):
    """The rows of a budget study's record: each (key, label, train arguments) of `models` trained with
    `train --minutes args.minutes` at args.factor for every seed of args.seeds (comma-separated) and scored by `eval` on
    args.views val views of `data`, seed by seed with every model in turn (a slow spell of the shared machine falls on
    all models, not on one). Runs go to args.work/KEY/seedS; finished runs and scores there are reused."""
    seeds = [int(s) for s in args.seeds.split(",")]
    runs = {key: [] for key, _, _ in models}
    for seed in seeds:
        for key, _, model_args in models:
            run_dir = train_for_minutes(args.exe, data, os.path.join(args.work, key, f"seed{seed}"), model_args, seed,
                                        args.minutes, args.factor, log)
            metrics = evaluate_val(args.exe, data, run_dir, args.views, log)
            runs[key].append(run_record(seed, run_dir, metrics))
    return [{"key": key, "label": label, "arguments": model_args, "runs": runs[key]} for key, label, model_args in models]


def budget_report_head(record, script, json_name, title):
    """The generated head of a budget study's report: banner, title, the runs' line (scene, budget, seeds, device,
    commit, date) and the table of models (SEED_TABLE_HEADER and render s/MP), as lines."""
    rows = record["rows"]
    header = ["model", *SEED_TABLE_HEADER, "render s/MP"]
    body = [[r["label"], *seed_table_cells(r["runs"]),
             f"{statistics.mean(x['render_seconds_per_megapixel'] for x in r['runs']):.1f}"] for r in rows]
    lines = [report_md.generated_banner(script, json_name), "", "# " + title, "",
             f"{record['scene']}; `train --minutes {record['budget_minutes']:g}` per run, seeds "
             f"{', '.join(str(s) for s in record['seeds'])}; device {device_line(rows[0]['runs'][0]['device'])}; "
             f"commit {record['commit']}; {record['date']}.", ""]
    return lines + report_md.table(header, "lrrrrrrr", body)


def budget_record(study, args, scene, started, rows):
    """A budget study's JSON record: its rows (models_seed_by_seed), what was measured and when."""
    return {
        "study": study, "date": time.strftime("%Y-%m-%d", time.gmtime()), "commit": commit_of(), "scene": scene,
        "budget_minutes": args.minutes, "seeds": [int(s) for s in args.seeds.split(",")],
        "wall_seconds": round(time.time() - started, 1), "rows": rows,
    }


def unbounded_scene(exe, work, log):
    """The built-in 360-degree capture (`make-scene --unbounded`) in work/scene, made once."""
    folder = os.path.join(work, "scene")
    if not os.path.exists(os.path.join(folder, "poses_bounds.npy")):
        run([exe, "make-scene", folder, "--unbounded"], log)
    return folder


def add_budget_arguments(parser, work, minutes, factor, factor_help, views_help, keys):
    """The flags every budget study takes: the build, its work folder, the budget, seeds, factor, views, --only."""
    parser.add_argument("--build", default="build", help="build folder holding mipnerf-cl")
    parser.add_argument("--work", default=work, help="the scene, runs and logs")
    parser.add_argument("--minutes", type=float, default=minutes, help="training budget of every run")
    parser.add_argument("--seeds", default="0,1,2", help="comma-separated seeds, each model trained once per seed")
    parser.add_argument("--factor", type=int, default=factor, help=f"the capture's downsampling ({factor_help})")
    parser.add_argument("--views", type=int, default=5, help=f"val views scored ({views_help})")
    parser.add_argument("--only", help=f"comma-separated model keys ({', '.join(keys)})")


def budget_setup(args, results, models):
    """Resolves args.exe and args.work, makes the work and results folders; returns the log path and the models
    (key, label, arguments) that --only keeps."""
    args.exe = os.path.abspath(os.path.join(args.build, "mipnerf-cl"))
    args.work = os.path.abspath(args.work)
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(results, exist_ok=True)
    kept = [m for m in models if not args.only or m[0] in args.only.split(",")]
    return os.path.join(args.work, "study.log"), kept


def gain_lines(what, runs, base_runs):
    """A report's line of PSNR gains seed by seed ("`what`, seed by seed: +x dB, … (mean +y dB)."), as lines."""
    gains = [x["psnr"] - y["psnr"] for x, y in zip(runs, base_runs)]
    return ["", f"{what}, seed by seed: " + ", ".join(f"{g:+.2f} dB" for g in gains)
            + f" (mean {statistics.mean(gains):+.2f} dB)."]


def wall_time_lines(record):
    """The study's wall time, as lines; none when every run was reused from --work (under a minute)."""
    if record["wall_seconds"] < 60:
        return []
    return ["", f"Study wall time {record['wall_seconds'] / 60:.1f} minutes."]


def measure_budget(args, study, results, models, data, scene):
    """A budget study's measurement: every kept model (budget_setup) trained seed by seed on `data` (a path, or a
    function of (exe, work, log) that makes the capture, e.g. unbounded_scene), its JSON record describing it as
    `scene` (formatted with args: {factor}, {views})."""
    log, kept = budget_setup(args, results, models)
    data = data(args.exe, args.work, log) if callable(data) else os.path.abspath(data)
    started = time.time()
    rows = models_seed_by_seed(args, data, kept, log)
    return budget_record(study, args, scene.format(factor=args.factor, views=args.views), started, rows)


# mip-NeRF 360 at the quick preset's size, as the scene chooses it on a 360-degree capture (unbounded_mipnerf's best
# row): proposal rounds of 32 on 4x64 density MLPs, the contracted IPE, the distortion loss 0.01.
M360_QUICK_32 = ("--preset quick --set sampler=proposal --set unbounded=true --set proposal_mlp_width=64 "
                 "--set proposal_samples=32 --set distortion_mult=0.01")

UNBOUNDED_SCENE = "make-scene --unbounded (40 views around, 5 held out), factor {factor}, {views} val views"


def budget_markdown(record, script, json_name, title, gains):
    """A budget study's report: its head (budget_report_head), a line of seed-by-seed gains for each (what, key,
    base key) of `gains` whose two rows were measured (`what` formatted with the row's {label}), the wall time."""
    lines = budget_report_head(record, script, json_name, title)
    by_key = {r["key"]: r for r in record["rows"]}
    for what, key, base in gains:
        if key in by_key and base in by_key:
            lines += gain_lines(what.format(label=by_key[key]["label"]), by_key[key]["runs"], by_key[base]["runs"])
    lines += wall_time_lines(record)
    return "\n".join(lines) + "\n"
