#!/usr/bin/env python3
"""Photos taken all around, through COLMAP: `dataset from-photos` on a 360-degree capture, then contraction against
spherified world rays at equal training time.

Issue 45 asks for the tool's `from-photos` on photos taken around an object, made with `make-scene`'s procedural scene
from a full orbit: `make-scene --unbounded --texture noise --jpeg` (40 views, 256x192 JPEGs; the ground, the pillars and
the central scene's surfaces carry non-periodic noise, which COLMAP can match: with the checker and stripes of the
default texture it registered every photo into a wrong, forward-facing model). The photos alone (images/, not the
scene's poses) go through `dataset from-photos`, which runs COLMAP and imports its model as a transforms.json; the
study checks COLMAP's cameras against the true ones (scale-free: every pair's distance over the true distance, whose
spread is the error), then trains on the import as a user would, with `train --minutes M` at `--set factor=4`
(64x48), every model seed by seed:
  - mip: mip-NeRF quick as `train` chooses on the capture with no setting (mip-NeRF 360's contracted IPE, proposal
    sampling, the disparity ladder to 1e6);
  - mip_sph: the same with `--set unbounded=false` (spherified world rays between the import's near and far,
    coarse/fine resampling: what `train` did on a 360-degree capture before issue 45);
  - zip, zip_sph: the same pair for Zip-NeRF fast.
Each run is scored by `eval` on the held-out views (every 8th photo). Finished runs and scores in --work are reused.

  /usr/bin/python3 bench/studies/unbounded_from_photos.py --minutes 3 --seeds 0,1,2
  python3 bench/studies/unbounded_from_photos.py --report-only
"""

import itertools
import json
import os
import statistics
import struct
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import add_budget_arguments, budget_markdown, measure_budget, run  # noqa: E402

RESULTS = report_md.results_folder("unbounded_from_photos")
SCRIPT = "bench/studies/unbounded_from_photos.py"
# (key, label, train arguments)
MODELS = [
    ("mip", "mip-NeRF quick, no setting (contracted, as train chooses on a 360° capture)", "--preset quick"),
    ("mip_sph", "mip-NeRF quick, spherified world rays (unbounded=false)", "--preset quick --set unbounded=false"),
    ("zip", "Zip-NeRF fast, no setting (contracted, as train chooses)", "--model zipnerf --preset fast"),
    ("zip_sph", "Zip-NeRF fast, spherified world rays (unbounded=false)",
     "--model zipnerf --preset fast --set unbounded=false"),
]
SCENE = ("make-scene --unbounded --texture noise --jpeg (40 photos around, 256x192) through `dataset from-photos` "
         "(COLMAP) as a transforms.json, factor {factor}, {views} held-out views")


def true_camera_centres(poses_bounds_path):
    """The camera centres of an LLFF poses_bounds.npy (float64, 17 per view), in view order, standard library only."""
    with open(poses_bounds_path, "rb") as f:
        data = f.read()
    header_length = struct.unpack("<H", data[8:10])[0]
    header = data[10:10 + header_length].decode("latin1")
    if "'<f8'" not in header or "False" not in header:
        raise SystemExit(f"{poses_bounds_path}: expected a C-ordered float64 array, header {header!r}")
    values = struct.unpack(f"<{(len(data) - 10 - header_length) // 8}d", data[10 + header_length:])
    rows = [values[k:k + 17] for k in range(0, len(values), 17)]
    return [(r[3], r[8], r[13]) for r in rows]  # the 3x5 matrix's 4th column


def imported_camera_centres(transforms_path):
    """The camera centres of the import's frames, by the photo's index (its name ends in imageNNN.jpg)."""
    with open(transforms_path) as f:
        frames = json.load(f)["frames"]
    centres = {}
    for frame in frames:
        index = int(os.path.basename(frame["file_path"]).rsplit("image", 1)[1].split(".")[0])
        centres[index] = tuple(row[3] for row in frame["transform_matrix"][:3])
    return centres


def pose_check(photos, transforms_path):
    """COLMAP's cameras against the true ones, free of the world's scale: every pair's imported distance over its true
    distance, normalised by the median; its largest deviation and median deviation say how far off the model is."""
    true = true_camera_centres(os.path.join(photos, "poses_bounds.npy"))
    found = imported_camera_centres(transforms_path)
    ratios = []
    for a, b in itertools.combinations(sorted(found), 2):
        true_distance = sum((x - y) ** 2 for x, y in zip(true[a], true[b])) ** 0.5
        found_distance = sum((x - y) ** 2 for x, y in zip(found[a], found[b])) ** 0.5
        ratios.append(found_distance / true_distance)
    scale = statistics.median(ratios)
    deviations = [abs(r / scale - 1) for r in ratios]
    return {"registered": len(found), "photos": len(true), "pair_distance_error_median": statistics.median(deviations),
            "pair_distance_error_max": max(deviations)}


def photos_scene(record_extra):
    """The capture: the photos made once in work/photos, `dataset from-photos` once into work/scene; returns a
    function of (exe, work, log) for measure_budget giving the import's transforms.json."""
    def make(exe, work, log):
        photos, scene = os.path.join(work, "photos"), os.path.join(work, "scene")
        if not os.path.exists(os.path.join(photos, "poses_bounds.npy")):
            run([exe, "make-scene", photos, "--unbounded", "--texture", "noise", "--jpeg"], log)
        transforms = os.path.join(scene, "transforms.json")
        if not os.path.exists(transforms):
            started = time.time()
            run([exe, "dataset", "from-photos", os.path.join(photos, "images"), scene], log)
            record_extra["from_photos_seconds"] = round(time.time() - started, 1)
        record_extra["pose_check"] = pose_check(photos, transforms)
        return transforms
    return make


def add_arguments(parser):
    add_budget_arguments(parser, "/tmp/mipnerf-unbounded-photos", 3.0, 4, "4: 64x48", "the import holds out 5",
                         [m[0] for m in MODELS])


def measure(args):
    extra = {}
    record = measure_budget(args, "unbounded_from_photos", RESULTS, MODELS, photos_scene(extra), SCENE)
    record.update(extra)
    return record


def write_markdown(record):
    text = budget_markdown(record, SCRIPT, "unbounded_from_photos.json",
                           "Photos taken all around through COLMAP: contraction against spherified world rays",
                           [("{label} minus spherified", "mip", "mip_sph"), ("{label} minus spherified", "zip", "zip_sph")])
    check = record.get("pose_check")
    if check:
        seconds = record.get("from_photos_seconds")
        text += (f"\nCOLMAP (through `dataset from-photos`{f', {seconds:g} s' if seconds else ''}) registered "
                 f"{check['registered']} of {check['photos']} photos; every pair of its cameras' distance against the "
                 f"true distance, scale removed: median error {100 * check['pair_distance_error_median']:.2f} %, "
                 f"largest {100 * check['pair_distance_error_max']:.2f} %.\n")
    return text


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "unbounded_from_photos", SCRIPT, add_arguments, measure, write_markdown)
