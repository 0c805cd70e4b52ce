#!/usr/bin/env python3
"""The host MLP's products through every CPU GEMM library built in, beside the machine's limits: runs
build/bench/bench_gemm_libs and writes bench/results/gemm_libs/gemm_libs.json and .md (the .md from the .json; hand notes
kept).

    python3 bench/studies/gemm_libs.py [--presets quick,paper] [--rounds 5] [--build build] [--report-only]

Per product (kind, m x n x k at the 256-row blocks; how often a forward + backward runs it) and library: GFLOP/s
in our thread arrangement (each thread its own block, the library held to one thread: what the host MLP does and
tune --host-gemm measures) and in the library's own (its threads on one product of both blocks' rows), median of
the rounds with the best in brackets; then per preset the time of one forward + backward's products with OpenBLAS
alone against the fastest library per product.
"""

import datetime
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib import cli_runs  # noqa: E402

from lib.provenance import REPO as ROOT  # noqa: E402  (the repository root)
RESULTS = report_md.results_folder("gemm_libs")


def measure(args):
    exe = os.path.join(ROOT, args.build, "bench", "bench_gemm_libs")
    out = os.path.join(RESULTS, "gemm_libs.json.tmp")
    load_start = os.getloadavg()
    subprocess.run([exe, "--presets", args.presets, "--rounds", str(args.rounds), "--out", out], check=True)
    with open(out) as f:
        record = json.load(f)
    os.remove(out)
    record["date"] = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    record["commit"] = cli_runs.commit_of(ROOT)
    record["command"] = "python3 bench/studies/gemm_libs.py " + " ".join(sys.argv[1:])
    record["load_average"] = {"start": load_start, "end": os.getloadavg()}
    return record


def rate(cell, arrangement):
    if "skipped" in cell:
        return None
    return cell[arrangement]


def products_time(products, pick):
    """Seconds of one forward + backward's products (each at its count) with the library `pick` chooses."""
    total = 0.0
    for p in products:
        gflops = pick(p)
        if gflops:
            total += p["count"] * p["gflop"] / gflops
    return total


def write_markdown(record):
    m = record["machine"]
    libs = [lib["name"] for lib in record["libraries"]]
    lines = [report_md.generated_banner("bench/studies/gemm_libs.py", "gemm_libs.json"), "",
             "# The host MLP's products on each CPU GEMM library", "",
             f"Date: {record['date']} (UTC), commit {record['commit']}. Command: `{record['command']}`. Load average "
             f"(1 min) {record['load_average']['start'][0]:.2f} at the start, {record['load_average']['end'][0]:.2f} "
             "at the end.", "",
             "Libraries: " + "; ".join(f"{lib['name']} {lib['version']} ({lib['threads']})"
                                       for lib in record["libraries"]) + ".", "",
             f"Machine limits (same run, {m['threads']} threads): FMA peak "
             f"{m['fma_peak_gflops']['all_threads']['best']:.1f} GFLOP/s "
             f"({m['fma_peak_gflops']['one_thread']['best']:.1f} on one thread), triad "
             f"{m['triad_gbs']['all_threads']['best']:.1f} GB/s, one large sgemm "
             f"{m['large_sgemm_gflops']['best']:.1f} GFLOP/s ({m['large_sgemm_gflops']['library']}, "
             f"{m['large_sgemm_gflops']['shape']}).", ""]
    for preset in record["presets"]:
        lines += [f"## {preset['preset']} ({preset['block_rows']}-row blocks)", "",
                  "GFLOP/s, median of the rounds (best). *ours*: 2 threads, each its own block; *library*: the "
                  "library's 2 threads on one product of both blocks. – : the library cannot run the shape.", ""]
        rows = []
        for p in preset["products"]:
            cells = []
            for lib in libs:
                cell = p["libraries"].get(lib, {"skipped": "not run"})
                for arrangement in ("ours", "library"):
                    r = rate(cell, arrangement)
                    cells.append("–" if r is None else f"{r['median']:.1f} ({r['best']:.1f})")
            rows.append([p["label"], str(p["count"])] + cells)
        header = ["product", "count"] + [f"{lib} {arrangement}" for lib in libs for arrangement in ("ours", "library")]
        lines += report_md.table(header, "l" + "r" * (len(header) - 1), rows)

        def best_of(p):
            rates = [rate(p["libraries"][lib], "ours") for lib in libs if lib in p["libraries"]]
            return max((r["median"] for r in rates if r), default=None)

        def openblas(p):
            r = rate(p["libraries"].get("openblas", {"skipped": ""}), "ours")
            return r["median"] if r else None

        t_openblas = products_time(preset["products"], openblas)
        t_best = products_time(preset["products"], best_of)
        flops = sum(p["count"] * p["gflop"] for p in preset["products"])
        lines += ["", f"One forward + backward's products (each at its count, {flops:.2f} GFLOP per block pair): "
                  f"OpenBLAS alone {1e3 * t_openblas:.2f} ms ({flops / t_openblas:.1f} GFLOP/s), the fastest library "
                  f"per product {1e3 * t_best:.2f} ms ({flops / t_best:.1f} GFLOP/s): "
                  f"{t_openblas / t_best:.2f}x; {100 * flops / t_best / m['large_sgemm_gflops']['best']:.0f} % of the "
                  "large-sgemm rate.", ""]
    return "\n".join(lines) + "\n"


def add_arguments(parser):
    parser.add_argument("--presets", default="quick,paper")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--build", default="build")


def main():
    report_md.study_main(__doc__, RESULTS, "gemm_libs", "bench/studies/gemm_libs.py", add_arguments, measure, write_markdown)

if __name__ == "__main__":
    main()
