#!/usr/bin/env python3
"""Side-by-side benchmark: mipnerf-cl against the official google/mipnerf (JAX) code.

THE MEASUREMENT (on a quiet machine, from a clean checkout of mipnerf-cl with build/mipnerf-cl built from it):

  git clone https://github.com/google/mipnerf /tmp/official && git -C /tmp/official checkout 84c969e
  python3 bench/studies/vs_official.py --official /tmp/official --data /work/shared/data/nerf_synthetic/lego \\
      --rounds 5 --configs quick paper --train-steps 1000 --device-name pocl_cpu

  (about 25 min on 2 CPU cores; --train-steps 1000 adds the val-PSNR comparison, about 10 of them; drop it for
  timings only). It writes bench/results/vs_official/vs_official_pocl_cpu.json (every round's every timing) and the .md
  generated from it. When /tmp/official is a `git archive` instead of a clone, add
  --official-commit 84c969e0a623edd183b75693aed72a7e7c22902d. It refuses to run on a tree with uncommitted
  changes (tracked or untracked files other than build*/ and runs/); --allow-dirty runs anyway and records the
  sha256 of the changes. Regenerate the .md alone (no measurement) with
  python3 bench/studies/vs_official.py --report-only bench/results/vs_official/vs_official_pocl_cpu.json
  Hand-written notes go under "## Notes (by hand)" at the end of the .md; regeneration keeps that section.

What it does (issue 13, deliverable 4), in one run on one machine:
  * For each configuration -- `quick` (the quick preset's network at 512 rays) and `paper` (the paper's network at
    1,024 rays) -- a probe run of mipnerf-cl (not counted) gives our configuration from its own `bench.json`; the
    official model is configured from it, and the two parameter counts must agree or the script stops. Then
    --rounds (default 5) ALTERNATING rounds: round 1 runs ours then the official code, round 2 the official code
    then ours, and so on, each side --quick-steps / --paper-steps warm steps per round. Every round records both
    sides' step times, the load average (1/5/15 min) before and after it, its wall time and, from /proc/stat, the
    CPU time other processes took during it. The report gives, per side and for the ratio, the median over rounds
    of each round's median and the min-max over rounds.
  * mipnerf-cl's step: `mipnerf-cl bench --sections train --presets P --set batch_size=B --data LEGO
    --set factor=4`, a fresh process per round, warm steps from bench.json (`warm_step_seconds`: wall time between
    step returns, each ending with the device queue finished; the cold first step and the kernel builds are
    excluded by bench itself).
  * The official step: its `train.train_step` (model `internal/models.py` MipNerfModel built by
    `construct_mipnerf`, the loss of train.py with coarse_loss_mult and lossmult weighting, gradient
    statistics), pmapped over the one CPU device exactly as train.py does, with Adam from optax
    behind a small `flax.optim` stand-in (modern flax has no `flax.optim`). Each step is timed with
    `block_until_ready`; the XLA compile and a warm-up step are excluded. Batches are random rays
    over all training images of the scene, built before timing (data loading excluded; the official
    train.py prefetches in a thread).
  * Render time (quick configuration only): the first training camera at the scene's size after
    --factor (100x100 for lego at factor 4), warm, s/MP from the best render, for both (ours in the probe run).
  * Records the mipnerf-cl commit, whether the tree was clean, the executable's sha256, the official commit and
    every version; writes bench/results/vs_official/vs_official_<device>.json and the .md generated from it (write_markdown).

The official code runs in a worker process (this same file with --worker) inside a virtual
environment the script creates (--venv) and fills from PyPI with jax[cpu], flax, optax, gin-config,
numpy, pillow. The official checkout is only read (sys.path), never copied or patched on disk; the
import-time stand-ins are installed in the worker's memory and listed in the results (STUBS, bench/lib/official.py: the worker side
this study, vs_official_llff.py and official_step.py share).

A smoke test of the whole path (minutes; write it outside bench/results):
  python3 bench/studies/vs_official.py --official /tmp/official --configs quick --rounds 2 --quick-steps 2 \\
      --render-reps 1 --allow-dirty --out-dir /tmp/vs_official_smoke

Requirements: a built mipnerf-cl (--bin, default build/mipnerf-cl), a checkout of
github:google/mipnerf (--official), the Blender lego scene (--data), network access to PyPI the
first time (venv creation). The project's tests only import this file (tests/bench/test_scripts_import.py).
"""

import argparse
import datetime
import json
import os
import platform
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402  (standard library only; the worker does not use it)
from lib.machine import between, load_average, snapshot  # noqa: E402
from lib.official import (STUBS, Official, OfficialError, Worker, add_official_arguments,  # noqa: E402
                          check_official_checkout, ensure_venv,
                          official_commit, official_settings, serve_requests)
from lib.provenance import cpu_model, file_sha256, tree_state  # noqa: E402

from lib.provenance import REPO  # noqa: E402
DEFAULT_DATA = os.path.normpath(os.path.join(REPO, "..", "shared", "data", "nerf_synthetic", "lego"))
DEFAULT_ROUNDS = 5
FORMAT = 2  # results format: 2 = per-round records; 1 (no "format" key) = pooled steps, before 2026-11-26

# The two configurations: our preset and the batch size; everything else comes from the preset.
CONFIGS = [("quick", "quick", 512), ("paper", "paper", 1024)]



# ----------------------------------------------------------------------------------------------
# Orchestrator side (standard library only)
# ----------------------------------------------------------------------------------------------

def our_gemm_label(config_result):
    """What ran our training products, as the bench's training record says (host BLAS, tuned or default CLBlast);
    results written before that record existed fall back to whether a CLBlast tuning file was loaded."""
    runs = list(config_result.get("our_runs", []))
    runs += [r["ours"]["run"] for r in config_result.get("rounds", []) if "run" in r.get("ours", {})]
    used = {run.get("gemm_in_training", "") for run in runs} - {""}
    if used:
        return ", ".join(sorted(used))
    return "tuned" if config_result["gemm"].get("tuned") else "CLBlast defaults"


def fail(message):
    sys.exit(f"vs_official.py: {message}")


def parse_args(argv):
    measurement = __doc__.split("THE MEASUREMENT", 1)[1].split("What it does", 1)[0].rstrip()
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="The measurement" + measurement + "\n")
    add_official_arguments(p, REPO, report_md.results_folder("vs_official"))
    p.add_argument("--data", default=DEFAULT_DATA, help="Blender scene folder (default: ../shared's lego)")
    p.add_argument("--factor", type=int, default=4, help="downsample factor of the scene, both sides")
    p.add_argument("--configs", nargs="+", default=[c[0] for c in CONFIGS], help="quick and/or paper")
    p.add_argument("--rounds", type=int, default=DEFAULT_ROUNDS,
                   help=f"alternating rounds per configuration (default {DEFAULT_ROUNDS}; order ours/official, "
                        "official/ours, ...)")
    p.add_argument("--quick-steps", type=int, default=8, help="warm steps per side and round, quick (>= 1)")
    p.add_argument("--paper-steps", type=int, default=3, help="warm steps per side and round, paper (>= 1)")
    p.add_argument("--render-reps", type=int, default=2, help="timed renders per side (quick config)")
    p.add_argument("--train-steps", type=int, default=0,
                   help="also train both (quick config) for this many steps and score val PSNR (0: off; long)")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if not args.worker and not args.report_only:
        check_inputs(args)
    return args


def check_inputs(args):
    check_official_checkout(args.official)  # OfficialError: main says it in one line
    if not os.access(args.bin, os.X_OK):
        fail(f"--bin {args.bin}: not an executable; build mipnerf-cl first (cmake --build build)")
    if not os.path.isfile(os.path.join(args.data, "transforms_train.json")):
        fail(f"--data {args.data}: no transforms_train.json; pass a Blender scene folder (e.g. lego)")
    if not os.access(args.bin, os.X_OK):
        fail(f"--bin {args.bin}: not an executable; build mipnerf-cl first (cmake --build build)")
    for c in args.configs:
        if c not in [n for n, _, _ in CONFIGS]:
            fail(f"--configs: unknown '{c}' (quick, paper)")
    if args.rounds < 1:
        fail("--rounds must be at least 1")
    if args.quick_steps < 1 or args.paper_steps < 1:
        fail("--quick-steps and --paper-steps must be at least 1")


# ---- the checkout's state (tree_state and file_sha256: lib/provenance.py) ----


# ---- what else ran on the machine ----



def run_ours(args, preset, batch, steps, render_size, render_reps):
    """One `mipnerf-cl bench` run of one preset; returns its record from bench.json."""
    with tempfile.TemporaryDirectory(prefix="vs_official_") as out:
        cmd = [args.bin, "bench", "--sections", "train", "--presets", preset, "--steps", str(steps),
               "--paper-steps", str(steps), "--time-box", "0", "--profile-steps", "0", "--data", args.data,
               "--set", f"factor={args.factor}", "--set", f"batch_size={batch}",
               "--render-size", render_size, "--render-reps", str(render_reps), "--out", out]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            fail(f"{' '.join(cmd)} failed:\n{r.stderr[-2000:]}")
        with open(os.path.join(out, "bench.json")) as f:
            record = json.load(f)
    record["command_line"] = " ".join(cmd[1:]).replace(out, "TMP")
    return record


def our_run_entry(record):
    t, = record["devices"][0]["training"]
    return {"command": record["command_line"], "first_step_s": t["first_step_seconds"],
            "warm_step_seconds": t["warm_step_seconds"], "gemm": record["devices"][0]["gemm"],
            "gemm_in_training": t.get("gemm_parameters", "")}


def round_summary(rounds, batch):
    """Per side: the median over rounds of each round's median s/step, and its min-max over rounds; for the ratio
    (ours' rays/s over the official's = official s/step over ours, each round's medians): median and min-max."""
    ours = [statistics.median(r["ours"]["step_seconds"]) for r in rounds]
    official = [statistics.median(r["official"]["step_seconds"]) for r in rounds]
    ratios = [o / u for u, o in zip(ours, official)]

    def side(meds):
        m = statistics.median(meds)
        return {"median_s": m, "min_s": min(meds), "max_s": max(meds), "rays_per_s": batch / m,
                "round_medians_s": meds}

    all_ours = [s for r in rounds for s in r["ours"]["step_seconds"]]
    all_official = [s for r in rounds for s in r["official"]["step_seconds"]]
    pooled = {"ours_median_s": statistics.median(all_ours), "official_median_s": statistics.median(all_official)}
    pooled["ratio"] = pooled["official_median_s"] / pooled["ours_median_s"]
    return {"rounds": len(rounds), "ours": side(ours), "official": side(official),
            "ratio_rays_per_s": {"median": statistics.median(ratios), "min": min(ratios), "max": max(ratios),
                                 "per_round": ratios},
            "pooled_all_steps": pooled}


def bench_config(args, worker, name, preset, batch):
    """A probe run, then --rounds alternating rounds (ours/official, official/ours, ...) of one configuration."""
    steps = args.quick_steps if name == "quick" else args.paper_steps
    # Our render is measured in the probe run of the quick config only; the other runs render a tiny image
    # (bench always renders) so their cost stays small.
    full = ("100x100" if args.factor == 4 else "64x64", args.render_reps) if name == "quick" else ("8x8", 1)
    probe = run_ours(args, preset, batch, steps, *full)
    dev = probe["devices"][0]
    train, = dev["training"]
    model, mlp, config = official_settings(train["config"])
    setup = worker.call(cmd="setup", model=model, mlp=mlp, config=config)
    if setup["parameters"] != train["parameters"]:
        fail(f"{name}: parameter counts differ: mipnerf-cl {train['parameters']}, official {setup['parameters']}")
    print(f"{name}: parameters mipnerf-cl {train['parameters']} = official {setup['parameters']}", flush=True)
    rounds = []
    for r in range(args.rounds):
        order = ["ours", "official"] if r % 2 == 0 else ["official", "ours"]
        before = snapshot(worker)
        entry = {"round": r + 1, "order": order}
        for side in order:
            if side == "ours":
                run = our_run_entry(run_ours(args, preset, batch, steps, "8x8", 1))
                entry["ours"] = {"step_seconds": run["warm_step_seconds"], "run": run}
            else:
                entry["official"] = {"step_seconds": worker.call(cmd="steps", n=steps)["seconds"]}
        entry.update(between(before, snapshot(worker)))
        rounds.append(entry)
        u, o = (statistics.median(entry[s]["step_seconds"]) for s in ("ours", "official"))
        print(f"{name}: round {r + 1}/{args.rounds} ({' then '.join(order)}): ours {u:.3f} s/step, official "
              f"{o:.3f} s/step, ratio {o / u:.2f}x; load {entry['load_before']} -> {entry['load_after']}",
              flush=True)
    result = {"name": name, "batch_rays": batch, "steps_per_side_and_round": steps, "our_config": train["config"],
              "official_model": model, "official_mlp": mlp, "official_config": config,
              "parameters": {"mipnerf-cl": train["parameters"], "official": setup["parameters"]},
              "official_compile_s": setup["compile_s"], "gemm": dev["gemm"],
              "device": {"opencl_device": dev["device"]["name"], "pocl": dev["device"]["driver_version"],
                         "clblast": dev["clblast_version"]},
              "probe": our_run_entry(probe), "rounds": rounds}
    result["summary"] = round_summary(rounds, batch)
    if name == "quick":
        result["render"] = bench_render(args, worker, probe)
    return result


def train_psnr(args, worker, quick):
    """Both trained from scratch on the scene for --train-steps (quick config), then val PSNR."""
    import re
    c = quick["our_config"]
    with tempfile.TemporaryDirectory(prefix="vs_official_train_") as out:
        cmd = [args.bin, "train", "--preset", "quick", "--data", args.data, "--set", f"factor={args.factor}",
               "--set", f"batch_size={quick['batch_rays']}", "--set", f"steps={args.train_steps}", "--out", out]
        t0 = time.time()
        r = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.time() - t0
    m = re.search(r"val PSNR ([0-9.]+) dB.*?over (\d+) images; trained (\d+) steps in ([0-9.]+) s", r.stdout)
    if r.returncode != 0 or not m:
        fail(f"{' '.join(cmd)} failed or printed no val PSNR:\n{r.stdout[-1000:]}\n{r.stderr[-1000:]}")
    ours = {"mean_psnr": float(m.group(1)), "val_views": int(m.group(2)), "steps": int(m.group(3)),
            "train_seconds": float(m.group(4)), "command_wall_seconds": wall,
            "command": " ".join(cmd[1:]).replace(out, "TMP")}
    off = worker.call(cmd="train", model=quick["official_model"], mlp=quick["official_mlp"],
                      config=quick["official_config"], steps=args.train_steps, val_views=c["val_views"],
                      chunk=c["render_chunk_rays"])
    return {"steps": args.train_steps, "ours": ours, "official": off}


def bench_render(args, worker, record):
    ours = record["devices"][0]["render"]
    our_best = min(r["render_seconds_best"] for r in ours)
    mp = ours[0]["width"] * ours[0]["height"] / 1e6
    off = worker.call(cmd="render", reps=args.render_reps, chunk=ours[0]["chunk_rays"])
    if abs(off["megapixels"] - mp) > 1e-9:
        fail(f"render sizes differ: ours {mp} MP, official {off['megapixels']} MP")
    return {"view": "first training camera", "width": ours[0]["width"], "height": ours[0]["height"],
            "chunk_rays": ours[0]["chunk_rays"],
            "ours_seconds": [s for r in ours for s in r.get("render_seconds", [r["render_seconds_best"]])],
            "ours_s_per_mp": our_best / mp,
            "official_seconds": off["seconds"], "official_first_call_s": off["first_call_s"],
            "official_s_per_mp": min(off["seconds"]) / mp,
            "ratio": (our_best / mp) / (min(off["seconds"]) / mp)}


def results_base(args):
    return os.path.join(args.out_dir, f"vs_official_{args.device_name}")


def regen_command(json_path):
    return f"python3 bench/studies/vs_official.py --report-only {os.path.relpath(json_path, REPO)}"


def write_results(args, doc):
    os.makedirs(args.out_dir, exist_ok=True)
    base = results_base(args)
    with open(base + ".json", "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    report_md.write_report(base + ".md", write_markdown(doc), regen_command(base + ".json"))
    print(f"wrote {base}.md and {base}.json")


# ---- the report (generated from the .json only) ----

def upgrade(doc):
    """A results document in the current format: records of format 1 (two rounds, steps pooled, before
    2026-11-26) get their rounds back from the order they were run in (round 1 ours then official, round 2 the
    reverse, ...: the first run of ours, the first `steps` official steps, ...). Returns a new dict."""
    if doc.get("format", 1) >= FORMAT:
        return doc
    doc = json.loads(json.dumps(doc))
    versions = doc["versions"]
    commit = versions.get("mipnerf-cl", "")
    if isinstance(commit, str):
        versions["mipnerf-cl"] = {"commit": commit.split()[0] if commit else "unknown",
                                  "dirty": "uncommitted" in commit, "dirty_paths": None}
    for c in doc["configs"]:
        runs = c["our_runs"]
        n = len(runs)
        official = c["official"]["step_seconds"]
        per = len(official) // n
        load = c.get("load_average_per_round", [])
        rounds = []
        for i, run in enumerate(runs):
            rounds.append({"round": i + 1, "order": ["ours", "official"] if i % 2 == 0 else ["official", "ours"],
                           "ours": {"step_seconds": run["warm_step_seconds"], "run": run},
                           "official": {"step_seconds": official[i * per:(i + 1) * per]},
                           "load_before": load[i] if i < len(load) else None,
                           "load_after": load[i + 1] if i + 1 < len(load) else None,
                           "wall_s": None, "other_cpu_cores": None, "steal_cores": None})
        c["rounds"] = rounds
        c["steps_per_side_and_round"] = per
        c["probe"] = None  # format 1: round 1's run of ours was also the probe (and the render)
        c["summary"] = round_summary(rounds, c["batch_rays"])
    doc["format_upgraded_from"] = 1
    return doc


def fmt_load(load):
    return "–" if not load else "/".join(f"{x:.2f}" for x in load)


def fmt_cores(x):
    return "–" if x is None else f"{x:.2f}"


def conditions(doc):
    """Generated lines on what the record can and cannot support, from its own data."""
    v = doc["versions"]["mipnerf-cl"]
    rounds = [len(c["rounds"]) for c in doc["configs"]]
    lines = []
    if doc.get("format_upgraded_from") == 1:
        lines.append("- **Record of the old format** (before 2026-11-26): rounds were not reported; they are "
                     "reconstructed here from the order the steps were run in. Its round 1 run of mipnerf-cl was "
                     "also the run that read the configuration and rendered (no separate probe run), and our "
                     "figures were medians of all steps pooled (shown below the summary).")
    if min(rounds) < DEFAULT_ROUNDS:
        lines.append(f"- **{min(rounds)} round(s)** per configuration, fewer than the {DEFAULT_ROUNDS} this "
                     "benchmark asks for: the min-max over rounds says little.")
    if v.get("dirty"):
        sha = v.get("diff_sha256")
        lines.append("- **The mipnerf-cl tree had uncommitted changes** (" +
                     (f"sha256 of the changes {sha}" if sha else "not recorded what they were") +
                     "): the code measured is not exactly commit " + v["commit"][:12] + ".")
    others = [r["other_cpu_cores"] for c in doc["configs"] for r in c["rounds"] if r.get("other_cpu_cores") is not None]
    if others and max(others) > 0.1:
        lines.append(f"- **Other processes used CPU during the rounds**: up to {max(others):.2f} cores on average "
                     "over a round (machine CPU time from /proc/stat minus this benchmark's own processes); the "
                     "machine was not quiet.")
    loads = [x[0] for c in doc["configs"] for r in c["rounds"] for x in (r.get("load_before"), r.get("load_after")) if x]
    if loads and not others:
        lines.append(f"- The 1-minute load average at the round boundaries ranged {min(loads):.2f}-{max(loads):.2f} "
                     f"on {doc['versions']['machine']['hardware_threads']} hardware threads (it includes this "
                     "benchmark's own processes; the other processes' CPU time was not recorded by this format).")
    if not lines:
        lines.append(f"- {min(rounds)} rounds per configuration, a clean tree at commit {v['commit'][:12]}, other "
                     "processes below 0.1 cores in every round.")
    return lines


def write_markdown(doc):
    """The report, generated from a results document (any format) alone."""
    doc = upgrade(doc)
    v = doc["versions"]
    mv = v["mipnerf-cl"]
    json_name = f"vs_official_{doc['device_name']}.json" if doc.get("device_name") else "the .json of the same name"
    lines = ["# mipnerf-cl against the official mip-NeRF code (JAX), same machine", "",
             report_md.generated_banner("bench/studies/vs_official.py", json_name), "",
             f"Measured {doc['date']} by `{doc['command']}` ({doc['seconds'] / 60:.1f} min).", "",
             "## Conditions", ""] + conditions(doc) + [""]
    lines += ["## Training steps (warm), over alternating rounds", "",
              "Each round times both sides (round 1 ours first, round 2 the official code first, ...). Per side: the "
              "median over rounds of the round's median s/step, with the min-max of the round medians; rays/s from "
              "that median. Ratio: ours' rays/s over the official's in each round (the official's median s/step "
              "over ours), median over rounds and min-max.", ""]
    rows = []
    for r in doc["configs"]:
        s, c = r["summary"], r["our_config"]
        o, j, q = s["ours"], s["official"], s["ratio_rays_per_s"]
        label = (f"{r['name']}: {r['batch_rays']} rays × {c['num_samples']} samples/level, "
                 f"{c['mlp_depth']}×{c['mlp_width']} (skip after {c['mlp_skip']}), view {c['view_branch_width']}, "
                 f"L = {c['pos_max_deg']}")
        rows.append([label, f"{s['rounds']} × {r['steps_per_side_and_round']}",
                     f"{o['median_s']:.3f} ({o['min_s']:.3f}-{o['max_s']:.3f}), {o['rays_per_s']:.0f}",
                     f"{j['median_s']:.3f} ({j['min_s']:.3f}-{j['max_s']:.3f}), {j['rays_per_s']:.0f}",
                     f"**{q['median']:.2f}×** ({q['min']:.2f}-{q['max']:.2f})", str(r["parameters"]["mipnerf-cl"])])
    lines += report_md.table(["config", "rounds × steps per side", "mipnerf-cl s/step (min-max), rays/s",
                              "official s/step (min-max), rays/s", "ratio, rays/s (min-max)", "parameters (both)"],
                             "lrrrrr", rows)
    lines += ["", "All steps pooled instead (one median per side over every round's steps; not the headline): " +
              "; ".join(f"{r['name']} {r['summary']['pooled_all_steps']['ours_median_s']:.3f} against "
                        f"{r['summary']['pooled_all_steps']['official_median_s']:.3f} s/step, "
                        f"{r['summary']['pooled_all_steps']['ratio']:.2f}×" for r in doc["configs"]) + ".", ""]
    lines += ["## Rounds", ""]
    rows = []
    for r in doc["configs"]:
        for x, ratio in zip(r["rounds"], r["summary"]["ratio_rays_per_s"]["per_round"]):
            u = statistics.median(x["ours"]["step_seconds"])
            o = statistics.median(x["official"]["step_seconds"])
            wall = "–" if x.get("wall_s") is None else f"{x['wall_s']:.0f}"
            rows.append([r["name"], str(x["round"]), " then ".join(x["order"]), f"{u:.3f}", f"{o:.3f}", f"{ratio:.2f}×",
                         f"{fmt_load(x.get('load_before'))} → {fmt_load(x.get('load_after'))}",
                         fmt_cores(x.get("other_cpu_cores")), wall])
    lines += report_md.table(["config", "round", "order", "mipnerf-cl median s/step", "official median s/step", "ratio",
                              "load average before → after (1/5/15 min)", "other processes' CPU (cores)",
                              "round wall s"], "lrlrrrlrr", rows)
    lines += ["", "Load averages include this benchmark's own processes (both cores busy during a round) and are "
              "updated by the kernel every 5 s, so a short round may show none of its own change; the "
              "other processes' CPU is the machine's busy CPU time during the round (/proc/stat) minus that of "
              "this script, its mipnerf-cl runs and the official worker, over the round's wall time.", ""]
    for r in doc["configs"]:
        if "render" in r:
            x = r["render"]
            lines += ["## Render (warm)", "",
                      f"{x['view']}, {x['width']}×{x['height']}, {x['chunk_rays']} rays per chunk, networks of "
                      f"the `{r['name']}` configuration after each side's timed steps, s/MP from the best render "
                      "(ours: `mipnerf-cl bench`'s render of the same camera in the "
                      f"{'probe run' if r.get('probe') else 'first round'}, its first chunk timed apart; "
                      "official: models.render_image after one untimed render). One measurement per side, not "
                      "alternated.", ""]
            lines += report_md.table(["", "mipnerf-cl", "official"], "lrr", [
                ["render s", ", ".join(f"{s:.2f}" for s in x["ours_seconds"]),
                 ", ".join(f"{s:.2f}" for s in x["official_seconds"])],
                ["s/MP (best)", f"{x['ours_s_per_mp']:.0f}", f"{x['official_s_per_mp']:.0f}"],
                ["ratio (time, lower is faster for us)", f"{x['ratio']:.2f}×", ""]])
            lines.append("")
    t = doc.get("training")
    if t:
        o, j = t["ours"], t["official"]
        lines += [f"## Training on the scene for {t['steps']} steps (quick configuration), then val PSNR", "",
                  "One run per side, after the rounds (not alternated).", ""]
        lines += report_md.table(["", "mipnerf-cl", "official"], "lrr", [
            [f"val PSNR (mean of the first {o['val_views']} val views)", f"{o['mean_psnr']:.2f} dB",
             f"{j['mean_psnr']:.2f} dB"],
            ["training wall time", f"{o['train_seconds']:.1f} s (whole command {o['command_wall_seconds']:.1f} s)",
             f"{j['train_seconds']:.1f} s (+ {j['compile_s']:.1f} s XLA compile and 2 warm-up steps)"]])
        lines += ["",
                  f"Ours: `mipnerf-cl {o['command']}`; official: fresh parameters, its learning_rate_decay with "
                  "our preset's schedule, a new batch of random rays over all images each step (made in the loop).",
                  ""]
    else:
        lines += ["Training both to a val PSNR (`--train-steps N`) was not run.", ""]
    lines += ["## Every step time (s)", ""]
    for r in doc["configs"]:
        if r.get("probe"):
            lines.append(f"- {r['name']}, probe run of mipnerf-cl (not in the rounds): "
                         f"{', '.join(f'{s:.3f}' for s in r['probe']['warm_step_seconds'])}")
        for x in r["rounds"]:
            lines.append(f"- {r['name']}, round {x['round']}: mipnerf-cl "
                         f"{', '.join(f'{s:.3f}' for s in x['ours']['step_seconds'])}; official "
                         f"{', '.join(f'{s:.3f}' for s in x['official']['step_seconds'])}")
        lines.append(f"- {r['name']}: official XLA compile + 2 warm-up steps {r['official_compile_s']:.1f} s; "
                     f"our GEMM in training: {our_gemm_label(r)}")
    if doc.get("notes"):
        lines += ["", "## Notes (recorded with the run: --note)", ""] + [f"- {n}" for n in doc["notes"]]
    commit_line = f"- mipnerf-cl: commit {mv['commit']}"
    if mv.get("dirty"):
        commit_line += " with uncommitted changes"
        if mv.get("diff_sha256"):
            paths = [p[3:] for p in mv.get("dirty_paths") or []]
            shown = ", ".join(paths[:12]) + (f" and {len(paths) - 12} more (all in the .json)" if len(paths) > 12 else "")
            commit_line += f" (sha256 of the changes {mv['diff_sha256']}; {len(paths)} changed paths: {shown})"
    else:
        commit_line += " (clean tree)"
    binary = v.get("binary")
    if binary:
        commit_line += f"; executable {binary['path']} sha256 {binary['sha256'][:16]}…, modified {binary['mtime']}"
    commit_line += (f"; OpenCL device {v['machine']['opencl_device']}, PoCL {v['machine']['pocl']}, "
                    f"CLBlast {v['machine']['clblast']}")
    lines += ["", "## Machine and versions", "",
              f"- CPU: {v['machine']['cpu']}, {v['machine']['hardware_threads']} hardware threads; "
              f"{v['machine']['platform']}",
              f"- load average (1/5/15 min): before the run {fmt_load(doc['load_average_before'])}, after it "
              f"{fmt_load(doc['load_average_after'])}",
              commit_line,
              f"- official: google/mipnerf {v['official_commit']}; python {v['python']}, jax {v['jax']}, "
              f"jaxlib {v['jaxlib']}, flax {v['flax']}, optax {v['optax']}, numpy {v['numpy']}, "
              f"gin-config {v['gin']}; XLA CPU devices {v['jax_devices']}", "",
              "## Configurations", ""]
    for r in doc["configs"]:
        first = r["probe"] or r["rounds"][0]["ours"]["run"]
        lines += [f"### {r['name']}", "",
                  f"- mipnerf-cl (`bench.json` config): `{json.dumps(r['our_config'], sort_keys=True)}`",
                  f"- our runs: `mipnerf-cl {first['command']}`" +
                  (" (the probe; the rounds' runs render 8x8 once)" if r.get("probe") else ""),
                  f"- official MipNerfModel: `{json.dumps(r['official_model'], sort_keys=True)}`",
                  f"- official MLP: `{json.dumps(r['official_mlp'], sort_keys=True)}`",
                  f"- official Config (train_step): `{json.dumps(r['official_config'], sort_keys=True)}`", ""]
    lines += ["## Stand-ins for the official code's imports (in the worker's memory; its files are unchanged)", ""]
    lines += [f"- `{s['name']}`: {s['what']}" for s in doc["stubs"]]
    lines += ["", "## What is identical and what is not", "", IDENTICAL, ""]
    return "\n".join(lines)


IDENTICAL = """\
Identical: the network (same layer shapes; the parameter counts are compared and printed), samples
per level, two levels through one shared MLP, IPE degrees, view encoding (degrees 0..3 + identity),
softplus density with bias -1, padded sigmoid colour, resample padding 0.01 with blur-pool, stratified
randomized sampling, near 2 / far 6, white background, the loss (coarse_loss_mult x coarse MSE + fine
MSE, lossmult-weighted, lossmult = 1 at one scale), Adam (b1 0.9, b2 0.999, eps 1e-8), float32, the
scene (lego at the same factor, box-downsampled on both sides), the batch size, the 2 CPU cores.

Not identical:
- Batches: ours draws its rays on the device inside the step (part of our timed step); the official
  step gets one of 8 batches of random rays over all images prepared beforehand, copied to the device
  before its timer starts (train_step donates it), so data loading is excluded on its side (train.py
  prefetches batches in a thread, so this is close to what it does in training). Random numbers differ.
- The official train_step also computes gradient statistics (norm, max) and a pmean over one device,
  as train.py does; it is pmapped over the single CPU device like train.py. Weight decay is 0 (skipped
  at trace time in neither: it is multiplied by 0 as in train.py).
- Adam: optax.adam inside a flax.optim stand-in instead of the removed flax.optim.Adam (same update).
- Our step times come from `mipnerf-cl bench` (a fresh process per round; the cold first step and
  kernel builds excluded); the official steps from one long-lived process (XLA compile excluded).
- Rendering: the official render goes through models.render_image with a pmapped eval function as in
  train.py, randomized = False, with the chunk size set to ours; both networks are the ones after
  each side's few timed steps (the cost of a render does not depend on the weights).
- XLA and PoCL choose their own threading on the 2 cores; neither is pinned."""


def orchestrate(args):
    started = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    t0 = time.time()
    tree = tree_state()
    if tree["dirty"]:
        listing = "\n  ".join(tree["dirty_paths"][:30])
        if not args.allow_dirty:
            fail(f"the mipnerf-cl checkout {REPO} differs from commit {tree['commit'][:12]} (git status --porcelain, "
                 f"build*/ and runs/ ignored):\n  {listing}\nCommit or remove the changes, or pass --allow-dirty "
                 "(the results then record the sha256 of the changes and say the tree was dirty).")
        print(f"vs_official.py: --allow-dirty: the tree differs from {tree['commit'][:12]} (sha256 of the changes "
              f"{tree['diff_sha256']}); recorded in the results", flush=True)
    tree["allow_dirty"] = args.allow_dirty
    binary = {"path": os.path.relpath(os.path.abspath(args.bin), REPO), "sha256": file_sha256(args.bin),
              "mtime": datetime.datetime.fromtimestamp(os.path.getmtime(args.bin), datetime.timezone.utc)
              .strftime("%Y-%m-%dT%H:%M:%SZ")}
    py = ensure_venv(args.venv, args.python)
    load_before = load_average()
    worker = Worker([py, os.path.abspath(__file__), "--worker", "--official", args.official, "--data", args.data,
                     "--factor", str(args.factor)])
    versions = worker.call(cmd="versions")
    results = [bench_config(args, worker, name, preset, batch)
               for name, preset, batch in CONFIGS if name in args.configs]
    versions["machine"] = {"cpu": cpu_model(), "hardware_threads": os.cpu_count(),
                           "platform": platform.platform(), **results[0]["device"]}
    versions["mipnerf-cl"] = tree
    versions["binary"] = binary
    versions["official_commit"] = args.official_commit or official_commit(args.official)
    doc = {"format": FORMAT, "tool": "bench/studies/vs_official.py", "date": started, "device_name": args.device_name,
           "command": "python3 bench/studies/vs_official.py " + shlex.join(sys.argv[1:]), "rounds_requested": args.rounds,
           "versions": versions, "stubs": [{"name": n, "what": w} for n, w in STUBS],
           "load_average_before": load_before, "configs": results, "training": None, "notes": args.note}
    doc["load_average_after"], doc["seconds"] = load_average(), time.time() - t0
    write_results(args, doc)
    if args.train_steps > 0:  # long: the timing results above are written first
        quick = [r for r in results if r["name"] == "quick"]
        if not quick:
            fail("--train-steps needs the quick configuration in --configs")
        doc["training"] = train_psnr(args, worker, quick[0])
        doc["load_average_after"], doc["seconds"] = load_average(), time.time() - t0
        write_results(args, doc)
    worker.close()


# ----------------------------------------------------------------------------------------------
# Worker side (runs in the venv; imports jax and the official code)
# ----------------------------------------------------------------------------------------------

def worker_main(args):
    serve_requests(lambda: Official(args.official, args.data, args.factor), {
        "versions": lambda off, req: off.versions(),
        "setup": lambda off, req: off.setup(**req),
        "steps": lambda off, req: {"seconds": off.steps(req["n"])},
        "render": lambda off, req: off.render(req["reps"], req["chunk"]),
        "train": lambda off, req: off.train_and_score(**req)})


def main(argv):
    try:
        dispatch(parse_args(argv))
    except OfficialError as e:  # the official side's one-line reasons (lib/official.py)
        fail(str(e))


def dispatch(args):
    if args.worker:
        worker_main(args)
    elif args.report_only:
        with open(args.report_only) as f:
            doc = json.load(f)
        if "pairs" in doc:
            fail(f"{args.report_only} is a forward-facing (LLFF) result: regenerate it with "
                 f"bench/studies/vs_official_llff.py --report-only {args.report_only}")
        md = os.path.splitext(args.report_only)[0] + ".md"
        report_md.write_report(md, write_markdown(doc), regen_command(os.path.abspath(args.report_only)))
        print(f"wrote {md}")
    else:
        orchestrate(args)


if __name__ == "__main__":
    main(sys.argv[1:])
