#!/usr/bin/env python3
"""Glorot's or He's initial weights: which trains further in the same time on a real capture?

google/mipnerf (the paper) draws every dense layer's weights from flax's default, Glorot-uniform U(±√(6/(in+out)));
multinerf (mip-NeRF 360) and camp_zipnerf (Zip-NeRF) set their MLPs' weight_init to He-uniform U(±√(6/in)), √2 wider
for a square layer. This tool used Glorot's for every family until `weight_init` (the mipnerf360 preset sets He's, as
360.gin). This study trains each family's two-core preset with either, side by side in one run, through the
command-line tool with `train --minutes M` (the step count fixed by the tool's timed warm-up, recorded):
  - zip_glorot / zip_he: `--model zipnerf --preset fast` (its tiny MLP behind the hash grid);
  - mip_glorot / mip_he: `--preset quick` (mip-NeRF's 4x128 MLP; NDC, cylinders on this capture).
The capture: ../shared/data/llff/flower at factor 8 (504x378), scored by `eval` on its 5 held-out views (PSNR, SSIM,
render time). Finished runs and scores in --work are reused.

  /usr/bin/python3 bench/studies/weight_init.py --minutes 3 --seeds 0,1,2
  python3 bench/studies/weight_init.py --report-only
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import add_budget_arguments, budget_markdown, measure_budget  # noqa: E402

RESULTS = report_md.results_folder("weight_init")
SCRIPT = "bench/studies/weight_init.py"
ZIP = "--model zipnerf --preset fast"
MIP = "--preset quick"
HE = " --set weight_init=he_uniform"
# (key, label, train arguments)
MODELS = [
    ("zip_glorot", "Zip-NeRF fast, Glorot-uniform weights (the default)", ZIP),
    ("zip_he", "Zip-NeRF fast, He-uniform weights (camp_zipnerf's)", ZIP + HE),
    ("mip_glorot", "mip-NeRF quick, Glorot-uniform weights (the default, google/mipnerf's)", MIP),
    ("mip_he", "mip-NeRF quick, He-uniform weights", MIP + HE),
]


def add_arguments(parser):
    parser.add_argument("--data", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                       "../../../shared/data/llff/flower"), help="the LLFF capture")
    add_budget_arguments(parser, "/tmp/mipnerf-weight-init", 3.0, 8, "8: 504x378", "flower holds out 5",
                         [m[0] for m in MODELS])


def measure(args):
    return measure_budget(args, "weight_init", RESULTS, MODELS, args.data,
                          "LLFF flower (real, 34 phone photos), factor {factor}, its {views} held-out views")


def write_markdown(record):
    return budget_markdown(record, SCRIPT, "weight_init.json",
                           "Glorot's against He's initial weights, at equal training time",
                           [("Zip-NeRF fast, He minus Glorot", "zip_he", "zip_glorot"),
                            ("mip-NeRF quick, He minus Glorot", "mip_he", "mip_glorot")])


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "weight_init", SCRIPT, add_arguments, measure, write_markdown)
