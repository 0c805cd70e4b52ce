#!/usr/bin/env python3
"""COLMAP's own lens models as test vectors (tests/official/fixtures/colmap_lenses.json).

Run by hand, never by the test suite: it needs pycolmap (PyPI), COLMAP's Python bindings, whose camera models are
COLMAP's C++ code. For each lens model mipnerf-cl reads (the rows of core/lens_models.cpp that take coefficients:
SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE, FULL_OPENCV) on a 640x480 camera with realistic coefficients, it
records for random image positions (and every pixel centre of a coarse grid) COLMAP's cam_from_img (the undistorted
normalised coordinates the ray goes through) and, for random normalised points, img_from_cam (the forward model). tests/official/test_lenses.cpp compares core/lens.hpp and the ray kernel
with them.

    python3 -m venv /tmp/pycolmap-venv && /tmp/pycolmap-venv/bin/pip install pycolmap numpy
    /tmp/pycolmap-venv/bin/python tests/official/make_lens_vectors.py --out tests/official/fixtures/colmap_lenses.json
"""
import argparse
import json

import numpy as np
import pycolmap

CAMERAS = [
    ("SIMPLE_RADIAL", [500.0, 320.0, 240.0, -0.08]),
    ("RADIAL", [500.0, 320.0, 240.0, -0.12, 0.03]),
    ("OPENCV", [510.0, 495.0, 318.5, 243.25, -0.15, 0.04, 0.0012, -0.0008]),
    ("OPENCV_FISHEYE", [230.0, 228.0, 320.0, 240.0, 0.05, -0.01, 0.002, -0.0004]),
    # k1, k2, p1, p2, k3, k4, k5, k6: a wide lens's rational radial profile (OpenCV's CALIB_RATIONAL_MODEL).
    ("FULL_OPENCV", [505.0, 498.0, 321.0, 238.5, -0.28, 0.09, 0.0009, -0.0006, -0.012, 0.05, -0.01, 0.002]),
]
WIDTH, HEIGHT = 640, 480


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    rng = np.random.default_rng(20261125)
    cameras = []
    for model, params in CAMERAS:
        camera = pycolmap.Camera(model=model, width=WIDTH, height=HEIGHT, params=params)
        pixels = np.concatenate([
            rng.uniform([0, 0], [WIDTH, HEIGHT], size=(200, 2)),
            np.stack(np.meshgrid(np.arange(0.5, WIDTH, 40.0), np.arange(0.5, HEIGHT, 40.0)), -1).reshape(-1, 2),
            [[0.5, 0.5], [WIDTH - 0.5, HEIGHT - 0.5], [0.5, HEIGHT - 0.5], [WIDTH - 0.5, 0.5]],
        ])
        undistorted = camera.cam_from_img(pixels)
        points = rng.uniform(-0.6, 0.6, size=(100, 2))
        projected = camera.img_from_cam(np.concatenate([points, np.ones((len(points), 1))], 1))
        cameras.append({
            "model": model,
            "params": params,
            "width": WIDTH,
            "height": HEIGHT,
            "pixels": pixels.tolist(),
            "cam_from_img": np.asarray(undistorted).tolist(),
            "points": points.tolist(),
            "img_from_cam": np.asarray(projected).tolist(),
        })
    with open(args.out, "w", encoding="utf-8") as f:
        json.dump({"generator": "tests/official/make_lens_vectors.py", "pycolmap": pycolmap.__version__,
                   "cameras": cameras}, f, indent=None)
        f.write("\n")


if __name__ == "__main__":
    main()
