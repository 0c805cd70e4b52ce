#!/usr/bin/env python3
"""A real forward-facing capture behind a lens: Zip-NeRF on the transforms.json `from-photos --camera-model
SIMPLE_RADIAL` writes, in NDC through its lens now against world rays before, at equal training time.

COLMAP's radial camera fits the flower photos better than its pinhole (bench/results/from_photos: rotation error
0.40 against 0.76 degrees), but LLFF's poses_bounds.npy holds a pinhole, so such an import is a transforms.json, and
`train` took it for world rays between the file's near and far with cones (the background of a forward-facing capture
lies far beyond the near bound, as NDC was made for). Now a forward-facing transforms.json with depths and one
projection trains as an LLFF capture does: NDC rays and cylinders, its radii from the lens tables.

The capture: ../shared/data/llff/flower/images_8 (34 photos at 504x378) through `dataset from-photos --camera-model
SIMPLE_RADIAL` (made once in --work, or --capture), held-out views every 8th (the same 5 photos as the LLFF split).
The runs, each `train --model zipnerf --preset fast --minutes M`, 3 seeds, scored by its own executable's `eval`:
  - before: the previous build (--before-exe), no flag: world rays, cones;
  - now: this build, no flag: NDC through the lens;
  - given: this build on the capture's own poses (poses_bounds.npy: LLFF, pinhole, NDC) at factor 8, the reference.
Finished runs and scores in --work are reused.

  python3 bench/studies/lens_ndc.py --before-exe /tmp/mipnerf-cl-before --minutes 3 --seeds 0,1,2
  python3 bench/studies/lens_ndc.py --report-only
"""

import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import (SEED_TABLE_HEADER, commit_of, device_line, evaluate_val, gain_lines, run,  # noqa: E402
                          run_record, seed_table_cells, train_for_minutes, wall_time_lines)

RESULTS = report_md.results_folder("lens_ndc")
SCRIPT = "bench/studies/lens_ndc.py"
MODEL = "--model zipnerf --preset fast"
# (key, label, which executable, which capture, factor)
ROWS = [
    ("before", "before: the lens capture on world rays and cones (as train took it)", "before", "lens", 1),
    ("now", "now: the lens capture in NDC through its lens (no flag)", "now", "lens", 1),
    ("given", "the capture's own poses (poses_bounds.npy: pinhole, NDC), for reference", "now", "given", 8),
]


def add_arguments(parser):
    parser.add_argument("--build", default="build", help="build folder holding this mipnerf-cl")
    parser.add_argument("--before-exe", help="the previous build's mipnerf-cl (the 'before' rows)")
    parser.add_argument("--data", default="../shared/data/llff/flower", help="the LLFF capture (images_8/)")
    parser.add_argument("--capture", help="an existing from-photos SIMPLE_RADIAL import of it (else made in --work)")
    parser.add_argument("--work", default="/tmp/mipnerf-lens-ndc", help="the import, runs and logs")
    parser.add_argument("--minutes", type=float, default=3.0, help="training budget of every run")
    parser.add_argument("--seeds", default="0,1,2", help="comma-separated seeds, each row trained once per seed")
    parser.add_argument("--views", type=int, default=5, help="val views scored (flower holds out 5)")


def measure(args):
    if not args.before_exe:
        sys.exit("lens_ndc: --before-exe (the previous build's mipnerf-cl) is needed to measure")
    exes = {"now": os.path.abspath(os.path.join(args.build, "mipnerf-cl")), "before": os.path.abspath(args.before_exe)}
    args.work = os.path.abspath(args.work)
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(RESULTS, exist_ok=True)
    log = os.path.join(args.work, "study.log")
    capture = os.path.abspath(args.capture) if args.capture else os.path.join(args.work, "radial")
    if not os.path.exists(os.path.join(capture, "transforms.json")):
        run([exes["now"], "dataset", "from-photos", os.path.join(args.data, "images_8"), capture,
             "--camera-model", "SIMPLE_RADIAL"], log)
    data = {"lens": os.path.join(capture, "transforms.json"), "given": os.path.abspath(args.data)}
    seeds = [int(s) for s in args.seeds.split(",")]
    started = time.time()
    runs = {key: [] for key, *_ in ROWS}
    # Seed by seed, every row in turn: a slow spell of the shared machine falls on all rows, not on one.
    for seed in seeds:
        for key, _, exe, which, factor in ROWS:
            run_dir = train_for_minutes(exes[exe], data[which], os.path.join(args.work, key, f"seed{seed}"), MODEL,
                                        seed, args.minutes, factor, log)
            metrics = evaluate_val(exes[exe], data[which], run_dir, args.views, log)
            runs[key].append(run_record(seed, run_dir, metrics))
    rows = [{"key": key, "label": label, "executable": exe, "capture": which, "factor": factor, "arguments": MODEL,
             "runs": runs[key]} for key, label, exe, which, factor in ROWS]
    return {
        "study": "lens_ndc", "date": time.strftime("%Y-%m-%d", time.gmtime()), "commit": commit_of(),
        "scene": f"flower (LLFF, 34 phone photos at 504x378) imported by `dataset from-photos --camera-model "
                 f"SIMPLE_RADIAL` ({os.path.basename(capture)}), {args.views} val views",
        "budget_minutes": args.minutes, "seeds": seeds, "wall_seconds": round(time.time() - started, 1), "rows": rows,
    }


def write_markdown(record):
    rows = record["rows"]
    header = ["run", *SEED_TABLE_HEADER]
    body = [[r["label"], *seed_table_cells(r["runs"])] for r in rows]
    lines = [report_md.generated_banner(SCRIPT, "lens_ndc.json"), "",
             "# A forward-facing capture behind a lens: NDC through the lens against world rays, at equal time", "",
             f"{record['scene']}; Zip-NeRF `{MODEL}`, `train --minutes {record['budget_minutes']:g}` per run, seeds "
             f"{', '.join(str(s) for s in record['seeds'])}; device {device_line(rows[0]['runs'][0]['device'])}; "
             f"commit {record['commit']}; {record['date']}.", ""]
    lines += report_md.table(header, "lrrrrrr", body)
    by_key = {r["key"]: r for r in rows}
    for a, b in (("now", "before"), ("now", "given")):
        lines += gain_lines(f"{a} minus {b}", by_key[a]["runs"], by_key[b]["runs"])
    lines += wall_time_lines(record)
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "lens_ndc", SCRIPT, add_arguments, measure, write_markdown)
