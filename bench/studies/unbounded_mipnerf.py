#!/usr/bin/env python3
"""Unbounded 360-degree scenes with the mip-NeRF model: mip-NeRF 360's contracted IPE against today's spherified world
rays, at equal training time.

Issue 45's bar for mip-NeRF 360's own model: on a 360-degree capture, the contracted model beats what `train` does
without it (spherified poses, world rays between the capture's near and far bounds, coarse/fine resampling) on held-out
views at equal training time, over 3 seeds. The capture is the tool's own, as bench/studies/unbounded.py's:
`make-scene --unbounded` (a procedural scene on an endless checkered ground with pillars 6 to 40 units away and a sky,
from a full orbit of 40 cameras; every 8th view held out), trained at `--set factor=4` (64x48). The models, each
through the command-line tool with `train --minutes M` (the step count fixed by the tool's timed warm-up, recorded):
  - mip: mip-NeRF quick as a 360-degree capture trains it without options (spherified, coarse/fine resampling);
  - m360: mip-NeRF quick as mip-NeRF 360 (multinerf configs/360.gin's model at the quick preset's size): proposal
    sampling (two rounds of 64 on density-only 4x64 MLPs, the outer interlevel loss, the dilation, the distortion loss
    0.01), every level's frustums through the contraction and encoded on the icosahedron's 21 directions (degrees
    0..11: 504 features), s spaced by the reciprocal from near 0.2 to far 1e6;
  - m360_32: the same with rounds of 32 (fewer encodings a step).
Each is trained for every seed and scored by `eval` on the val views (PSNR, SSIM, render time). The table holds the
mean and sample standard deviation over seeds, and each seed's PSNR. Finished runs and scores in --work are reused.

  /usr/bin/python3 bench/studies/unbounded_mipnerf.py --minutes 4 --seeds 0,1,2
  python3 bench/studies/unbounded_mipnerf.py --report-only
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import (UNBOUNDED_SCENE, add_budget_arguments, budget_markdown, measure_budget,  # noqa: E402
                          unbounded_scene)

RESULTS = report_md.results_folder("unbounded_mipnerf")
SCRIPT = "bench/studies/unbounded_mipnerf.py"
M360 = ("--preset quick --set sampler=proposal --set unbounded=true --set proposal_mlp_width=64 "
        "--set distortion_mult=0.01")
# (key, label, train arguments)
MODELS = [
    ("mip", "mip-NeRF quick, spherified world rays (the 360° default)", "--preset quick"),
    ("m360", "mip-NeRF 360 at quick's size: contracted IPE, proposal 2 × 64 (4×64 MLPs)", M360),
    ("m360_32", "the same, proposal rounds of 32", M360 + " --set proposal_samples=32"),
]


def add_arguments(parser):
    add_budget_arguments(parser, "/tmp/mipnerf-unbounded-mipnerf", 4.0, 4, "4: 64x48", "the capture holds out 5",
                         [m[0] for m in MODELS])


def measure(args):
    return measure_budget(args, "unbounded_mipnerf", RESULTS, MODELS, unbounded_scene, UNBOUNDED_SCENE)


def write_markdown(record):
    return budget_markdown(record, SCRIPT, "unbounded_mipnerf.json",
                           "Unbounded 360° scenes, mip-NeRF: mip-NeRF 360's contracted IPE against spherified "
                           "world rays, at equal training time",
                           [("{label} minus spherified", key, "mip") for key in ("m360", "m360_32")])


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "unbounded_mipnerf", SCRIPT, add_arguments, measure, write_markdown)
