#!/usr/bin/env python3
"""Photos taken all around, as `dataset from-photos` writes them (a transforms.json): what Zip-NeRF gets from them now
against what it got before, at equal training time.

A 360-degree capture that arrives as a transforms.json (what `from-photos` and `import-colmap` write for photos that
are not forward-facing, and what instant-ngp and nerfstudio write) was trained by Zip-NeRF bounded: near/far from the
file, the grid's cube [-1.5, 1.5]^3 in a world whose median camera the import puts 4 from the centre, so the
background lay outside the grid. Now such a capture is an unbounded scene for Zip-NeRF as a 360-degree LLFF capture
is, and an unbounded run moves the world to the one the contraction expects (centred where the cameras look, RMS
camera distance 1; data::world_around_cameras), as spherify does for LLFF.

The capture: `make-scene --unbounded` (40 views around, 5 held out) written as a transforms.json the way the import
writes one (the world centred where the cameras look, the median camera 4 from it, then moved by an arbitrary offset
since other tools leave their own origin; near/far from the views' depth bounds with the import's 0.9/1.1 margins),
and as written (centred), trained at `--set factor=4` (64x48) for `train --minutes M`, 3 seeds. The runs:
  - before: the previous build's executable (--before-exe), no flag: what `train --model zipnerf` did with the moved
    capture (bounded, proposal-free coarse/fine);
  - before_centred: the same on the capture as the import writes it (centred);
  - stored: the previous build with `--set sampler=proposal --set unbounded=true` given by hand on the moved capture:
    the contraction in the file's world (cameras at 4 from a centre 33 from the origin, contraction from radius 1);
  - now: this build, no flag, on the moved capture: the scene's choice (proposal, unbounded, the world around the
    cameras; the centred capture gives it the same world).
Each scored by its own executable's `eval` on the val views. Finished runs and scores in --work are reused.

  python3 bench/studies/unbounded_photos.py --before-exe /tmp/mipnerf-cl-before --minutes 3 --seeds 0,1,2
  python3 bench/studies/unbounded_photos.py --report-only
"""

import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import (SEED_TABLE_HEADER, commit_of, device_line, evaluate_val, gain_lines, run,  # noqa: E402
                          run_record, seed_table_cells, train_for_minutes, wall_time_lines)

RESULTS = report_md.results_folder("unbounded_photos")
SCRIPT = "bench/studies/unbounded_photos.py"
# (key, label, which executable, which capture, train arguments)
MODELS = [
    ("before", "before: Zip-NeRF fast as the tool trained it (bounded)", "before", "moved",
     "--model zipnerf --preset fast"),
    ("before_centred", "before, on the import's own world (centred where the cameras look)", "before", "centred",
     "--model zipnerf --preset fast"),
    ("stored", "before, unbounded by hand: contraction in the file's world (cameras at 4)", "before", "moved",
     "--model zipnerf --preset fast --set sampler=proposal --set unbounded=true"),
    ("now", "now: Zip-NeRF fast, no flag (unbounded, the world around the cameras)", "now", "moved",
     "--model zipnerf --preset fast"),
]
IMPORTED_CAMERA_DISTANCE = 4.0  # data::kImportedCameraDistance
# The capture's origin: "moved" as another tool's (instant-ngp, nerfstudio) would leave it, "centred" as the import
# writes it (the look-at point at the origin).
CAPTURES = {"moved": ("transforms.json", (30.0, -12.0, 5.0)), "centred": ("transforms_centred.json", (0.0, 0.0, 0.0))}


def add_arguments(parser):
    parser.add_argument("--build", default="build", help="build folder holding this mipnerf-cl")
    parser.add_argument("--before-exe", help="the previous build's mipnerf-cl (the 'before' rows)")
    parser.add_argument("--work", default="/tmp/mipnerf-unbounded-photos", help="the capture, runs and logs")
    parser.add_argument("--minutes", type=float, default=3.0, help="training budget of every run")
    parser.add_argument("--seeds", default="0,1,2", help="comma-separated seeds, each model trained once per seed")
    parser.add_argument("--factor", type=int, default=4, help="the capture's downsampling (4: 64x48)")
    parser.add_argument("--views", type=int, default=5, help="val views scored (the capture holds out 5)")


def read_npy_rows(path):
    """The rows of a 2-D little-endian float64 .npy (poses_bounds.npy), without numpy."""
    import ast
    import struct
    with open(path, "rb") as f:
        data = f.read()
    assert data[:6] == b"\x93NUMPY", f"{path}: not a .npy file"
    header_length = struct.unpack("<H", data[8:10])[0] if data[6] == 1 else struct.unpack("<I", data[8:12])[0]
    start = 10 if data[6] == 1 else 12
    header = ast.literal_eval(data[start:start + header_length].decode("latin1"))
    assert header["descr"] == "<f8" and not header["fortran_order"], f"{path}: expected C-ordered float64"
    rows, cols = header["shape"]
    values = struct.unpack(f"<{rows * cols}d", data[start + header_length:start + header_length + 8 * rows * cols])
    return [list(values[r * cols:(r + 1) * cols]) for r in range(rows)]


def solve3(a, b):
    """x with a x = b for a 3x3 a (Cramer's rule)."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    d = det(a)
    return [det([[b[i] if j == k else a[i][j] for j in range(3)] for i in range(3)]) / d for k in range(3)]


def look_at_point(centres, axes):
    """The least-squares point closest to every optical axis (data::closest_point_to_axes)."""
    a = [[0.0] * 3 for _ in range(3)]
    b = [0.0] * 3
    for o, d in zip(centres, axes):
        n = math.sqrt(sum(x * x for x in d))
        d = [x / n for x in d]
        for i in range(3):
            for j in range(3):
                p = (1.0 if i == j else 0.0) - d[i] * d[j]
                a[i][j] += p
                b[i] += p * o[j]
    return solve3(a, b)


def write_transforms_json(scene_dir, name, offset, log):
    """scene_dir/name: scene_dir's LLFF capture the way the COLMAP import writes one (see __doc__), moved by offset."""
    path = os.path.join(scene_dir, name)
    if os.path.exists(path):
        return path
    rows = read_npy_rows(os.path.join(scene_dir, "poses_bounds.npy"))
    # Per view a 3x5 matrix, row-major: columns down, right, backwards (LLFF), position, (h, w, focal); then bounds.
    views = [[row[5 * r:5 * r + 5] for r in range(3)] for row in rows]
    centres = [[m[r][3] for r in range(3)] for m in views]
    # LLFF's columns (down, right, backwards) to OpenGL's (right, up, backwards); the optical axis is -backwards.
    rotations = [[[m[r][1], -m[r][0], m[r][2]] for r in range(3)] for m in views]
    centre = look_at_point(centres, [[-rot[r][2] for r in range(3)] for rot in rotations])
    distances = sorted(math.dist(c, centre) for c in centres)
    median = (distances[(len(distances) - 1) // 2] + distances[len(distances) // 2]) / 2
    scale = IMPORTED_CAMERA_DISTANCE / median
    height, width, focal = (views[0][r][4] for r in range(3))
    images = sorted(os.listdir(os.path.join(scene_dir, "images")))
    frames = []
    for name, rot, c in zip(images, rotations, centres):
        matrix = [rot[r] + [scale * (c[r] - centre[r]) + offset[r]] for r in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
        frames.append({"file_path": f"images/{name}", "transform_matrix": matrix})
    near = 0.9 * scale * min(row[15] for row in rows)
    far = 1.1 * scale * max(row[16] for row in rows)
    document = {"fl_x": focal, "fl_y": focal, "cx": width / 2, "cy": height / 2, "w": int(width), "h": int(height),
                "near": near, "far": far, "frames": frames}
    with open(path, "w") as f:
        json.dump(document, f, indent=1)
    with open(log, "a") as f:
        f.write(f"wrote {path}: centre {centre}, scale {scale:.4g}, near {near:.3g}, far {far:.3g}\n")
    return path


def measure(args):
    if not args.before_exe:
        sys.exit("unbounded_photos: --before-exe (the previous build's mipnerf-cl) is needed to measure")
    exes = {"now": os.path.abspath(os.path.join(args.build, "mipnerf-cl")), "before": os.path.abspath(args.before_exe)}
    args.work = os.path.abspath(args.work)
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(RESULTS, exist_ok=True)
    log = os.path.join(args.work, "study.log")
    scene = os.path.join(args.work, "scene")
    if not os.path.exists(os.path.join(scene, "poses_bounds.npy")):
        run([exes["now"], "make-scene", scene, "--unbounded"], log)
    data = {key: write_transforms_json(scene, name, offset, log) for key, (name, offset) in CAPTURES.items()}
    seeds = [int(s) for s in args.seeds.split(",")]
    started = time.time()
    runs = {key: [] for key, _, _, _, _ in MODELS}
    # Seed by seed, every model in turn: a slow spell of the shared machine falls on all models, not on one.
    for seed in seeds:
        for key, _, exe, capture, model_args in MODELS:
            run_dir = train_for_minutes(exes[exe], data[capture], os.path.join(args.work, key, f"seed{seed}"),
                                        model_args, seed, args.minutes, args.factor, log)
            metrics = evaluate_val(exes[exe], data[capture], run_dir, args.views, log)
            runs[key].append(run_record(seed, run_dir, metrics))
    rows = [{"key": key, "label": label, "executable": exe, "capture": capture, "arguments": model_args,
             "runs": runs[key]} for key, label, exe, capture, model_args in MODELS]
    return {
        "study": "unbounded_photos", "date": time.strftime("%Y-%m-%d", time.gmtime()), "commit": commit_of(),
        "scene": f"make-scene --unbounded as a transforms.json (median camera {IMPORTED_CAMERA_DISTANCE:g} from where "
                 f"the cameras look, moved by {CAPTURES['moved'][1]}; and as written, centred), factor {args.factor}, "
                 f"{args.views} val views",
        "budget_minutes": args.minutes, "seeds": seeds, "wall_seconds": round(time.time() - started, 1), "rows": rows,
    }


def write_markdown(record):
    rows = record["rows"]
    header = ["model", *SEED_TABLE_HEADER]
    body = [[r["label"], *seed_table_cells(r["runs"])] for r in rows]
    lines = [report_md.generated_banner(SCRIPT, "unbounded_photos.json"), "",
             "# Photos taken all around as a transforms.json: Zip-NeRF now and before, at equal training time", "",
             f"{record['scene']}; `train --minutes {record['budget_minutes']:g}` per run, seeds "
             f"{', '.join(str(s) for s in record['seeds'])}; device {device_line(rows[0]['runs'][0]['device'])}; "
             f"commit {record['commit']}; {record['date']}.", ""]
    lines += report_md.table(header, "lrrrrrr", body)
    by_key = {r["key"]: r for r in rows}
    for other in (k for k in ("before", "before_centred", "stored") if k in by_key):
        lines += gain_lines(f"Now minus {other}", by_key["now"]["runs"], by_key[other]["runs"])
    lines += wall_time_lines(record)
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "unbounded_photos", SCRIPT, add_arguments, measure, write_markdown)
