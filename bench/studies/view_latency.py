#!/usr/bin/env python3
"""How long `mipnerf-cl view` takes to show a new viewpoint: its progressive render's time to the first frame (1/8
of the size) and to the full-size frame, per preset. Writes bench/results/view_latency/view_latency_<tag>.{json,md}.

  python3 bench/studies/view_latency.py --bin BUILD/mipnerf-cl [--size 128] [--rounds 5] [--presets tiny,quick,small,paper]
      [--tag pocl_cpu] [--note "..."] [--work /tmp/view_latency]
  python3 bench/studies/view_latency.py --report-only [--tag pocl_cpu]      (the .md again from the .json)

For each preset: a procedural scene of SIZE x SIZE images, a run trained 2 steps (a render's cost depends on the
network and the samples, not on the weights), `view` on a free port, then ROUNDS new viewpoints (an orbit step each),
each requested as the page does: 1/8, 1/4, 1/2, full size one after another, each a full mip-NeRF render at that
size. Measured per viewpoint from the client (HTTP round trip, PNG included): the first frame's seconds and the
seconds until the full-size frame arrived; medians with their ranges. The first viewpoint after start-up is one of
the rounds (the viewer warms the kernels up before it listens).
"""
import argparse
import datetime
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.provenance import REPO, commit_of  # noqa: E402
from lib.run import RunError, run  # noqa: E402

DIVISORS = [8, 4, 2, 1]


def post(url, body):
    request = urllib.request.Request(url, data=json.dumps(body).encode(), headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(request, timeout=600) as response:
        return response.read(), response.headers


def orbit_camera(frame, target, radius, elevation_deg, azimuth_deg):
    """The page's orbit camera (host/view/viewer.html), for up = +z: a look-at pose as a camera path frame."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    eye = [target[0] + radius * math.cos(e) * math.cos(a), target[1] + radius * math.cos(e) * math.sin(a),
           target[2] + radius * math.sin(e)]
    z = [eye[i] - target[i] for i in range(3)]
    n = math.sqrt(sum(v * v for v in z))
    z = [v / n for v in z]
    x = [-z[1], z[0], 0.0]  # up × z with up = +z
    n = math.sqrt(sum(v * v for v in x))
    x = [v / n for v in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    pose = [[x[r], y[r], z[r], eye[r]] for r in range(3)] + [[0, 0, 0, 1]]
    return {"frames": [dict(frame, transform_matrix=pose)]}


def measure_preset(args, preset, work):
    scene, run_dir = os.path.join(work, "scene"), os.path.join(work, f"run_{preset}")
    if not os.path.exists(os.path.join(scene, "transforms_train.json")):
        run([args.bin, "make-scene", scene, "--size", str(args.size), "--views", "8"])
    shutil.rmtree(run_dir, ignore_errors=True)
    run([args.bin, "train", "--data", scene, "--out", run_dir, "--preset", preset, "--steps", "2",
         "--set", "val_every=0", "--set", "val_views=1", "--set", "log_every=1"])
    view = subprocess.Popen([args.bin, "view", run_dir, "--port", "0"], stdout=subprocess.PIPE, text=True)
    started = time.monotonic()
    line = view.stdout.readline()
    ready_seconds = time.monotonic() - started
    match = re.search(r"at (http://127\.0\.0\.1:\d+/) ?", line)
    if not match:
        view.kill()
        sys.exit(f"view_latency: view printed {line!r}")
    base = match.group(1)
    device = re.search(r"on (.*)\) at", line).group(1)
    try:
        with urllib.request.urlopen(base + "api/cameras", timeout=60) as r:
            orbit = json.load(r)["orbit"]
        rounds, generation = [], 0
        for k in range(args.rounds):
            camera = orbit_camera(orbit["frame"], orbit["target"], orbit["radius"], orbit["elevation_deg"], 15.0 * k)
            t0, frames = time.monotonic(), []
            for divisor in DIVISORS:
                generation += 1
                _, headers = post(base + "api/render", {"camera": camera, "divisor": divisor, "generation": generation})
                frames.append({"divisor": divisor, "size": headers["X-Render-Size"],
                               "render_seconds": float(headers["X-Render-Seconds"]),
                               "client_seconds": time.monotonic() - t0})
            rounds.append(frames)
    finally:
        view.terminate()
        view.wait(timeout=30)
    first = [r[0]["client_seconds"] for r in rounds]
    full = [r[-1]["client_seconds"] for r in rounds]
    return {"preset": preset, "device": device, "start_seconds": ready_seconds, "sizes": [f["size"] for f in rounds[0]],
            "first_frame_seconds": summary(first), "full_size_seconds": summary(full), "rounds": rounds}


def summary(values):
    return {"median": statistics.median(values), "min": min(values), "max": max(values), "n": len(values)}


def markdown(result):
    lines = ["# `mipnerf-cl view`: time to the first frame and to full size", "",
             f"Measured {result['date']} on {result['device']}, commit {result['commit']}; "
             f"`{result['command']}`.", ""]
    if result.get("note"):
        lines += [f"**Note:** {result['note']}", ""]
    lines += [f"Per preset: {result['rounds']} new viewpoints, each rendered 1/8 → 1/4 → 1/2 → full size "
              f"({result['size']}x{result['size']}) one after another as the page asks; seconds from the request "
              "of the viewpoint's first frame, measured by the client (HTTP and PNG included); median (min–max). "
              f"The quick preset's target for the first frame: ≤ 0.3 s.", ""]
    fmt = lambda s: f"{s['median']:.3f} ({s['min']:.3f}–{s['max']:.3f})"
    lines += report_md.table(["preset", "sizes", "first frame (s)", "full size (s)", "view start-up incl. warm-up (s)"],
                             "llrrr", [[p["preset"], " → ".join(p["sizes"]), fmt(p["first_frame_seconds"]),
                                        fmt(p["full_size_seconds"]), f"{p['start_seconds']:.1f}"]
                                       for p in result["presets"]])
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", default=os.path.join(REPO, "build", "mipnerf-cl"))
    parser.add_argument("--size", type=int, default=128)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--presets", default="tiny,quick,small,paper")
    parser.add_argument("--tag", default="pocl_cpu")
    parser.add_argument("--note", default="")
    parser.add_argument("--work", default="/tmp/view_latency")
    parser.add_argument("--report-only", action="store_true")
    args = parser.parse_args()
    out = os.path.join(report_md.results_folder("view_latency"), f"view_latency_{args.tag}")
    if not args.report_only:
        os.makedirs(args.work, exist_ok=True)
        presets = [measure_preset(args, p, args.work) for p in args.presets.split(",")]
        commit = commit_of(REPO)
        result = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                  "device": presets[0]["device"], "commit": commit, "size": args.size, "rounds": args.rounds,
                  "command": "python3 bench/studies/view_latency.py " + " ".join(sys.argv[1:]), "note": args.note,
                  "presets": presets}
        with open(out + ".json", "w") as f:
            json.dump(result, f, indent=1)
            f.write("\n")
    with open(out + ".json") as f:
        result = json.load(f)
    with open(out + ".md", "w") as f:
        f.write(markdown(result))
    print(markdown(result))


if __name__ == "__main__":
    try:
        main()
    except RunError as e:
        sys.exit(f"view_latency: {e}")
