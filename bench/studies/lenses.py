#!/usr/bin/env python3
"""Lens-aware training against undistort-first on a real capture. Writes bench/results/lenses/lenses.{json,md}.

  python3 bench/studies/lenses.py --photos /tmp/from_photos/photos --bin BUILD/mipnerf-cl [--steps 600] [--preset quick]
      [--work /tmp/lenses]

PHOTOS is a folder of JPEG photos of one camera (bench/studies/from_photos.py writes flower's images_8 as JPEG there). In
--work, outside the repository:

  1. `BIN dataset from-photos PHOTOS WORK/opencv --camera-model OPENCV`: COLMAP estimates an OPENCV lens; the import
     keeps it (a transforms.json: lens cameras train with cone rays).
  2. COLMAP's `image_undistorter` on the same sparse model and photos (WORK/undistorted: PINHOLE cameras, resampled
     and cropped photos), imported with `--layout transforms`: the same layout and ray shape as (1), so the lens is the
     only difference.
  3. Both trained with the same preset and steps (seed 0), then `BIN eval` on each one's test split (every 8th photo
     in name order: the same photos in both, each against its own images).
  4. The cost of lens-aware rays per step: `train --profile` for 30 steps on each, the "rays" stage's mean.

Re-running reuses what WORK holds (finished imports, trainings and evals); --redo starts over.
"""

import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.provenance import REPO, commit_of  # noqa: E402
from lib.run import RunError, run  # noqa: E402



def run_timed(command, log):
    """lib/run.py's run, its output appended to `log`; returns the wall seconds it took."""
    started = time.time()
    run(command, log)
    return time.time() - started


def load(path):
    with open(path) as f:
        return json.load(f)


def device_name(args):
    out = subprocess.run([args.bin, "devices"], capture_output=True, text=True).stdout
    for line in out.splitlines():
        if "<- selected" in line:
            return line.split("]", 1)[1].split("<-")[0].strip()
    return "?"


def import_captures(args, work):
    opencv = os.path.join(work, "opencv")
    record = {}
    if not os.path.exists(os.path.join(opencv, "transforms.json")):
        seconds = run_timed([args.bin, "dataset", "from-photos", args.photos, opencv, "--camera-model", "OPENCV"],
                      os.path.join(work, "from-photos.log"))
        record["from_photos_seconds"] = round(seconds, 1)
    undistorted = os.path.join(work, "undistorted")
    pinhole = os.path.join(work, "pinhole")
    if not os.path.exists(os.path.join(pinhole, "transforms.json")):
        shutil.rmtree(undistorted, ignore_errors=True)
        sparse = os.path.join(opencv, "colmap", "sparse", "0")
        seconds = run_timed([args.colmap, "image_undistorter", "--image_path", args.photos, "--input_path", sparse,
                       "--output_path", undistorted, "--output_type", "COLMAP"], os.path.join(work, "undistort.log"))
        record["undistort_seconds"] = round(seconds, 1)
        run([args.bin, "dataset", "import-colmap", os.path.join(undistorted, "sparse"),
             os.path.join(undistorted, "images"), pinhole, "--layout", "transforms"], os.path.join(work, "import.log"))
    inspect = {}
    for name, path in (("opencv", opencv), ("pinhole", pinhole)):
        out = subprocess.run([args.bin, "dataset", "inspect", path], capture_output=True, text=True).stdout
        inspect[name] = [line.strip() for line in out.splitlines() if "lens:" in line or "images" in line][:4]
    record["inspect"] = inspect
    return {"opencv": opencv, "pinhole": pinhole}, record


def train_and_eval(args, work, name, data):
    run_dir = os.path.join(work, "run_" + name)
    if not os.path.exists(os.path.join(run_dir, "summary.json")):
        shutil.rmtree(run_dir, ignore_errors=True)
        run([args.bin, "train", "--data", data, "--out", run_dir, "--preset", args.preset, "--steps", str(args.steps),
             "--val_every", "0", "--set", "val_views=1"], os.path.join(work, f"train_{name}.log"))
    eval_dir = os.path.join(work, "eval_" + name)
    if not os.path.exists(os.path.join(eval_dir, "metrics.json")):
        run([args.bin, "eval", "--checkpoint", run_dir, "--split", "test", "--no-images", "--out", eval_dir],
            os.path.join(work, f"eval_{name}.log"))
    profile_dir = os.path.join(work, "profile_" + name)
    if not os.path.exists(os.path.join(profile_dir, "profile.md")):
        shutil.rmtree(profile_dir, ignore_errors=True)
        run([args.bin, "train", "--data", data, "--out", profile_dir, "--preset", args.preset, "--steps", "30",
             "--val_every", "0", "--set", "val_views=1", "--profile"], os.path.join(work, f"profile_{name}.log"))
    summary, metrics = load(os.path.join(run_dir, "summary.json")), load(os.path.join(eval_dir, "metrics.json"))
    with open(os.path.join(profile_dir, "profile.md")) as f:
        profile = f.read()
    rays_row = next((line for line in profile.splitlines() if line.startswith("| rays ")), "")
    return {
        "data": data,
        "steps": summary["steps"],
        "train_seconds": round(summary["train_seconds"], 1),
        "test_images": metrics["mean"]["images"],
        "test_psnr": round(metrics["mean"]["psnr"], 3),
        "test_ssim": round(metrics["mean"]["ssim"], 4),
        "render_seconds_per_megapixel": metrics.get("render", {}).get("seconds_per_megapixel"),
        "profile_rays_row": rays_row,
        "profile": os.path.join(profile_dir, "profile.md"),
    }


def write_markdown(record, path):
    o, p = record["runs"]["opencv"], record["runs"]["pinhole"]
    lines = [
        "# Lens-aware training vs undistort-first (bench/studies/lenses.py)",
        "",
        f"Capture: {record['photos']} ({record['photo_count']} JPEG photos). Device: {record['device']}. "
        f"Commit {record['commit']}, {record['date']}. Preset {record['preset']}, {o['steps']} steps each, seed 0.",
        "",
    ]

    def row(label, camera, r):
        return [label, camera, str(r["test_images"]), f"{r['test_psnr']:.2f}", f"{r['test_ssim']:.4f}",
                str(r["train_seconds"]), f"`{r['profile_rays_row']}`"]
    lines += report_md.table(["", "camera", "test views", "test PSNR (dB)", "SSIM", "train s",
                              "rays stage per step (profile)"], "llrrrrl",
                             [row("COLMAP OPENCV, trained as is", "lens tables", o),
                              row("COLMAP image_undistorter, PINHOLE", "pinhole", p)])
    lines += [
        "",
        "What `dataset inspect` says of each:",
        "",
    ]
    for name, inspect in record["import"]["inspect"].items():
        lines.append(f"- {name}: " + "; ".join(inspect))
    lines += ["", "Each PSNR is against the capture's own images (the undistorted run's are COLMAP's resampled, "
              "cropped photos), on the same photos (every 8th in name order).", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--photos", default="/tmp/from_photos/photos")
    parser.add_argument("--bin", default=os.path.join(REPO, "build", "mipnerf-cl"))
    parser.add_argument("--colmap", default="colmap")
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--preset", default="quick")
    parser.add_argument("--work", default="/tmp/lenses")
    parser.add_argument("--results", default=report_md.results_folder("lenses"))
    parser.add_argument("--redo", action="store_true")
    args = parser.parse_args()
    if not os.path.isdir(args.photos):
        sys.exit(f"lenses: {args.photos}: no such folder of photos (bench/studies/from_photos.py writes flower's there)")
    if args.redo:
        shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work, exist_ok=True)
    captures, import_record = import_captures(args, args.work)
    record = {
        "photos": os.path.abspath(args.photos),
        "photo_count": len([f for f in os.listdir(args.photos) if f.lower().endswith((".jpg", ".jpeg", ".png"))]),
        "device": device_name(args),
        "commit": commit_of(REPO),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "preset": args.preset,
        "load_average": os.getloadavg(),
        "import": import_record,
        "runs": {name: train_and_eval(args, args.work, name, path) for name, path in captures.items()},
    }
    os.makedirs(args.results, exist_ok=True)
    with open(os.path.join(args.results, "lenses.json"), "w") as f:
        json.dump(record, f, indent=1)
    write_markdown(record, os.path.join(args.results, "lenses.md"))
    print(json.dumps(record["runs"], indent=1))


if __name__ == "__main__":
    try:
        main()
    except RunError as e:
        sys.exit(f"lenses: {e}")
