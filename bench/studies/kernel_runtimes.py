#!/usr/bin/env python3
"""The ray-math kernels on PoCL's CPU device beside Intel's CPU OpenCL runtime on the same machine, in one run.

Runs build/bench/bench_kernels (the paper's batch: 4,096 rays x 128 samples) on both runtimes, alternating, for
`--rounds` rounds, and also the fused Gaussian + IPE kernel with a sincos per degree (MIPNERF_IPE_SINCOS_EVERY=1:
what it was before angle doubling) beside the device default. Per kernel: the median over the rounds of each
round's best call, PoCL / Intel, and whether PoCL is within 1.5x (issue 28's target). Intel's runtime comes from
scripts/install-intel-opencl.sh (PyPI), as in the test command. Each round also runs PoCL twice as a diagnostic of its
worker threads, reported in a table of their own and never in the verdict: on one worker (POCL_MAX_PTHREAD_COUNT=1),
and with its workers unpinned (POCL_AFFINITY=0, where mipnerf-cl's default pins them: host/cl/device.cpp).

    python3 bench/studies/kernel_runtimes.py [--rounds 3] [--reps 10] [--build build] [--name kernel_runtimes] [--report-only]

Writes bench/results/kernel_runtimes/<name>.json and .md (the .md from the .json; hand notes kept): kernel_runtimes for the machine
the committed figures were first taken on (PoCL's `pthread-haswell-AMD EPYC`), another name for another machine
(e.g. kernel_runtimes_xeon). Each run records both runtimes' device names.
"""

import argparse
import datetime
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib import cli_runs  # noqa: E402

from lib.provenance import REPO as ROOT  # noqa: E402  (the repository root)
RESULTS = report_md.results_folder("kernel_runtimes")
POCL = "Portable Computing Language"
TARGET_RATIO = 1.5


def intel_environment():
    """The environment lines install-intel-opencl.sh prints (OCL_ICD_VENDORS, INTEL_OPENCL_PLATFORM)."""
    out = subprocess.run([os.path.join(ROOT, "scripts", "install-intel-opencl.sh")], capture_output=True, text=True,
                         check=True).stdout
    env = {}
    for line in out.splitlines():
        if line.startswith("export "):
            name, value = line[len("export "):].split("=", 1)
            env[name] = value.replace("\\", "")
    return env


def parse_kernel_table(text):
    """stage -> (best ms, median ms) from bench_kernels' markdown table."""
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 4 or "(" not in cells[2]:
            continue
        try:
            best, median = cells[2].replace(")", "").split("(")
            rows[cells[0]] = (float(best), float(median))
        except ValueError:
            continue
    return rows


def device_of(text):
    """The device name bench_kernels' heading gives ("## Ray-math kernels: NAME"), or ""."""
    for line in text.splitlines():
        if line.startswith("## Ray-math kernels: "):
            return line[len("## Ray-math kernels: "):].strip()
    return ""


def run_bench(exe, platform, env, reps, sincos_every=None, extra_args=()):
    environment = dict(os.environ, **env)
    environment.pop("MIPNERF_IPE_SINCOS_EVERY", None)
    if sincos_every is not None:
        environment["MIPNERF_IPE_SINCOS_EVERY"] = str(sincos_every)
    out = subprocess.run([exe, "--device", f"platform={platform}", "--reps", str(reps), *extra_args],
                         capture_output=True, text=True, env=environment, check=True).stdout
    return parse_kernel_table(out), device_of(out)


def measure(args):
    exe = os.path.join(ROOT, args.build, "bench", "bench_kernels")
    intel_env = intel_environment()
    intel = intel_env.get("INTEL_OPENCL_PLATFORM", "Intel(R) OpenCL")
    runs = []
    for round_index in range(args.rounds):
        for name, platform, env in (("pocl", POCL, {}), ("intel", intel, intel_env)):
            for sincos_every in (None, 1):
                load = os.getloadavg()[0]
                rows, device = run_bench(exe, platform, env, args.reps, sincos_every)
                runs.append({"round": round_index, "runtime": name, "platform": platform, "device": device,
                             "sincos_every": sincos_every or "default", "load_1min": load, "stages": rows})
                print(f"round {round_index} {name} sincos_every={sincos_every or 'default'}: "
                      f"{len(rows)} stages, load {load:.2f}", file=sys.stderr)
        # The diagnostics of PoCL's short launches: its work on one worker thread, and with no CPU left idle.
        for variant, env, extra in DIAGNOSTICS:
            load = os.getloadavg()[0]
            rows, device = run_bench(exe, POCL, env, args.reps, None, extra)
            runs.append({"round": round_index, "runtime": "pocl", "variant": variant, "platform": POCL,
                         "device": device, "sincos_every": "default", "load_1min": load, "stages": rows})
            print(f"round {round_index} pocl {variant}: {len(rows)} stages, load {load:.2f}", file=sys.stderr)
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "commit": cli_runs.commit_of(ROOT), "rounds": args.rounds, "reps": args.reps,
            "command": "python3 bench/studies/kernel_runtimes.py " + " ".join(sys.argv[1:]), "name": args.name, "runs": runs}


# PoCL diagnostics per round (variant, environment, bench_kernels arguments): one worker thread
# (POCL_MAX_PTHREAD_COUNT=1), and its workers left where Linux places them (POCL_AFFINITY=0; mipnerf-cl pins them,
# host/cl/device.cpp).
DIAGNOSTICS = (("one worker", {"POCL_MAX_PTHREAD_COUNT": "1"}, ()),
               ("workers unpinned", {"POCL_AFFINITY": "0"}, ()))


def summary(record):
    """stage -> {runtime/variant: median over rounds of the best ms}."""
    table = {}
    for run in record["runs"]:
        key = run["runtime"] + ("" if run["sincos_every"] == "default" else f" K={run['sincos_every']}")
        if run.get("variant"):
            key += " " + run["variant"]
        for stage, (best, _median) in run["stages"].items():
            table.setdefault(stage, {}).setdefault(key, []).append(best)
    return {stage: {key: statistics.median(values) for key, values in by.items()} for stage, by in table.items()}


def devices_text(record):
    """"PoCL: NAME; Intel: NAME" from the runs (older records, without names: the machine they were taken on)."""
    names = {}
    for run in record["runs"]:
        if run.get("device"):
            names.setdefault(run["runtime"], run["device"])
    if not names:
        return "not recorded (runs before 2026-11-26 21:40 UTC: PoCL's `pthread-haswell-AMD EPYC`, 2 cores)"
    return "; ".join(f"{'PoCL' if runtime == 'pocl' else 'Intel'} `{name}`" for runtime, name in names.items())


def write_markdown(record):
    s = summary(record)
    loads = [run["load_1min"] for run in record["runs"]]
    lines = [report_md.generated_banner("bench/studies/kernel_runtimes.py", record.get("name", "kernel_runtimes") + ".json"), "",
             "# Ray-math kernels: PoCL beside Intel's CPU runtime", "",
             f"Date: {record['date']} (UTC), commit {record['commit']}. Command: `{record['command']}`; "
             f"{record['rounds']} alternating rounds, each kernel's best of {record['reps']} calls per round, the "
             f"median over rounds shown. Load average (1 min) at each run: {min(loads):.2f}-{max(loads):.2f}.", "",
             "Devices: " + devices_text(record) + ".", "",
             "Batch: 4,096 rays x 128 samples (bench_kernels' defaults). Target (issue 28): PoCL within "
             f"{TARGET_RATIO}x of Intel's runtime.", ""]
    rows = []
    for stage, by in s.items():
        if "pocl" not in by or "intel" not in by:
            continue
        ratio = by["pocl"] / by["intel"]
        rows.append([stage, f"{by['pocl']:.3f}", f"{by['intel']:.3f}", f"{ratio:.2f}",
                     "yes" if ratio <= TARGET_RATIO else "no"])
    lines += report_md.table(["kernel", "PoCL ms", "Intel ms", "PoCL / Intel", "within 1.5x"], "lrrrc", rows)
    fused = [(stage, by) for stage, by in s.items() if "pocl K=1" in by and stage.startswith("gaussian_ipe_fwd")]
    if fused:
        lines += ["", "The fused Gaussian + IPE kernel with a sincos per degree (K = 1, before angle doubling) and "
                  "with each runtime's default (a sincos every 4 degrees on CPUs):", ""]
        lines += report_md.table(
            ["kernel", "PoCL K=1 ms", "PoCL default ms", "Intel K=1 ms", "Intel default ms"], "lrrrr",
            [[stage, f"{by['pocl K=1']:.3f}", f"{by['pocl']:.3f}", f"{by.get('intel K=1', float('nan')):.3f}",
              f"{by['intel']:.3f}"] for stage, by in fused])
    diagnosed = [(stage, by) for stage, by in s.items() if "pocl one worker" in by and "pocl workers unpinned" in by]
    if diagnosed:
        lines += ["", "PoCL's workers (diagnostics, same rounds): on one worker thread (`POCL_MAX_PTHREAD_COUNT=1`), "
                  "and left where Linux places them (`POCL_AFFINITY=0`; mipnerf-cl pins them by default, "
                  "host/cl/device.cpp):", ""]
        rows = []
        for stage, by in diagnosed:
            if "intel" not in by:
                continue
            unpinned = by["pocl workers unpinned"]
            rows.append([stage, f"{by['pocl']:.3f}", f"{by['pocl one worker']:.3f}", f"{unpinned:.3f}",
                         f"{by['intel']:.3f}", f"{unpinned / by['intel']:.2f}"])
        lines += report_md.table(["kernel", "PoCL ms (pinned)", "PoCL one worker ms", "PoCL unpinned ms", "Intel ms",
                                  "unpinned / Intel"], "lrrrrr", rows)
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--reps", type=int, default=10)
    parser.add_argument("--build", default="build")
    parser.add_argument("--name", default="kernel_runtimes",
                        help="results stem: bench/results/kernel_runtimes/NAME.json and .md (another machine, another name)")
    parser.add_argument("--report-only", action="store_true", help="rewrite the .md from the .json")
    args = parser.parse_args()
    script = "bench/studies/kernel_runtimes.py" + ("" if args.name == "kernel_runtimes" else f" --name {args.name}")
    report_md.measure_or_reload(RESULTS, args.name, script, args.report_only, lambda: measure(args),
                                write_markdown)

if __name__ == "__main__":
    main()
