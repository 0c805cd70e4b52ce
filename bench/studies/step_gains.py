#!/usr/bin/env python3
"""What the CPU GEMM library choice and the encoding's angle doubling buy for a whole training step and a render,
in one run: `mipnerf-cl bench --sections train` per preset under three settings, alternating over rounds:

  before     MIPNERF_HOST_GEMM_LIBRARY=openblas MIPNERF_IPE_SINCOS_EVERY=1  (every product on OpenBLAS, a sincos
             per degree: the host path as it was before both)
  doubling   MIPNERF_HOST_GEMM_LIBRARY=openblas                            (angle doubling only)
  tuned      the device's tuning file from `tune --host-gemm` (XDG_CACHE_HOME=--cache) and angle doubling

    python3 bench/studies/step_gains.py --cache DIR [--presets quick,paper] [--rounds 2] [--report-only]

--cache is an XDG_CACHE_HOME whose mipnerf-cl/ tuning file for the device has a host_libraries choice (run
`XDG_CACHE_HOME=DIR build/mipnerf-cl tune --host-gemm` first). Writes bench/results/step_gains/step_gains.{json,md}: per
preset and setting, the median over rounds of the warm s/step median and rays/s, and render s/MP.
"""

import argparse
import datetime
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib import cli_runs  # noqa: E402

from lib.provenance import REPO as ROOT  # noqa: E402  (the repository root)
RESULTS = report_md.results_folder("step_gains")
SETTINGS = {
    "before": {"MIPNERF_HOST_GEMM_LIBRARY": "openblas", "MIPNERF_IPE_SINCOS_EVERY": "1"},
    "doubling": {"MIPNERF_HOST_GEMM_LIBRARY": "openblas"},
    "tuned": {},
}


def run_bench(exe, preset, env_extra, cache, work):
    env = dict(os.environ, XDG_CACHE_HOME=cache)
    for name in ("MIPNERF_HOST_GEMM_LIBRARY", "MIPNERF_IPE_SINCOS_EVERY"):
        env.pop(name, None)
    env.update(env_extra)
    out = tempfile.mkdtemp(dir=work)
    subprocess.run([exe, "bench", "--sections", "train", "--presets", preset, "--profile-steps", "0", "--out", out],
                   check=True, env=env, capture_output=True)
    record = cli_runs.read_json(os.path.join(out, "bench.json"))
    device = record["devices"][0]
    return {"device": device["device"].get("name"), "train": device["training"][0], "render": device["render"][0],
            "load_1min": os.getloadavg()[0]}


def measure(args):
    exe = os.path.join(ROOT, args.build, "mipnerf-cl")
    work = tempfile.mkdtemp(prefix="step_gains-")
    runs = []
    for round_index in range(args.rounds):
        order = list(SETTINGS) if round_index % 2 == 0 else list(reversed(SETTINGS))
        for preset in args.presets.split(","):
            for name in order:
                result = run_bench(exe, preset, SETTINGS[name], args.cache, work)
                result.update({"round": round_index, "preset": preset, "setting": name})
                runs.append(result)
                print(f"round {round_index} {preset} {name}: load {result['load_1min']:.2f}", file=sys.stderr)
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "commit": cli_runs.commit_of(ROOT), "rounds": args.rounds,
            "command": "python3 bench/studies/step_gains.py " + " ".join(sys.argv[1:]), "runs": runs}


def write_markdown(record):
    loads = [r["load_1min"] for r in record["runs"]]
    device = record["runs"][0]["device"] if record["runs"] else "?"
    lines = [report_md.generated_banner("bench/studies/step_gains.py", "step_gains.json"), "",
             "# What the CPU GEMM library choice and the angle doubling buy per step", "",
             f"Date: {record['date']} (UTC), commit {record['commit']}, device {device}. Command: "
             f"`{record['command']}`; {record['rounds']} rounds, settings alternating. Load average (1 min) after "
             f"each run: {min(loads):.2f}-{max(loads):.2f}.", ""]
    rows_out = []
    presets = []
    for r in record["runs"]:
        if r["preset"] not in presets:
            presets.append(r["preset"])
    for preset in presets:
        base = None
        for name in SETTINGS:
            rows = [r for r in record["runs"] if r["preset"] == preset and r["setting"] == name]
            if not rows:
                continue
            steps = statistics.median(r["train"]["step_seconds_median"] for r in rows)
            rays = statistics.median(r["train"]["rays_per_second"] for r in rows)
            render = statistics.median(r["render"]["seconds_per_megapixel"] for r in rows)
            base = base or steps
            rows_out.append([preset, name, f"{steps:.3f}", f"{rays:.0f}", f"{render:.1f}", f"{base / steps:.2f}x"])
    lines += report_md.table(["preset", "setting", "warm s/step (median over rounds)", "rays/s", "render s/MP",
                              "vs before"], "llrrrr", rows_out)
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cache", help="XDG_CACHE_HOME with the device's tune --host-gemm choice")
    parser.add_argument("--presets", default="quick,paper")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--build", default="build")
    parser.add_argument("--report-only", action="store_true")
    args = parser.parse_args()
    if not args.report_only and not args.cache:
        parser.error("--cache is needed to measure (the tuned setting reads its tuning file)")
    report_md.measure_or_reload(RESULTS, "step_gains", "bench/studies/step_gains.py", args.report_only, lambda: measure(args),
                                write_markdown)

if __name__ == "__main__":
    main()
