#!/usr/bin/env python3
"""Unbounded 360-degree scenes: Zip-NeRF with contraction against today's spherified world rays, at equal training time.

Issue 45's bar: on a 360-degree capture, the contracted model beats what `train` did before it (spherified poses,
world rays between the capture's near and far bounds, the grid's cube [-1.5, 1.5]^3) on held-out views at equal
training time, over 3 seeds. The capture is the tool's own: `make-scene --unbounded` (a procedural scene on an endless
checkered ground with pillars 6 to 40 units away and a sky, from a full orbit of 40 cameras; its held-out views are
every 8th, as the LLFF loader holds them out), trained at `--set factor=4` (64x48). The models, each through the
command-line tool with `train --minutes M` (the step count fixed by the tool's timed warm-up and recorded):
  - sph: Zip-NeRF fast as a 360-degree capture trains without the option (spherified, coarse/fine resampling);
  - prop: the same with proposal sampling (sampler=proposal), still bounded: what proposal sampling alone buys;
  - unb: proposal sampling with `unbounded=true`: the contraction into [-2, 2]^3 and the power ladder from 0 to 1e6;
  - mip: mip-NeRF quick (spherified), the paper's model.
Each is trained for every seed and scored by `eval` on the val views (PSNR, SSIM, render time). The table holds the
mean and sample standard deviation over seeds, and each seed's PSNR. Finished runs and scores in --work are reused.

  /usr/bin/python3 bench/studies/unbounded.py --minutes 4 --seeds 0,1,2
  python3 bench/studies/unbounded.py --report-only
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import (UNBOUNDED_SCENE, add_budget_arguments, budget_markdown, measure_budget,  # noqa: E402
                          unbounded_scene)

RESULTS = report_md.results_folder("unbounded")
SCRIPT = "bench/studies/unbounded.py"
# (key, label, train arguments)
MODELS = [
    ("sph", "Zip-NeRF fast, spherified world rays (the 360° default before)", "--model zipnerf --preset fast"),
    ("prop", "Zip-NeRF fast + proposal sampling, bounded", "--model zipnerf --preset fast --set sampler=proposal"),
    ("unb", "Zip-NeRF fast + proposal + unbounded (contraction, power ladder)",
     "--model zipnerf --preset fast --set sampler=proposal --set unbounded=true"),
    ("mip", "mip-NeRF quick, spherified world rays", "--preset quick"),
]


def add_arguments(parser):
    add_budget_arguments(parser, "/tmp/mipnerf-unbounded", 4.0, 4, "4: 64x48", "the capture holds out 5",
                         [m[0] for m in MODELS])


def measure(args):
    return measure_budget(args, "unbounded", RESULTS, MODELS, unbounded_scene, UNBOUNDED_SCENE)


def write_markdown(record):
    return budget_markdown(record, SCRIPT, "unbounded.json",
                           "Unbounded 360° scenes: contraction against spherified world rays, at equal training time",
                           [("Contracted minus spherified", "unb", "sph")])


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "unbounded", SCRIPT, add_arguments, measure, write_markdown)
