#!/usr/bin/env python3
"""Times the official google/mipnerf training step at the paper's configuration on the device JAX runs on.

For scripts/device-check.sh (docs/devices.md): on a lent GPU it runs with the image's JAX, once with JAX's default
matmul precision (on NVIDIA GPUs since Ampere, float32 products run in TF32) and once with
jax_default_matmul_precision = 'float32' (full float32 products), each in its own process:

  python3 bench/studies/official_step.py --official DIR --data SCENE --precision default --steps 10 \\
      --our-bench BENCH_JSON --out official_default.json

It reuses the official-code module of the studies (bench/lib/official.py) (the official model built by construct_mipnerf, train.train_step
pmapped over the local devices as train.py does, Adam behind a flax.optim stand-in, random rays over every training
image of a Blender scene; the XLA compile and two warm-up steps are not timed; each timed step ends with
block_until_ready). The settings are our paper preset's, read from the training record of a `mipnerf-cl bench`
bench.json (--our-bench; the parameter counts must agree), else the official code's own defaults, which are the
paper's. --data is a Blender scene folder (`mipnerf-cl make-scene DIR`); without one, --synthetic-scene writes a
scene of random images to time the step on (the step's cost does not depend on what the pixels hold).
Writes one JSON record (--out) and prints one line; exits non-zero when the step could not be timed or the parameter
counts differ. Standard library and the official code's own dependencies only; the official checkout is only read.
"""

import argparse
import json
import os
import platform
import statistics
import sys
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/

PRECISIONS = {"default": None, "float32": "float32"}


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--official", required=True, help="checkout of github:google/mipnerf (train.py, internal/)")
    p.add_argument("--data", help="Blender scene folder (transforms_train.json, train/*.png)")
    p.add_argument("--synthetic-scene", metavar="DIR",
                   help="write a Blender scene of random images here and time on it (when there is no --data)")
    p.add_argument("--precision", choices=sorted(PRECISIONS), default="default",
                   help="default: JAX's default matmul precision (TF32 on NVIDIA GPUs); float32: full float32")
    p.add_argument("--steps", type=int, default=10, help="timed steps after the compile and warm-up (>= 1)")
    p.add_argument("--our-bench", help="bench.json of `mipnerf-cl bench --presets paper`: our settings and parameters")
    p.add_argument("--batch", type=int, help="rays per step (default: our bench's batch_size, else 4096)")
    p.add_argument("--out", required=True, help="the JSON record written")
    args = p.parse_args(argv)
    if args.steps < 1:
        p.error("--steps must be at least 1")
    if not os.path.isfile(os.path.join(args.official, "internal", "models.py")):
        p.error(f"--official {args.official}: no internal/models.py there; pass the google/mipnerf checkout")
    if not args.data and not args.synthetic_scene:
        p.error("pass --data SCENE (mipnerf-cl make-scene) or --synthetic-scene DIR")
    return args


def write_synthetic_scene(folder, views=40, size=64, seed=0):
    """A Blender-format scene of random RGBA images seen from cameras around the origin at radius 4 (as our
    procedural scene's), enough to time a step: its cost depends on the rays' count, not the pixels."""
    import numpy as np
    from PIL import Image
    rng = np.random.RandomState(seed)
    os.makedirs(os.path.join(folder, "train"), exist_ok=True)
    frames = []
    for i in range(views):
        azimuth, elevation = rng.uniform(0, 2 * np.pi), rng.uniform(0.1, 1.2)
        eye = 4.0 * np.array([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                              np.sin(elevation)])
        back = eye / np.linalg.norm(eye)  # the camera looks down its -z axis, at the origin
        right = np.cross([0.0, 0.0, 1.0], back)
        right /= np.linalg.norm(right)
        up = np.cross(back, right)
        pose = np.eye(4)
        pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = right, up, back, eye
        pixels = (rng.uniform(size=(size, size, 4)) * 255).astype(np.uint8)
        Image.fromarray(pixels, "RGBA").save(os.path.join(folder, "train", f"r_{i}.png"))
        frames.append({"file_path": f"./train/r_{i}", "transform_matrix": pose.tolist()})
    with open(os.path.join(folder, "transforms_train.json"), "w") as f:
        json.dump({"camera_angle_x": 0.6911112070083618, "frames": frames}, f)
    return folder


def our_settings(path):
    """Our paper preset's training config and parameter count from a bench.json, or (None, None)."""
    if not path or not os.path.isfile(path):
        return None, None
    with open(path) as f:
        record = json.load(f)
    for device in record.get("devices", []):
        for training in device.get("training", []):
            if training.get("preset") == "paper" and training.get("config"):
                return training["config"], training.get("parameters")
    return None, None


def main(argv):
    args = parse_args(argv)
    result = {"tool": "bench/studies/official_step.py", "precision": args.precision, "argv": argv,
              "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    status = 1
    try:
        status = measure(args, result)
    except Exception as e:
        traceback.print_exc()
        result["error"] = repr(e)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1)
    if "median_s" in result:
        print(f"official step, {args.precision} precision, {result['batch_rays']} rays: median "
              f"{result['median_s'] * 1e3:.1f} ms/step ({result['rays_per_s']:.0f} rays/s) over {args.steps} steps on "
              f"{result['jax']['device_kind']}; compile + 2 warm-up steps {result['compile_s']:.1f} s")
    return status


def measure(args, result):
    import jax
    if PRECISIONS[args.precision]:
        jax.config.update("jax_default_matmul_precision", PRECISIONS[args.precision])
    result["jax_default_matmul_precision"] = str(jax.config.jax_default_matmul_precision)
    devices = jax.devices()
    result["jax"] = {"version": jax.__version__, "backend": jax.default_backend(), "devices": [str(d) for d in devices],
                     "device_kind": devices[0].device_kind, "python": platform.python_version()}
    from lib import official as official_code  # Official, official_settings (standard library at import)

    data = args.data
    if not data or not os.path.isfile(os.path.join(data, "transforms_train.json")):
        data = write_synthetic_scene(args.synthetic_scene)
        result["scene"] = "synthetic: 40 random 64x64 images"
    else:
        result["scene"] = data
    official = official_code.Official(args.official, data, 1)
    result["shims"] = list(official_code.INSTALLED_COMPAT_SHIMS)
    result["versions"] = official.versions()
    result["stubs"] = [name for name, _ in official_code.STUBS]

    our_config, our_parameters = our_settings(args.our_bench)
    if our_config:
        model, mlp, config = official_code.official_settings(our_config)
        result["settings"] = "our paper preset's, from " + os.path.basename(args.our_bench)
    else:  # the official defaults are the paper's (MipNerfModel, MLP and Config)
        model, mlp, config = {}, {}, {"batching": "all_images"}
        result["settings"] = "the official code's defaults (the paper's): no bench.json of ours was given or readable"
    if args.batch:
        config["batch_size"] = args.batch
    config.setdefault("batch_size", 4096)
    result.update({"official_model": model, "official_mlp": mlp, "official_config": config,
                   "batch_rays": config["batch_size"]})

    setup = official.setup(model, mlp, config)
    result["compile_s"] = setup["compile_s"]
    result["parameters"] = {"official": setup["parameters"], "mipnerf-cl": our_parameters}
    seconds = official.steps(args.steps)
    median = statistics.median(seconds)
    result.update({"step_seconds": seconds, "median_s": median, "min_s": min(seconds), "max_s": max(seconds),
                   "rays_per_s": config["batch_size"] / median})
    if our_parameters is not None and our_parameters != setup["parameters"]:
        result["error"] = f"parameter counts differ: official {setup['parameters']}, mipnerf-cl {our_parameters}"
        print(f"official_step.py: {result['error']}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
