#!/usr/bin/env python3
"""`mipnerf-cl dataset from-photos` on a real capture: COLMAP's cameras against the capture's own, and mip-NeRF
trained on each. Writes bench/results/from_photos/from_photos.{json,md}.

  python3 bench/studies/from_photos.py --data /work/shared/data/llff/flower --bin BUILD/mipnerf-cl \\
      [--steps 600] [--seeds 1] [--preset quick] [--work /tmp/from_photos]

DATA is an LLFF capture with images_8/*.png and its own poses_bounds.npy (flower: 34 phone photos at 504x378).
Everything is made in --work, outside the repository; nothing of the capture is copied into it.

  1. Photos: images_8/*.png saved as JPEG (quality 95, Pillow's defaults otherwise: 4:2:0 chroma, no EXIF), as a
     phone would hand them over, in WORK/photos.
  2. `BIN dataset from-photos WORK/photos WORK/colmap_capture` (defaults: exhaustive matching, features at up to
     1600 px, 8192 per photo, layout auto), timed: photos, registered images, layout, points, COLMAP's steps.
  3. Poses: COLMAP's (WORK/colmap_capture/poses_bounds.npy, rows in the order of its images/ names NNNNN_<photo>)
     against DATA/poses_bounds.npy (rows in sorted image-name order), views matched by photo name. A similarity
     (Umeyama: rotation, translation, scale) fitted from COLMAP's camera centres to the given ones; per view the
     rotation error (angle of R_given (R_fit R_colmap)^T, camera-to-world rotations in OpenGL axes) and the
     position error after the fit as a fraction of the capture's extent (the largest distance between two given
     camera centres); the focal length (COLMAP's against the given one scaled to the photos' width); the depth
     bounds after the fit.
  4. Training: the same preset and steps on COLMAP's capture (WORK/colmap_capture, factor 1) and on the given
     poses (WORK/given: the given poses_bounds.npy unchanged and images_8/ = links to the same JPEGs, trained with
     factor 8 so the loader takes images_8/ with focal / 8, as the official loader does); both are LLFF captures
     (NDC, cylinders, every LLFF convention). Then `BIN eval --checkpoint RUN` on each one's held-out views (every
     8th image of its own order) for test PSNR, SSIM and render s/MP.
  5. bench/results/from_photos/from_photos.json (everything, raw) and from_photos.md generated from it (write_markdown);
     `--report-only` regenerates the .md alone. Hand-written notes go under "## Notes (by hand)" at the end of the
     .md, which regeneration keeps.

Re-running reuses what WORK holds (the photos, COLMAP's capture and its record, finished trainings and evals);
--redo removes WORK's runs first. The measurement needs numpy and Pillow: without them the script re-runs itself
with the Python of ~/.cache/mipnerf-cl/vs-official-venv (--python). --report-only needs neither.
"""

import argparse
import datetime
import glob
import json
import os
import platform
import re
import resource
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import read_json, run, train_resumable  # noqa: E402
from lib.provenance import cpu_model, file_sha256, tree_state  # noqa: E402

from lib.provenance import REPO  # noqa: E402
DEFAULT_PYTHON = os.path.join(os.path.expanduser("~"), ".cache", "mipnerf-cl", "vs-official-venv", "bin", "python")
JPEG_QUALITY = 95
TICK = os.sysconf("SC_CLK_TCK")


# ---- the machine and the checkout ----

def machine_busy_seconds():
    """Busy CPU seconds of the whole machine since boot (/proc/stat: user nice system irq softirq)."""
    with open("/proc/stat") as f:
        fields = [int(x) for x in f.readline().split()[1:]]
    user, nice, system, _idle, _iowait, irq, softirq = fields[:7]
    return (user + nice + system + irq + softirq) / TICK


def own_cpu_seconds():
    """CPU seconds of this script and its finished children (the mipnerf-cl and COLMAP runs)."""
    return sum(resource.getrusage(who).ru_utime + resource.getrusage(who).ru_stime
               for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))


class Phase:
    """Wall time, load average and CPU use of a phase: ours (this script's children) and everything else's."""

    def __init__(self):
        self.t0, self.load0 = time.monotonic(), [round(x, 2) for x in os.getloadavg()]
        self.machine0, self.own0 = machine_busy_seconds(), own_cpu_seconds()

    def end(self):
        wall = time.monotonic() - self.t0
        own = own_cpu_seconds() - self.own0
        machine = machine_busy_seconds() - self.machine0
        return {"wall_seconds": round(wall, 2), "own_cpu_seconds": round(own, 1),
                "own_cores": round(own / wall, 2) if wall > 0 else None,
                "other_cores": round(max(machine - own, 0.0) / wall, 2) if wall > 0 else None,
                "load_before": self.load0, "load_after": [round(x, 2) for x in os.getloadavg()]}


def colmap_version():
    r = subprocess.run(["colmap", "-h"], capture_output=True, text=True, env={**os.environ, "QT_QPA_PLATFORM": "offscreen"})
    for line in (r.stdout + r.stderr).splitlines():
        if line.startswith("COLMAP"):
            return line.strip()
    return "unknown"


# ---- 1. photos ----

def make_photos(data, photos):
    from PIL import Image
    sources = sorted(glob.glob(os.path.join(data, "images_8", "*.png")))
    if not sources:
        raise SystemExit(f"{data}/images_8/: no PNGs")
    os.makedirs(photos, exist_ok=True)
    sizes, total = set(), 0
    for src in sources:
        dst = os.path.join(photos, os.path.splitext(os.path.basename(src))[0] + ".jpg")
        with Image.open(src) as im:
            sizes.add(im.size)
            if not os.path.exists(dst):
                im.convert("RGB").save(dst + ".tmp.jpg", "JPEG", quality=JPEG_QUALITY)
                os.replace(dst + ".tmp.jpg", dst)
        total += os.path.getsize(dst)
    return {"folder": photos, "count": len(sources), "sizes": sorted(list(s) for s in sizes),
            "format": f"JPEG quality {JPEG_QUALITY} (Pillow defaults: 4:2:0 chroma subsampling, no EXIF)",
            "bytes": total, "source": os.path.join(data, "images_8", "*.png")}


# ---- 2. COLMAP ----

def parse_import_output(text):
    out = {}
    m = re.search(r"imported (\d+) images \((\d+) cameras?: ([^)]*)\) and (\d+) points", text)
    if m:
        out.update(images=int(m.group(1)), cameras=int(m.group(2)), camera_models=m.group(3),
                   points=int(m.group(4)))
    m = re.search(r"^layout: ([^,]+), (.*)$", text, re.M)
    if m:
        out.update(layout=m.group(1).strip(), layout_reason=m.group(2).strip())
    m = re.search(r"bounds per image .*?: ([0-9.e+-]+) \.\. ([0-9.e+-]+)", text)
    if m:
        out.update(bounds_min=float(m.group(1)), bounds_max=float(m.group(2)))
    m = re.search(r"COLMAP registered (\d+) of (\d+)", text)
    if m:
        out["warning"] = m.group(0)
    return out


def colmap_steps(log_path):
    """Each COLMAP step's own 'Elapsed time' (minutes) from OUT/colmap/colmap.log, in the order they ran."""
    steps, current = [], None
    with open(log_path, errors="replace") as f:
        for line in f:
            if line.startswith("$ "):
                m = re.search(r"'(feature_extractor|\w+_matcher|mapper)'", line)
                current = m.group(1) if m else line[2:40]
            m = re.search(r"Elapsed time: ([0-9.]+) \[minutes\]", line)
            if m and current:
                steps.append({"step": current, "minutes": float(m.group(1))})
    # the mapper prints an elapsed time per sub-step; keep the last (its total) for each step
    total = {}
    for s in steps:
        total[s["step"]] = s["minutes"]
    return [{"step": k, "seconds": round(v * 60, 1)} for k, v in total.items()]


def model_stats(sparse_model):
    """`colmap model_analyzer` of the imported model: observations, track length, reprojection error."""
    r = subprocess.run(["colmap", "model_analyzer", "--path", sparse_model], capture_output=True, text=True,
                       env={**os.environ, "QT_QPA_PLATFORM": "offscreen"})
    stats = {}
    for line in (r.stdout + r.stderr).splitlines():
        m = re.search(r"(Cameras|Images|Registered images|Points|Observations|Mean track length|"
                      r"Mean observations per image|Mean reprojection error)\s*:\s*([0-9.]+)", line)
        if m:
            stats[m.group(1).lower().replace(" ", "_")] = float(m.group(2))
    return stats


def run_colmap(exe, photos, out, work, photo_count):
    record_path = os.path.join(work, "colmap_record.json")
    if os.path.exists(record_path) and os.path.exists(os.path.join(out, "poses_bounds.npy")):
        return read_json(record_path)
    if os.path.exists(out):
        shutil.rmtree(out)
    command = [exe, "dataset", "from-photos", photos, out]
    phase = Phase()
    r = subprocess.run(command, capture_output=True, text=True)
    measured = phase.end()
    with open(os.path.join(work, "from-photos.log"), "w") as f:
        f.write("$ " + " ".join(command) + "\n" + r.stdout + "\n--- stderr ---\n" + r.stderr)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({r.returncode}):\n{r.stderr[-2000:]}")
    record = {"command": command, "photos": photo_count, **measured, **parse_import_output(r.stdout + r.stderr),
              "stdout": r.stdout}
    m = re.search(r"points from (\S+) \(", r.stdout)
    record["sparse_model"] = m.group(1) if m else None
    record["colmap_steps"] = colmap_steps(os.path.join(out, "colmap", "colmap.log"))
    if record["sparse_model"]:
        record["model_analyzer"] = model_stats(record["sparse_model"])
    record["models_found"] = sorted(os.listdir(os.path.join(out, "colmap", "sparse")))
    with open(record_path, "w") as f:
        json.dump(record, f, indent=2)
    return record


# ---- 3. poses ----

def llff_c2w(rows):
    """(N, 3, 4) camera-to-world in OpenGL axes (right, up, back) from LLFF rows (down, right, back, position)."""
    import numpy as np
    m = rows[:, :15].reshape(-1, 3, 5)
    return np.concatenate([m[:, :, 1:2], -m[:, :, 0:1], m[:, :, 2:3], m[:, :, 3:4]], axis=2)


def umeyama(src, dst):
    """s, R, t minimising sum |dst - (s R src + t)|^2 (Umeyama 1991), R a proper rotation."""
    import numpy as np
    mu_s, mu_d = src.mean(0), dst.mean(0)
    xs, xd = src - mu_s, dst - mu_d
    cov = xd.T @ xs / len(src)
    u, d, vt = np.linalg.svd(cov)
    fix = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        fix[2, 2] = -1
    rot = u @ fix @ vt
    scale = np.trace(np.diag(d) @ fix) / (xs ** 2).sum(1).mean()
    return scale, rot, mu_d - scale * rot @ mu_s


def angle_deg(rot):
    import numpy as np
    return float(np.degrees(np.arccos(np.clip((np.trace(rot) - 1) / 2, -1.0, 1.0))))


def given_poses(data):
    import numpy as np
    rows = np.load(os.path.join(data, "poses_bounds.npy"))
    names = [os.path.splitext(os.path.basename(p))[0] for p in sorted(glob.glob(os.path.join(data, "images_8", "*")))]
    return rows, names


def compare_poses(data, out, photo_width):
    import numpy as np
    colmap_rows = np.load(os.path.join(out, "poses_bounds.npy"))
    colmap_files = sorted(os.listdir(os.path.join(out, "images")))
    colmap_names = [os.path.splitext(f.split("_", 1)[1])[0] for f in colmap_files]
    return compare_rows(*given_poses(data), colmap_rows, colmap_names, photo_width)


def compare_rows(given_rows, given_names, colmap_rows, colmap_names, photo_width):
    """compare_poses on LLFF rows: COLMAP's (colmap_rows, named colmap_names) against the given ones."""
    import numpy as np
    if len(colmap_names) != len(colmap_rows) or len(given_names) != len(given_rows):
        raise SystemExit("poses and image names differ in number")
    index_given = {n: i for i, n in enumerate(given_names)}
    matched = [(n, index_given[n], j) for j, n in enumerate(colmap_names) if n in index_given]
    gi = [g for _, g, _ in matched]
    cj = [c for _, _, c in matched]
    given, colmap = llff_c2w(given_rows)[gi], llff_c2w(colmap_rows)[cj]
    scale, rot, trans = umeyama(colmap[:, :, 3], given[:, :, 3])
    fitted_centres = scale * colmap[:, :, 3] @ rot.T + trans
    all_given_centres = llff_c2w(given_rows)[:, :, 3]
    extent = max(float(np.linalg.norm(a - b)) for a in all_given_centres for b in all_given_centres)
    views = []
    for k, (name, g, c) in enumerate(matched):
        rot_err = angle_deg(given[k, :, :3] @ (rot @ colmap[k, :, :3]).T)
        pos_err = float(np.linalg.norm(fitted_centres[k] - given[k, :, 3]))
        views.append({"name": name, "given_row": g, "colmap_row": c, "rotation_error_deg": rot_err,
                      "position_error": pos_err, "position_error_of_extent": pos_err / extent,
                      "given_bounds": [float(x) for x in given_rows[g, 15:17]],
                      "colmap_bounds_fitted": [float(x) * scale for x in colmap_rows[c, 15:17]]})
    # A diagnostic: the best rotation from the orientations alone (the chordal mean of R_given R_colmap^T), to tell
    # the orientations' own scatter from a tilt of the centre fit.
    acc = sum(given[k, :, :3] @ colmap[k, :, :3].T for k in range(len(matched)))
    u, _, vt = np.linalg.svd(acc)
    rot_orient = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
    orient_errs = [angle_deg(given[k, :, :3] @ (rot_orient @ colmap[k, :, :3]).T) for k in range(len(matched))]
    h_g, w_g, f_g = (float(x) for x in given_rows[0, :15].reshape(3, 5)[:, 4])
    h_c, w_c, f_c = (float(x) for x in colmap_rows[0, :15].reshape(3, 5)[:, 4])
    given_focal = f_g * photo_width / w_g
    rot_errs = [v["rotation_error_deg"] for v in views]
    pos_errs = [v["position_error_of_extent"] for v in views]
    near_ratio = [v["colmap_bounds_fitted"][0] / v["given_bounds"][0] for v in views]
    far_ratio = [v["colmap_bounds_fitted"][1] / v["given_bounds"][1] for v in views]
    return {
        "matched_views": len(matched),
        "given_views": len(given_rows),
        "colmap_views": len(colmap_rows),
        "unregistered": sorted(set(given_names) - set(colmap_names)),
        "fit": {"scale": float(scale), "rotation": rot.tolist(), "translation": trans.tolist(),
                "rotation_angle_deg": angle_deg(rot)},
        "extent": extent,
        "extent_definition": "largest distance between two given camera centres (given units)",
        "rotation_error_deg": {"median": float(np.median(rot_errs)), "mean": float(np.mean(rot_errs)),
                               "max": float(np.max(rot_errs))},
        "position_error_of_extent": {"median": float(np.median(pos_errs)), "mean": float(np.mean(pos_errs)),
                                     "max": float(np.max(pos_errs))},
        "rotation_error_deg_orientation_fit": {"median": float(np.median(orient_errs)),
                                               "max": float(np.max(orient_errs)),
                                               "fit_vs_centre_fit_deg": angle_deg(rot_orient @ rot.T)},
        "focal": {"colmap_px": f_c, "colmap_hw": [h_c, w_c], "given_px_full": f_g, "given_hw_full": [h_g, w_g],
                  "given_px_at_photo_width": given_focal, "photo_width": photo_width,
                  "relative_difference": f_c / given_focal - 1},
        "bounds": {"given_min_near": float(given_rows[:, 15].min()), "given_max_far": float(given_rows[:, 16].max()),
                   "colmap_fitted_min_near": float(colmap_rows[:, 15].min() * scale),
                   "colmap_fitted_max_far": float(colmap_rows[:, 16].max() * scale),
                   "near_ratio_median": float(np.median(near_ratio)), "far_ratio_median": float(np.median(far_ratio))},
        "views": views,
    }


# ---- 3b. a diagnostic: the same matches mapped with a radial-distortion camera ----

COLMAP_MODELS = {"SIMPLE_PINHOLE": 0, "PINHOLE": 1, "SIMPLE_RADIAL": 2}


def qvec_to_rotation(q):
    import numpy as np
    w, x, y, z = q
    return np.array([[1 - 2 * y * y - 2 * z * z, 2 * x * y - 2 * w * z, 2 * x * z + 2 * w * y],
                     [2 * x * y + 2 * w * z, 1 - 2 * x * x - 2 * z * z, 2 * y * z - 2 * w * x],
                     [2 * x * z - 2 * w * y, 2 * y * z + 2 * w * x, 1 - 2 * x * x - 2 * y * y]])


def read_text_model(folder):
    """cameras.txt and images.txt of a COLMAP text model: ({id: (model, w, h, params)}, [(name, R_w2c, t, cam)])."""
    import numpy as np
    cameras, images = {}, []
    with open(os.path.join(folder, "cameras.txt")) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            p = line.split()
            cameras[int(p[0])] = (p[1], int(p[2]), int(p[3]), [float(x) for x in p[4:]])
    with open(os.path.join(folder, "images.txt")) as f:
        lines = [line for line in f if not line.startswith("#")]
    for line in lines[0::2]:
        p = line.split()
        if len(p) < 10:
            continue
        images.append((p[9], qvec_to_rotation([float(x) for x in p[1:5]]), np.array([float(x) for x in p[5:8]]),
                       int(p[8])))
    return cameras, images


def rows_from_text_model(cameras, images):
    """LLFF rows (no bounds: zeros) and photo names, sorted by name, from a COLMAP text model."""
    import numpy as np
    rows, names = [], []
    for name, r_w2c, t, cam in sorted(images, key=lambda i: i[0]):
        _, w, h, params = cameras[cam]
        rot = r_w2c.T                      # camera-to-world, OpenCV axes (x right, y down, z forward)
        centre = -r_w2c.T @ t
        right, up, back = rot[:, 0], -rot[:, 1], -rot[:, 2]
        m = np.stack([-up, right, back, centre, np.array([h, w, params[0]], float)], 1)
        rows.append(np.concatenate([m.reshape(-1), [0.0, 0.0]]))
        names.append(os.path.splitext(name)[0])
    return np.array(rows), names


def radial_check(data, photos, out, work, photo_width):
    """The from-photos run's features and matches (its database, copied) mapped again with one SIMPLE_RADIAL camera
    (focal, centre, one radial coefficient): does a distortion term move COLMAP's focal length and poses to the
    given ones? Not what from-photos does (its import takes pinhole cameras); a diagnostic only."""
    import sqlite3
    import numpy as np
    folder = os.path.join(work, "radial_check")
    record_path = os.path.join(folder, "record.json")
    if os.path.exists(record_path):
        return read_json(record_path)
    if os.path.exists(folder):
        shutil.rmtree(folder)
    os.makedirs(os.path.join(folder, "sparse"))
    database = os.path.join(folder, "database.db")
    shutil.copyfile(os.path.join(out, "colmap", "database.db"), database)
    with sqlite3.connect(database) as db:
        cams = db.execute("SELECT camera_id, model, width, height, params, prior_focal_length FROM cameras").fetchall()
        prior = []
        for cam_id, model, w, h, params, prior_focal in cams:
            values = np.frombuffer(params, dtype=np.float64)
            prior.append({"camera_id": cam_id, "model": model, "params": values.tolist(),
                          "prior_focal_length": bool(prior_focal)})
            new = np.array([values[0], values[1], values[2], 0.0], dtype=np.float64)
            db.execute("UPDATE cameras SET model=?, params=? WHERE camera_id=?",
                       (COLMAP_MODELS["SIMPLE_RADIAL"], new.tobytes(), cam_id))
    os.environ["QT_QPA_PLATFORM"] = "offscreen"  # COLMAP's Qt needs no display for these steps
    log = os.path.join(folder, "colmap.log")
    phase = Phase()
    run(["colmap", "mapper", "--database_path", database, "--image_path", photos, "--output_path",
         os.path.join(folder, "sparse")], log)
    measured = phase.end()
    models = sorted(os.listdir(os.path.join(folder, "sparse")))
    best = None
    for m in models:
        txt = os.path.join(folder, "text_" + m)
        os.makedirs(txt, exist_ok=True)
        run(["colmap", "model_converter", "--input_path", os.path.join(folder, "sparse", m), "--output_path", txt,
             "--output_type", "TXT"], log)
        cameras, images = read_text_model(txt)
        if best is None or len(images) > len(best[1]):
            best = (cameras, images)
    cameras, images = best
    rows, names = rows_from_text_model(cameras, images)
    comparison = compare_rows(*given_poses(data), rows, names, photo_width)
    comparison.pop("bounds", None)
    for v in comparison["views"]:
        v.pop("colmap_bounds_fitted", None)
    camera = next(iter(cameras.values()))
    record = {"what": "the from-photos database (its features and matches) mapped again with one SIMPLE_RADIAL "
                      "camera (f, cx, cy, k); a diagnostic, not imported",
              "database_cameras_before": prior, "registered": len(images), "models": models,
              "camera": {"model": camera[0], "width": camera[1], "height": camera[2], "params": camera[3]},
              "mapper_phase": measured, "comparison": comparison}
    with open(record_path, "w") as f:
        json.dump(record, f, indent=2)
    return record


# ---- 4. training ----

def given_capture(data, photos, folder):
    """WORK/given: the given poses_bounds.npy (a copy, unchanged) and images_8/ = links to the JPEGs."""
    os.makedirs(os.path.join(folder, "images_8"), exist_ok=True)
    dst = os.path.join(folder, "poses_bounds.npy")
    if not os.path.exists(dst):
        shutil.copyfile(os.path.join(data, "poses_bounds.npy"), dst)
    for jpg in sorted(glob.glob(os.path.join(photos, "*.jpg"))):
        link = os.path.join(folder, "images_8", os.path.basename(jpg))
        if not os.path.lexists(link):
            os.symlink(os.path.abspath(jpg), link)
    return folder


def train_and_eval(exe, data, out, preset, settings, log):
    """Trains (or resumes) and evaluates a run; its record is kept in OUT/bench_record.json, so a re-run of the
    script reuses a finished run with the timings and conditions measured when it ran."""
    record_path = os.path.join(out, "bench_record.json")
    if os.path.exists(record_path):
        record = read_json(record_path)
        if record.get("steps") == settings.get("steps") and record.get("settings") == settings:
            return record
    phase = Phase()
    summary, command = train_resumable(exe, data, out, preset, "mipnerf", settings, log)
    train_phase = phase.end()
    metrics_path = os.path.join(out, "eval_test", "metrics.json")
    eval_command = [exe, "eval", "--checkpoint", out]
    phase = Phase()
    if not os.path.exists(metrics_path) or read_json(metrics_path).get("step") != summary["steps"]:
        run(eval_command, log)
    eval_phase = phase.end()
    metrics = read_json(metrics_path)
    config = read_json(os.path.join(out, "config.json"))
    val_log = []
    val_path = os.path.join(out, "val_log.csv")
    if os.path.exists(val_path):
        with open(val_path) as f:
            header = f.readline().strip().split(",")
            val_log = [dict(zip(header, line.strip().split(","))) for line in f if line.strip()]
    record = {
        "data": data, "out": out, "settings": settings, "train_command": command, "eval_command": eval_command,
        "steps": summary["steps"], "train_seconds": summary["train_seconds"], "device": summary.get("device"),
        "parameters": summary.get("parameters"),
        "train_val": summary.get("val"), "val_log": val_log,
        "test_psnr": metrics["mean"]["psnr"], "test_ssim": metrics["mean"]["ssim"],
        "test_views": metrics["mean"]["images"],
        "test_files": [os.path.basename(i["file"]) for i in metrics["images"]],
        "test_per_view": [{"file": os.path.basename(i["file"]), "psnr": i["psnr"], "ssim": i["ssim"]}
                          for i in metrics["images"]],
        "render_s_per_mp": metrics["render"]["seconds_per_megapixel"],
        "render_seconds": metrics["render"]["render_seconds"], "megapixels": metrics["render"]["megapixels"],
        "test_size": [metrics["images"][0]["width"], metrics["images"][0]["height"]] if metrics["images"] else None,
        "scene_effects": config.get("scene_effects"),
        "train_phase": train_phase, "eval_phase": eval_phase,
    }
    with open(record_path, "w") as f:
        json.dump(record, f, indent=2)
    return record


def photo_name(file):
    """A held-out view's photo name: COLMAP's capture names its images NNNNN_<photo>."""
    stem = os.path.splitext(os.path.basename(file))[0]
    return stem.split("_", 1)[1] if re.match(r"^\d{5}_", stem) else stem


# ---- main ----

def ensure_python(args):
    try:
        import numpy  # noqa: F401
        import PIL  # noqa: F401
    except ImportError:
        if os.environ.get("FROM_PHOTOS_REEXEC") or not os.path.exists(args.python):
            raise SystemExit(f"numpy and Pillow are needed (none in {sys.executable}; --python {args.python})")
        os.environ["FROM_PHOTOS_REEXEC"] = "1"
        os.execv(args.python, [args.python, os.path.abspath(__file__)] + sys.argv[1:])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default="/work/shared/data/llff/flower")
    parser.add_argument("--bin", default=os.path.join(REPO, "build", "mipnerf-cl"))
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--seeds", type=int, default=1, help="trainings per capture (seeds 0..N-1)")
    parser.add_argument("--preset", default="quick")
    parser.add_argument("--val-every", type=int, default=300)
    parser.add_argument("--val-views", type=int, default=1, help="views scored every --val-every steps")
    parser.add_argument("--work", default="/tmp/from_photos")
    parser.add_argument("--results", default=report_md.results_folder("from_photos"))
    parser.add_argument("--python", default=DEFAULT_PYTHON, help="a Python with numpy and Pillow")
    parser.add_argument("--no-radial-check", dest="radial_check", action="store_false",
                        help="skip the diagnostic: COLMAP's mapper again on the same matches with a SIMPLE_RADIAL "
                             "camera (after the trainings, about as long as the first mapping)")
    parser.add_argument("--redo", action="store_true", help="remove WORK's COLMAP capture and runs first")
    parser.add_argument("--report-only", action="store_true",
                        help="regenerate from_photos.md from from_photos.json in --results (no runs)")
    args = parser.parse_args()
    if args.report_only:
        return report_only(args.results)
    ensure_python(args)
    work = os.path.abspath(args.work)
    if os.path.commonpath([work, REPO]) == REPO:
        raise SystemExit("--work must be outside the repository (the capture must not be copied into it)")
    exe = os.path.abspath(args.bin)
    if args.redo:
        for sub in ("colmap_capture", "colmap_record.json", "runs", "radial_check"):
            p = os.path.join(work, sub)
            if os.path.isdir(p):
                shutil.rmtree(p)
            elif os.path.exists(p):
                os.remove(p)
    os.makedirs(work, exist_ok=True)
    log = os.path.join(work, "bench.log")
    started = datetime.datetime.now().isoformat(timespec="seconds")
    tree = tree_state()

    photos = make_photos(args.data, os.path.join(work, "photos"))
    photo_width = photos["sizes"][0][0]
    print(f"from_photos: {photos['count']} photos -> {photos['folder']}", flush=True)
    out = os.path.join(work, "colmap_capture")
    colmap = run_colmap(exe, photos["folder"], out, work, photos["count"])
    print(f"from_photos: COLMAP registered {colmap.get('images')} of {photos['count']} in "
          f"{colmap['wall_seconds']:.0f} s, layout {colmap.get('layout')}", flush=True)
    poses = compare_poses(args.data, out, photo_width)
    print(f"from_photos: rotation error median {poses['rotation_error_deg']['median']:.3f} deg, position "
          f"{poses['position_error_of_extent']['median'] * 100:.2f} % of extent", flush=True)

    given = given_capture(args.data, photos["folder"], os.path.join(work, "given"))
    captures = {"colmap": {"data": out, "settings": {}},
                "given": {"data": given, "settings": {"factor": 8}}}
    runs = {name: [] for name in captures}
    for seed in range(args.seeds):
        for name, capture in captures.items():
            settings = {"steps": args.steps, "val_every": args.val_every, "val_views": args.val_views, "seed": seed,
                        **capture["settings"]}
            r = train_and_eval(exe, capture["data"], os.path.join(work, "runs", f"{name}_seed{seed}"), args.preset,
                               settings, log)
            r["seed"] = seed
            runs[name].append(r)
            print(f"from_photos: {name} seed {seed}: test PSNR {r['test_psnr']:.2f} dB, SSIM {r['test_ssim']:.4f}, "
                  f"{r['train_seconds']:.0f} s", flush=True)
    radial = None
    if args.radial_check:
        radial = radial_check(args.data, photos["folder"], out, work, photo_width)
        print(f"from_photos: SIMPLE_RADIAL check: focal {radial['camera']['params'][0]:.2f}, k "
              f"{radial['camera']['params'][3]:.4f}", flush=True)
    same_views = ([photo_name(f) for f in runs["colmap"][0]["test_files"]]
                  == [photo_name(f) for f in runs["given"][0]["test_files"]])

    record = {
        "date": datetime.date.today().isoformat(), "started": started,
        "finished": datetime.datetime.now().isoformat(timespec="seconds"),
        "tree": tree, "executable": exe, "executable_sha256": file_sha256(exe),
        "executable_mtime": datetime.datetime.fromtimestamp(os.path.getmtime(exe)).isoformat(timespec="seconds"),
        "colmap_version": colmap_version(),
        "machine": {"cpu": cpu_model(), "cores": os.cpu_count(), "python": sys.version.split()[0]},
        "command": (f"python3 bench/studies/from_photos.py --data {args.data} --bin {args.bin} --steps {args.steps} "
                    f"--seeds {args.seeds} --preset {args.preset} --work {args.work}"),
        "data": args.data, "preset": args.preset, "steps": args.steps, "seeds": args.seeds,
        "val_every": args.val_every, "val_views": args.val_views,
        "photos": photos, "colmap": colmap, "poses": poses, "runs": runs,
        "same_held_out_views": same_views, "radial_check": radial,
    }
    os.makedirs(args.results, exist_ok=True)
    with open(os.path.join(args.results, "from_photos.json"), "w") as f:
        json.dump(record, f, indent=2)
        f.write("\n")
    print(write_report(record, args.results))


# ---- the report ----

def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else float("nan")


def fmt_phase(p):
    return (f"{p['wall_seconds']:,.0f} s wall; load {p['load_before'][0]:.1f} → {p['load_after'][0]:.1f}; "
            f"ours {p['own_cores']:.2f} cores, other processes {p['other_cores']:.2f} cores")


def write_markdown(record):
    """The report, generated from from_photos.json alone."""
    colmap, poses, runs, photos = record["colmap"], record["poses"], record["runs"], record["photos"]
    tree = record["tree"]
    focal = poses["focal"]
    fit = poses["fit"]
    dirty = (f"**dirty** ({len(tree['dirty_paths'])} tracked files differ from HEAD; diff sha256 "
             f"{tree.get('diff_sha256', '?')[:16]}…)" if tree["dirty"] else "clean")
    registered = colmap.get("images")
    by_near = sorted(poses["views"], key=lambda v: v["colmap_bounds_fitted"][0])
    nearest = by_near[0]
    second_near = by_near[1]["colmap_bounds_fitted"][0] if len(by_near) > 1 else float("nan")
    lines = [
        "# From photos: COLMAP's cameras against the capture's own, on the real flower capture",
        "",
        report_md.generated_banner("bench/studies/from_photos.py", "from_photos.json"),
        "",
        f"Date {record['date']} (run {record['started']} → {record['finished']}). Commit `{tree['commit']}`, tree "
        f"{dirty}. Executable `{record['executable']}` (sha256 {record['executable_sha256'][:16]}…, built "
        f"{record['executable_mtime']}). {record['colmap_version']}.",
        f"Machine: {record['machine']['cpu']}, {record['machine']['cores']} cores, shared with other work "
        "(the load and other processes' CPU per phase are below).",
        "",
        f"Command: `{record['command']}`",
        "",
        f"Data: `{record['data']}` (LLFF flower: {photos['count']} handheld-phone photos at "
        f"{'×'.join(map(str, photos['sizes'][0]))}, images_8/, with the capture's own poses_bounds.npy). The PNGs "
        f"were saved as {photos['format']} into a work folder outside the repository; both trainings read those "
        "JPEGs.",
        "",
        "## Registration (`mipnerf-cl dataset from-photos PHOTOS OUT`, defaults)",
        "",
    ]
    lines += report_md.table(
        ["photos", "registered", "layout", "sparse points", "cameras", "COLMAP wall s", "mean reprojection error (px)",
         "mean track length"], "rrlrlrrr",
        [[str(photos["count"]), str(registered), str(colmap.get("layout")), f"{colmap.get('points', 0):,}",
          f"{colmap.get('cameras')} ({colmap.get('camera_models')})", f"{colmap['wall_seconds']:,.0f}",
          f"{colmap.get('model_analyzer', {}).get('mean_reprojection_error', float('nan')):.3f}",
          f"{colmap.get('model_analyzer', {}).get('mean_track_length', float('nan')):.2f}"]])
    lines += [
        "",
        "COLMAP's steps (their own elapsed times): "
        + ", ".join(f"{s['step']} {s['seconds']:,.0f} s" for s in colmap.get("colmap_steps", []))
        + f". The whole command: {fmt_phase(colmap)}.",
        f"Layout reason: {colmap.get('layout_reason')}.",
    ]
    if registered is not None and registered < photos["count"]:
        lines += ["", f"**COLMAP registered {registered} of {photos['count']} photos**; not registered: "
                      f"{', '.join(poses['unregistered'])}. Everything below uses the registered ones."]
    lines += [
        "",
        "## COLMAP's cameras against the given ones",
        "",
        f"{poses['matched_views']} views matched by photo name. A similarity (Umeyama) fitted from COLMAP's camera "
        f"centres to the given centres (scale {fit['scale']:.4g} given units per COLMAP unit, rotation "
        f"{fit['rotation_angle_deg']:.1f}°). Rotation error: the angle of R_given·(R_fit·R_colmap)ᵀ, camera-to-world "
        "rotations in OpenGL axes. Position error: |given centre − fitted COLMAP centre| after the fit, as a "
        f"fraction of the capture's extent (the largest distance between two given centres, {poses['extent']:.3g} "
        "given units).",
        "",
    ]
    errors = [("rotation error (°)", poses["rotation_error_deg"], 1, ".3f"),
              ("position error (% of extent)", poses["position_error_of_extent"], 100, ".2f"),
              ("rotation error with the rotation fitted to the orientations instead (°)",
               poses["rotation_error_deg_orientation_fit"], 1, ".3f")]
    lines += report_md.table(["", "median", "max"], "lrr",
                             [[name, f"{e['median'] * scale:{form}}", f"{e['max'] * scale:{form}}"]
                              for name, e, scale, form in errors])
    lines += [
        "",
        f"(The last row's rotation differs from the centre fit's by "
        f"{poses['rotation_error_deg_orientation_fit']['fit_vs_centre_fit_deg']:.3f}°.)",
        "",
    ]
    lines += report_md.table(["focal length", "px"], "lr", [
        [f"COLMAP (SIMPLE_PINHOLE, at {focal['colmap_hw'][1]:.0f}×{focal['colmap_hw'][0]:.0f})",
         f"{focal['colmap_px']:.2f}"],
        [f"given ({focal['given_px_full']:.2f} at {focal['given_hw_full'][1]:.0f}×{focal['given_hw_full'][0]:.0f}, "
         f"scaled to {focal['photo_width']} wide)", f"{focal['given_px_at_photo_width']:.2f}"],
        ["difference", f"{focal['relative_difference'] * 100:+.2f} %"]])
    lines += [
        "",
        f"Depth bounds (COLMAP's × the fit's scale, against the given): nearest "
        f"{poses['bounds']['colmap_fitted_min_near']:.2f} vs {poses['bounds']['given_min_near']:.2f}, farthest "
        f"{poses['bounds']['colmap_fitted_max_far']:.2f} vs {poses['bounds']['given_max_far']:.2f}; per view the "
        f"median ratio is {poses['bounds']['near_ratio_median']:.3f} (near) and "
        f"{poses['bounds']['far_ratio_median']:.3f} (far). The LLFF loader scales each capture so that its nearest "
        "bound is 4/3 and NDC starts at depth 1, so a different nearest bound gives a differently scaled NDC scene.",
        "",
        f"The nearest COLMAP bound is view {nearest['name']}'s: {nearest['colmap_bounds_fitted'][0]:.2f} (fitted) "
        f"against {nearest['given_bounds'][0]:.2f} given for that view; the nearest bound of the other views is "
        f"{second_near:.2f}.",
        "",
        "Worst views by rotation error:",
        "",
    ]
    worst = sorted(poses["views"], key=lambda v: -v["rotation_error_deg"])[:5]
    lines += report_md.table(["view", "rotation error (°)", "position error (% of extent)"], "lrr",
                             [[v["name"], f"{v['rotation_error_deg']:.3f}", f"{v['position_error_of_extent'] * 100:.2f}"]
                              for v in worst])

    radial = record.get("radial_check")
    if radial:
        rc = radial["comparison"]
        cam = radial["camera"]
        lines += [
            "",
            "### Diagnostic: the same matches mapped with a radial-distortion camera",
            "",
            f"{radial['what']}. Registered {radial['registered']} of {photos['count']}; mapper "
            f"{radial['mapper_phase']['wall_seconds']:,.0f} s wall.",
            "",
        ]

        def camera_row(name, fit, k):
            # `fit`: a comparison shaped like radial["comparison"] (focal, rotation and position errors).
            return [name, f"{fit['focal']['colmap_px']:.2f}", f"{fit['focal']['relative_difference'] * 100:+.2f} %", k,
                    f"{fit['rotation_error_deg']['median']:.3f} / {fit['rotation_error_deg']['max']:.3f}",
                    f"{fit['rotation_error_deg_orientation_fit']['median']:.3f} / "
                    f"{fit['rotation_error_deg_orientation_fit']['max']:.3f}",
                    f"{fit['position_error_of_extent']['median'] * 100:.2f} / "
                    f"{fit['position_error_of_extent']['max'] * 100:.2f}"]
        lines += report_md.table(
            ["camera", "focal (px at 504 wide)", "vs given", "k (radial)", "rotation error median / max (°)",
             "same, rotation fitted to orientations (°)", "position error median / max (% of extent)"], "lrrrrrr",
            [camera_row("SIMPLE_PINHOLE (from-photos)", dict(poses, focal=focal), "—"),  # the main run's, same shape
             camera_row(cam["model"], rc, f"{cam['params'][3]:+.4f}")])

    colmap_runs, given_runs = runs["colmap"], runs["given"]
    held = ", ".join(photo_name(f) for f in colmap_runs[0]["test_files"])
    held_given = ", ".join(photo_name(f) for f in given_runs[0]["test_files"])
    lines += [
        "",
        f"## mip-NeRF at equal steps: COLMAP's poses against the given poses",
        "",
        f"Preset `{record['preset']}`, {record['steps']:,} steps, seeds 0..{record['seeds'] - 1}, val every "
        f"{record['val_every']} steps on {record['val_views']} view(s) (timed apart from training). Both are LLFF "
        f"captures: `{colmap_runs[0]['scene_effects']}`. COLMAP's capture trains from OUT/images/ (factor 1); the "
        "given one from a folder with the given poses_bounds.npy unchanged and images_8/ = the same JPEGs "
        "(`--set factor=8`: the loader takes images_8/ and the focal length / 8, as the official loader does), so "
        f"both train on the same {'×'.join(map(str, colmap_runs[0]['test_size'] or []))} JPEG pixels. Test: "
        "`mipnerf-cl eval --checkpoint RUN`, each capture's held-out views (every 8th image in its own order).",
        "",
        f"Held-out views: COLMAP's capture {held}; given capture {held_given} — "
        + ("**the same views**." if record["same_held_out_views"] else "**not the same views** (registration "
                                                                      "changed the order or dropped photos)."),
        "",
    ]

    def curve(r):
        return ", ".join(f"{int(float(row['step']))}: {float(row['val_psnr']):.2f}"
                         for row in r["val_log"] if "val_psnr" in row and "step" in row) or "—"

    rows = [[label, str(r["seed"]), f"{r['steps']:,}", f"{r['train_seconds']:,.0f}", f"{r['test_psnr']:.2f}",
             f"{r['test_ssim']:.4f}", f"{r['render_s_per_mp']:,.0f}", curve(r)]
            for label, rs in (("COLMAP (from-photos)", colmap_runs), ("given (poses_bounds.npy)", given_runs))
            for r in rs]
    if record["seeds"] > 1:
        rows += [[label, "", f"{rs[0]['steps']:,}", f"{mean(r['train_seconds'] for r in rs):,.0f}",
                  f"{mean(r['test_psnr'] for r in rs):.2f}", f"{mean(r['test_ssim'] for r in rs):.4f}",
                  f"{mean(r['render_s_per_mp'] for r in rs):,.0f}", ""]
                 for label, rs in (("COLMAP, mean", colmap_runs), ("given, mean", given_runs))]
    lines += report_md.table(["poses", "seed", "steps", "train s", "test PSNR (dB)", "test SSIM", "render s/MP",
                              "val PSNR by step"], "lrrrrrrl", rows)
    gap = mean(r["test_psnr"] for r in colmap_runs) - mean(r["test_psnr"] for r in given_runs)
    lines += [
        "",
        f"PSNR, COLMAP's poses minus the given poses: {gap:+.2f} dB.",
        "",
        "Per held-out view (test PSNR dB, seed 0):",
        "",
    ]
    given_by_name = {photo_name(v["file"]): v for v in given_runs[0]["test_per_view"]}

    def given_psnr(v):
        g = given_by_name.get(photo_name(v["file"]))
        return f"{g['psnr']:.2f}" if g else "—"
    lines += report_md.table(["view", "COLMAP's poses", "given poses"], "lrr",
                             [[photo_name(v["file"]), f"{v['psnr']:.2f}", given_psnr(v)]
                              for v in colmap_runs[0]["test_per_view"]])
    lines += ["", "Conditions per phase:", ""]
    lines.append(f"- from-photos: {fmt_phase(colmap)}")
    for label, rs in (("COLMAP", colmap_runs), ("given", given_runs)):
        for r in rs:
            lines.append(f"- train {label} seed {r['seed']}: {fmt_phase(r['train_phase'])}; eval: "
                         f"{fmt_phase(r['eval_phase'])}")
    lines += [
        "",
        "Train seconds are the run's own (summary.json: training steps, val renders excluded); render s/MP is "
        "eval's over the held-out views. Both depend on the load, which other work on the machine set.",
    ]
    return "\n".join(lines) + "\n"


def write_report(record, results):
    path = os.path.join(results, "from_photos.md")
    return report_md.write_report(path, write_markdown(record),
                                  f"python3 bench/studies/from_photos.py --report-only --results {results}")


def report_only(results):
    record = read_json(os.path.join(results, "from_photos.json"))
    write_report(record, results)
    print(f"from_photos: wrote {results}/from_photos.md from from_photos.json")


if __name__ == "__main__":
    main()
