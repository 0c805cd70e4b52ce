#!/usr/bin/env python3
"""The summary of a scripts/device-check.sh run, from its work folder: summary.md and summary.json (each step's status,
seconds and limit, the machine, and each step's key figures), bench.json (the presets' bench.json records) and
official.json (the official step's record per precision), written into --out. Standard library only (it runs with
whatever python3 the device machine has)."""

import argparse
import csv
import glob
import json
import os
import time
import xml.etree.ElementTree as ElementTree

PRESETS = ["quick", "small", "paper"]
PRECISIONS = ["default", "float32"]


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def read_tsv(path, fields):
    try:
        with open(path) as f:
            return [dict(zip(fields, row)) for row in csv.reader(f, delimiter="\t", quoting=csv.QUOTE_NONE)]
    except OSError:
        return []


def training_figures(record):
    """One preset's training record of a bench.json: step time, rays/s, what ran the products, the costliest stages."""
    device = record["devices"][0]
    t = device["training"][0]
    profile = t.get("stage_profile") or {}
    stages = sorted(profile.get("stages", []), key=lambda s: -s["seconds_per_step"])[:6]
    return {"device": device["device"]["name"], "preset": t["preset"], "batch_rays": t["batch_rays"],
            "samples_per_level": t["samples_per_level"], "parameters": t["parameters"],
            "first_step_s": t["first_step_seconds"], "warm_steps": t["warm_steps"],
            "step_s_median": t["step_seconds_median"], "step_s_best": t["step_seconds_best"],
            "rays_per_s": t["rays_per_second"], "gemm": t.get("gemm_parameters", ""),
            "gemm_gflops_in_step": profile.get("gemm_gflops"),
            "costliest_stages": [(s["stage"], s["seconds_per_step"]) for s in stages],
            "render_s_per_mp": next((r["seconds_per_megapixel"] for r in device.get("render", [])
                                     if r.get("preset") == t["preset"]), None),
            "errors": device.get("errors", [])}


def gemm_figures(record):
    """The GEMM section of a bench.json: best GFLOP/s of each product with CLBlast's default and tuned parameters."""
    gemm = record["devices"][0].get("gemm") or {}
    rows = []
    for p in gemm.get("products", []):
        rows.append({"product": f"{p['kind']} {p['m']}x{p['n']}x{p['k']}",
                     "default_gflops": (p.get("CLBlast default") or {}).get("gflops_best"),
                     "tuned_gflops": (p.get("CLBlast tuned") or {}).get("gflops_best")})
    return {"tuned": gemm.get("tuned"), "tuning_file": gemm.get("tuning_file"), "products": rows}


def selftest_figures(path):
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError):
        return None
    cases = root.iter("testcase")
    counts = {"checks": 0, "failed": 0, "skipped": 0}
    failed = []
    for case in cases:
        counts["checks"] += 1
        if case.find("failure") is not None or case.find("error") is not None:
            counts["failed"] += 1
            failed.append(case.get("name"))
        elif case.find("skipped") is not None:
            counts["skipped"] += 1
    counts["failed_checks"] = failed[:20]
    return counts


def warm_seconds_per_step(run_dir):
    """The median step time after the first (cold) step, from a run's train_log.csv (log_every 1), or None."""
    try:
        with open(os.path.join(run_dir, "train_log.csv")) as f:
            header = f.readline().strip().split(",")
            walls = [float(line.split(",")[header.index("wall_seconds")]) for line in f if line.strip()]
    except (OSError, ValueError, IndexError):
        return None
    steps = sorted(b - a for a, b in zip(walls[1:], walls[2:]))
    return steps[len(steps) // 2] if steps else None


def zipnerf_figures(folder):
    """Each Zip-NeRF candidate's warm s/step and batch (the zipnerf step's runs), in the order they ran."""
    out = {}
    for run_dir in sorted(glob.glob(os.path.join(folder, "*")), key=os.path.getmtime):
        config = load_json(os.path.join(run_dir, "config.json")) or {}
        seconds = warm_seconds_per_step(run_dir)
        if seconds is not None:
            batch = (config.get("settings") or config).get("batch_size")
            out[os.path.basename(run_dir)] = {"s_per_step": seconds, "batch_size": batch}
    return out


def collect(work):
    figures = {}
    benches = {p: load_json(os.path.join(work, "bench", p, "bench.json")) for p in PRESETS}
    for preset, record in benches.items():
        if record and record.get("devices") and record["devices"][0].get("training"):
            figures[f"bench-{preset}"] = training_figures(record)
    if benches["quick"] and benches["quick"].get("devices"):
        figures["gemm"] = gemm_figures(benches["quick"])
    officials = {p: load_json(os.path.join(work, "official", f"{p}.json")) for p in PRECISIONS}
    for precision, record in officials.items():
        if record:
            keep = ["median_s", "min_s", "max_s", "rays_per_s", "batch_rays", "compile_s", "parameters", "settings",
                    "jax_default_matmul_precision", "error"]
            figures[f"official-{precision}"] = {k: record[k] for k in keep if k in record}
            figures[f"official-{precision}"]["jax"] = record.get("jax")
    selftest = selftest_figures(os.path.join(work, "artifacts", "selftest.xml"))
    if selftest:
        figures["selftest"] = selftest
    run = load_json(os.path.join(work, "train", "summary.json"))
    if run:
        val = run.get("val") or {}
        figures["train"] = {"steps": run.get("steps"), "train_seconds": run.get("train_seconds"),
                            "val_psnr": val.get("mean_psnr"), "val_ssim": val.get("mean_ssim"),
                            "val_views": val.get("views"), "render_s_per_mp": val.get("render_seconds_per_megapixel"),
                            "device": run.get("device")}
    zipnerf = zipnerf_figures(os.path.join(work, "zipnerf"))
    if zipnerf:
        figures["zipnerf"] = zipnerf
    frames = glob.glob(os.path.join(work, "train", "render_orbit", "*.png"))
    if frames:
        figures["render"] = {"frames": len(frames)}
    tuning = [os.path.basename(p) for p in glob.glob(os.path.join(work, "artifacts", "gemm-*.json"))]
    if tuning:
        figures["tune"] = {"tuning_files": tuning}
    return figures, {k: v for k, v in benches.items() if v}, {k: v for k, v in officials.items() if v}


def fmt(x, digits=3):
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.{digits}g}" if abs(x) < 1000 else f"{x:.0f}"
    return str(x)


def key_line(step, figures):
    """One line of a step's key figures for the steps table."""
    f = figures.get(step)
    if step == "selftest" and f:
        return f"{f['checks']} checks, {f['failed']} failed, {f['skipped']} skipped"
    if step.startswith("bench-") and f:
        return (f"{fmt(f['step_s_median'])} s/step, {fmt(f['rays_per_s'])} rays/s at {f['batch_rays']} rays "
                f"(first step {fmt(f['first_step_s'])} s; products: {f['gemm']})")
    if step.startswith("official-") and f:
        if "median_s" not in f:
            return f.get("error", "")
        return (f"{fmt(f['median_s'] * 1e3)} ms/step, {fmt(f['rays_per_s'])} rays/s at {f['batch_rays']} rays "
                f"(compile + 2 warm-up steps {fmt(f['compile_s'])} s)")
    if step == "train" and f:
        return (f"val PSNR {fmt(f['val_psnr'], 4)} dB over {f['val_views']} views after {f['steps']} steps in "
                f"{fmt(f['train_seconds'])} s; render {fmt(f['render_s_per_mp'])} s/MP")
    if step == "zipnerf" and f:
        return "; ".join(f"{name} {fmt(v['s_per_step'])} s/step" + (f" ({fmt(v['batch_size'] / v['s_per_step'])} rays/s)"
                                                                    if v.get("batch_size") else "")
                         for name, v in f.items())
    if step == "render" and f:
        return f"{f['frames']} orbit frames"
    if step == "tune" and f:
        return ", ".join(f["tuning_files"])
    return ""


def markdown(summary):
    facts, figures, steps = summary["facts"], summary["figures"], summary["steps"]
    lines = ["# Device check", "",
             f"{summary['date']}: `{facts.get('command', 'scripts/device-check.sh')}`, {summary['seconds']} s of a "
             f"{summary['budget_s']} s budget.", ""]
    for key in ["machine", "gpu", "opencl_driver", "python", "bundle"]:
        if key in facts:
            lines.append(f"- {key.replace('_', ' ')}: {facts[key]}")
    lines += ["", "| step | status | seconds | limit s | key figures / note |", "|---|---|---:|---:|---|"]
    for s in steps:
        note = key_line(s["step"], figures) or s["note"]
        if s["status"] != "ok" and s["note"] and note != s["note"]:
            note = f"{s['note']}; {note}"
        lines.append(f"| {s['step']} | {s['status']} | {s['seconds']} | {s['limit']} | {note} |")
    lines.append("")
    ours, base = figures.get("bench-paper"), figures.get("official-default")
    if ours or base:
        lines += ["## The paper's configuration: mipnerf-cl against the official code, same machine", "",
                  "| | rays per step | s/step (median) | rays/s | note |", "|---|---:|---:|---:|---|"]
        if ours:
            lines.append(f"| mipnerf-cl (`bench --presets paper`) | {ours['batch_rays']} | {fmt(ours['step_s_median'])} | "
                         f"{fmt(ours['rays_per_s'])} | {ours['warm_steps']} warm steps; products: {ours['gemm']}; "
                         f"{ours['device']} |")
        for precision in PRECISIONS:
            o = figures.get(f"official-{precision}")
            if o and "median_s" in o:
                jax = o.get("jax") or {}
                lines.append(f"| official, {precision} matmul precision | {o['batch_rays']} | {fmt(o['median_s'])} | "
                             f"{fmt(o['rays_per_s'])} | JAX {jax.get('version')} on {jax.get('device_kind')}; "
                             f"{o.get('settings', '')} |")
        if ours:
            for precision in PRECISIONS:
                o = figures.get(f"official-{precision}")
                if o and "rays_per_s" in o and o["batch_rays"] == ours["batch_rays"]:
                    lines.append(f"\nmipnerf-cl's rays/s over the official code's ({precision} precision): "
                                 f"**{ours['rays_per_s'] / o['rays_per_s']:.2f}×** (one run each, not alternated rounds)")
        lines.append("")
    for preset in PRESETS:
        f = figures.get(f"bench-{preset}")
        if f and f["costliest_stages"]:
            stages = ", ".join(f"{name} {seconds * 1e3:.2f} ms" for name, seconds in f["costliest_stages"])
            lines.append(f"- {preset}: costliest stages per step (profiled): {stages}"
                         + (f"; products at {fmt(f['gemm_gflops_in_step'])} GFLOP/s" if f["gemm_gflops_in_step"] else ""))
    gemm = figures.get("gemm")
    if gemm and gemm["products"]:
        lines += ["", "| GEMM product (bench --sections gemm) | CLBlast default GFLOP/s | CLBlast tuned GFLOP/s |",
                  "|---|---:|---:|"]
        lines += [f"| {p['product']} | {fmt(p['default_gflops'])} | {fmt(p['tuned_gflops'])} |" for p in gemm["products"]]
    selftest = figures.get("selftest")
    if selftest and selftest["failed_checks"]:
        lines += ["", "Self-test checks that failed: " + ", ".join(selftest["failed_checks"])]
    lines += ["", "Files: summary.md, summary.json, log.txt (every step's output), bench.json (the presets' bench.json "
              "records), official.json (the official step per precision), artifacts.tar.gz (bench.md files, the "
              "self-test's JUnit file, the tuning file, the training run without checkpoints, the orbit's frames)."]
    return "\n".join(lines) + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--work", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--budget", type=int, required=True)
    p.add_argument("--seconds", type=int, required=True)
    args = p.parse_args()
    steps = read_tsv(os.path.join(args.work, "steps.tsv"), ["step", "status", "exit", "seconds", "limit", "note"])
    facts = {row["key"]: row["value"] for row in read_tsv(os.path.join(args.work, "facts.tsv"), ["key", "value"])}
    figures, benches, officials = collect(args.work)
    summary = {"tool": "scripts/device-check.sh", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
               "seconds": args.seconds, "budget_s": args.budget, "facts": facts, "steps": steps, "figures": figures,
               "steps_seconds_total": round(sum(float(s["seconds"]) for s in steps if s["seconds"] not in ("", "-")), 1)}
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write(markdown(summary))
    with open(os.path.join(args.out, "bench.json"), "w") as f:
        json.dump({"presets": benches}, f, indent=1)
    with open(os.path.join(args.out, "official.json"), "w") as f:
        json.dump({"precisions": officials}, f, indent=1)


if __name__ == "__main__":
    main()
