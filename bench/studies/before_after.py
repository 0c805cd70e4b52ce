#!/usr/bin/env python3
"""Before/after: the `mipnerf-cl bench` figures of two builds, measured side by side in alternating rounds.

THE MEASUREMENT (issue "Renovation, step two"; each tree a git worktree with only its executable built):

  python3 bench/studies/before_after.py --before /work/before/build/mipnerf-cl --after /work/after/build/mipnerf-cl \\
      --before-label edbea28 --after-label a8dc898 --rounds 5

Each round runs `BIN bench --quick --presets tiny,quick --sections gemm,kernels,train --out DIR` once per side, the
order alternating (before, after | after, before | before, after ...) so that slow drifts of the machine's other load
fall on both sides alike. Each side has its own POCL_CACHE_DIR, emptied at the start: round 1 is the cold round
(kernel builds), reported but left out of the medians. For every figure bench.json holds -- training s/step (median
warm step) and render s/MP per preset, GEMM GFLOP/s (best call) per product and parameter set, kernel items/s (best
call) per kernel -- the report gives per side the median over rounds 2.. with its min-max, and the after/before ratio
of the medians; and per run the load average and the CPU other processes took (from /proc/stat).

Writes bench/results/before_after/NAME.json (every round's every figure) and NAME.md generated from it (write_markdown);
`--report-only JSON` regenerates the .md, keeping its "## Notes (by hand)" section. --sections/--presets narrow a
re-run (e.g. one section whose figure looked odd), --bench-args adds bench flags (more repetitions); write such runs
elsewhere with --name or --out-dir.
"""

import argparse
import datetime
import json
import os
import resource
import shlex
import shutil
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import commit_of  # noqa: E402
from lib.provenance import file_sha256  # noqa: E402

from lib.provenance import REPO  # noqa: E402
SIDES = ("before", "after")
TICK = os.sysconf("SC_CLK_TCK")


def figures_of(bench):
    """{figure name: value} from one bench.json, and {figure name: unit}; names carry the device when several."""
    values, units = {}, {}
    devices = bench["devices"]
    for d in devices:
        prefix = f"[{d['device'].get('name')}] " if len(devices) > 1 else ""

        def put(name, unit, value):
            values[prefix + name], units[prefix + name] = value, unit

        for t in d.get("training", []):
            put(f"train {t['preset']}", "s/step", t["step_seconds_median"])
        for r in d.get("render", []):
            put(f"render {r['preset']}", "s/MP", r["seconds_per_megapixel"])
        for p in (d.get("gemm") or {}).get("products", []):
            for series, v in p.items():
                if isinstance(v, dict) and "gflops_best" in v:
                    put(f"GEMM {p['kind']} {p['m']}x{p['n']}x{p['k']} ({series})", "GFLOP/s", v["gflops_best"])
        for s in (d.get("kernels") or {}).get("stages", []):
            put(f"kernel {s['stage']}", "items/s", s["items_per_second"])
    return values, units


def cpu_busy_seconds():
    """The whole machine's busy CPU seconds since boot (/proc/stat)."""
    with open("/proc/stat") as f:
        user, nice, system, _idle, _iowait, irq, softirq = [int(x) for x in f.readline().split()[1:8]]
    return (user + nice + system + irq + softirq) / TICK


def children_cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def bench_once(side, binary, args, out, cache):
    """One `mipnerf-cl bench` run; its figures, the settings it records and what else ran meanwhile."""
    shutil.rmtree(out, ignore_errors=True)
    command = [binary, "bench", "--quick", "--presets", args.presets, "--sections", args.sections, "--out", out] + \
        shlex.split(args.bench_args)
    env = dict(os.environ, POCL_CACHE_DIR=cache)
    load_start = [round(x, 2) for x in os.getloadavg()]
    busy0, own0, t0 = cpu_busy_seconds(), children_cpu_seconds(), time.monotonic()
    with open(out + ".log", "w") as log:
        result = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT, env=env)
    wall = time.monotonic() - t0
    other = max(0.0, (cpu_busy_seconds() - busy0) - (children_cpu_seconds() - own0)) / wall
    if result.returncode != 0:
        sys.exit(f"before_after.py: {' '.join(command)} failed ({result.returncode}); see {out}.log")
    with open(os.path.join(out, "bench.json")) as f:
        bench = json.load(f)
    values, units = figures_of(bench)
    d = bench["devices"][0]
    return {"side": side, "command": " ".join(command[1:]).replace(out, "DIR"), "wall_s": round(wall, 1),
            "load_start": load_start, "load_end": [round(x, 2) for x in os.getloadavg()],
            "other_cpu_cores": round(other, 2), "version": bench.get("version"), "device": d["device"],
            "clblast": d.get("clblast_version"), "gemm_tuned": d["gemm"].get("tuned") if d.get("gemm") else None,
            "gemm_in_training": {t["preset"]: t.get("gemm_parameters") for t in d.get("training", [])},
            "errors": [e for dev in bench["devices"] for e in dev.get("errors", [])],
            "figures": values, "units": units}


def measure(args):
    os.makedirs(args.work, exist_ok=True)
    caches = {side: os.path.join(args.work, f"pocl-cache-{side}") for side in SIDES}
    for cache in caches.values():  # round 1 is cold on both sides
        shutil.rmtree(cache, ignore_errors=True)
        os.makedirs(cache)
    binaries = {"before": os.path.abspath(args.before), "after": os.path.abspath(args.after)}
    record = {"format": 1, "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
              "script_commit": commit_of(REPO), "command": " ".join([os.path.relpath(__file__, REPO)] +
                                                                                 sys.argv[1:]),
              "sides": {s: {"label": getattr(args, f"{s}_label"), "binary": binaries[s],
                            "binary_sha256": file_sha256(binaries[s])} for s in SIDES},
              "bench_args": f"bench --quick --presets {args.presets} --sections {args.sections} --out DIR "
                            f"{args.bench_args}".rstrip(),
              "rounds": [], "notes": args.note}
    for n in range(1, args.rounds + 1):
        order = SIDES if n % 2 == 1 else SIDES[::-1]
        runs = []
        for side in order:
            runs.append(bench_once(side, binaries[side], args, os.path.join(args.work, f"r{n}-{side}"), caches[side]))
            print(f"before_after: round {n} {side}: {runs[-1]['wall_s']} s, load {runs[-1]['load_start'][0]}, "
                  f"other processes {runs[-1]['other_cpu_cores']} cores", flush=True)
        record["rounds"].append({"round": n, "order": list(order), "runs": runs})
    return record


# ---- the report ----

def summary(record):
    """Rows (name, unit, {side: (median, min, max, n)}, ratio) over rounds 2.. (all rounds when there is only one)."""
    rounds = record["rounds"][1:] or record["rounds"]
    names, units = [], {}
    for rnd in record["rounds"]:
        for run in rnd["runs"]:
            for name in run["figures"]:
                if name not in units:
                    names.append(name)
                units[name] = run["units"][name]
    rows = []
    for name in names:
        stats = {}
        for side in SIDES:
            vals = [run["figures"][name] for rnd in rounds for run in rnd["runs"]
                    if run["side"] == side and name in run["figures"]]
            stats[side] = (statistics.median(vals), min(vals), max(vals), len(vals)) if vals else None
        ratio = stats["after"][0] / stats["before"][0] if stats["before"] and stats["after"] and stats["before"][0] \
            else None
        rows.append((name, units[name], stats, ratio))
    return rows


def fmt(v):
    return f"{v:.3g}" if abs(v) < 1e4 else f"{v:.3g}".replace("e+0", "e").replace("e+", "e")


def separated(stats):
    """True when the two sides' min-max ranges do not overlap."""
    b, a = stats["before"], stats["after"]
    return bool(b and a) and (a[1] > b[2] or a[2] < b[1])


def write_markdown(record):
    sides = record["sides"]
    lb, la = sides["before"]["label"], sides["after"]["label"]
    first = record["rounds"][0]["runs"][0]
    n = len(record["rounds"])
    used = "rounds 2–%d" % n if n > 1 else "round 1 (the only one)"
    lines = [f"# `mipnerf-cl bench` before ({lb}) and after ({la})", "",
             report_md.generated_banner("bench/studies/before_after.py", "its .json"), "",
             f"Date {record['date']}; run from the checkout at {record['script_commit']}. Device: {first['device'].get('name')} "
             f"({first['device'].get('platform')}), CLBlast {first['clblast']}, "
             f"GEMM tuning file: {'yes' if first['gemm_tuned'] else 'none (CLBlast defaults)'}. Both executables are "
             "Release builds of their own worktree:", ""]
    for s in SIDES:
        lines.append(f"- {s}: {sides[s]['label']}, `{sides[s]['binary']}`, sha256 {sides[s]['binary_sha256'][:16]}…")
    training = {s: sorted({f"{p}: {g}" for r in record["rounds"] for run in r["runs"] if run["side"] == s
                           for p, g in run["gemm_in_training"].items()}) for s in SIDES}
    lines += ["", f"Each round ran `mipnerf-cl {record['bench_args']}` once per side, alternating the order "
              "(round 1 before then after, round 2 after then before, ...), each side with its own POCL_CACHE_DIR "
              f"emptied at the start. Round 1 is cold (kernel builds) and left out: the table gives per side the "
              f"median over {used} with [min–max], and after/before = ratio of the medians (above 1: after is "
              "larger; for s/step and s/MP that is slower, for GFLOP/s and items/s faster). GEMM: the best call of a "
              "product; kernels: the best call; training: the median warm step. \"ranges apart\" marks a figure whose "
              "two min–max ranges do not overlap.",
              ""]
    if any(training.values()):
        lines += ["Training GEMMs ran on: " + "; ".join(f"{s}: {', '.join(training[s])}" for s in SIDES) + ".", ""]
    for note in record.get("notes", []):
        lines += [note, ""]
    one_sided, rows = [], []
    for name, unit, stats, ratio in summary(record):
        if ratio is None:
            one_sided.append(name)
            continue
        cell = {s: f"{fmt(stats[s][0])} [{fmt(stats[s][1])}–{fmt(stats[s][2])}]" for s in SIDES}
        rows.append([name, unit, cell["before"], cell["after"], f"{ratio:.2f}",
                     "ranges apart" if separated(stats) else ""])
    lines += report_md.table(["figure", "unit", f"before ({lb}) median [min–max]", f"after ({la}) median [min–max]",
                              "after/before", ""], "llrrrl", rows, blank="  ")
    if one_sided:
        lines += ["", "Figures measured on one side only: " + ", ".join(one_sided) + "."]
    lines += ["", "## Load per run", "",
              "Load average (1 min) at the run's start and end; other processes: the machine's busy CPU time during "
              "the run (/proc/stat) minus the bench's own, in cores (of 2).", ""]
    lines += report_md.table(
        ["round", "run", "side", "wall s", "load 1-min start → end", "other processes, cores"], "rrlrlr",
        [[f"{rnd['round']}{' (cold)' if rnd['round'] == 1 and n > 1 else ''}", str(i + 1), run["side"],
          f"{run['wall_s']:.0f}", f"{run['load_start'][0]:.2f} → {run['load_end'][0]:.2f}",
          f"{run['other_cpu_cores']:.2f}"] for rnd in record["rounds"] for i, run in enumerate(rnd["runs"])])
    errors = [(r["round"], run["side"], e) for r in record["rounds"] for run in r["runs"] for e in run["errors"]]
    if errors:
        lines += ["", "Sections that failed: " + "; ".join(f"round {r} {s}: {e['section']}: {e['message']}"
                                                            for r, s, e in errors)]
    lines += ["", f"Command: `python3 {record['command']}`. Every round's every figure: the .json."]
    return "\n".join(lines) + "\n"


def write_report(record, json_path):
    md = os.path.splitext(json_path)[0] + ".md"
    report_md.write_report(md, write_markdown(record),
                           f"python3 bench/studies/before_after.py --report-only {os.path.relpath(json_path, REPO)}")
    return md


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="The measurement" + __doc__.split("THE MEASUREMENT", 1)[1].split("Each round")[0])
    p.add_argument("--before", help="the before build's mipnerf-cl")
    p.add_argument("--after", help="the after build's mipnerf-cl")
    p.add_argument("--before-label", default="before", help="commit or name of the before build")
    p.add_argument("--after-label", default="after", help="commit or name of the after build")
    p.add_argument("--rounds", type=int, default=5, help="alternating rounds (default 5; round 1 is cold, left out)")
    p.add_argument("--presets", default="tiny,quick")
    p.add_argument("--sections", default="gemm,kernels,train")
    p.add_argument("--bench-args", default="", help="more bench flags, for a diagnostic re-run (e.g. \"--kernel-reps 30\")")
    p.add_argument("--work", default="/tmp/mipnerf-before-after", help="bench outputs, logs and PoCL caches")
    p.add_argument("--out-dir", default=report_md.results_folder("before_after"))
    p.add_argument("--name", default="renovation2_before_after", help="results file name (without extension)")
    p.add_argument("--note", action="append", default=[], help="a paragraph recorded in the .json (repeatable)")
    p.add_argument("--report-only", metavar="JSON", help="regenerate the .md beside JSON from it; measure nothing")
    args = p.parse_args()
    if args.report_only:
        with open(args.report_only) as f:
            print(f"before_after: wrote {write_report(json.load(f), args.report_only)}")
        return
    for side in SIDES:
        binary = getattr(args, side)
        if not binary or not os.access(binary, os.X_OK):
            p.error(f"--{side}: pass a built mipnerf-cl executable (got {binary!r})")
    if args.rounds < 1:
        p.error("--rounds must be at least 1")
    record = measure(args)
    os.makedirs(args.out_dir, exist_ok=True)
    json_path = os.path.join(args.out_dir, args.name + ".json")
    with open(json_path, "w") as f:
        json.dump(record, f, indent=1)
        f.write("\n")
    print(f"before_after: wrote {json_path} and {write_report(record, json_path)}")


if __name__ == "__main__":
    main()
