#!/usr/bin/env python3
"""mip-NeRF 360's own training pieces at the quick preset's size: do they buy accuracy at equal training time?

The `mipnerf360` preset holds multinerf configs/360.gin exactly; besides the sizes (a GPU's), it trains differently from
the mip-NeRF 360 model the scene picks for a 360-degree capture at the quick preset's size (bench/studies/
unbounded_mipnerf.py): Charbonnier's data term √(r² + 0.001²) instead of the squared error, taken as a per-channel mean
(which weighs the data term a third as much against the interlevel and distortion losses), an opaque last interval, and
the gradient clipped to norm 1e-3 with Adam's ε at 1e-6. This study trains both on the same capture, side by side in
one run, through the command-line tool with `train --minutes M` (the step count fixed by the tool's timed warm-up,
recorded):
  - m360_32: the scene's choice at the quick preset's size (unbounded_mipnerf's best row: proposal rounds of 32 on 4x64
    density MLPs, the contracted IPE on 21 directions, the distortion loss 0.01), mip-NeRF's squared error summed over
    channels, a see-through background, no clipping;
  - m360_32_official: the same with multinerf's data term, its normalisation, the opaque background, the clipping and ε.
The capture is the tool's own `make-scene --unbounded` at `--set factor=4` (64x48; every 8th view held out), as
unbounded_mipnerf.py's. Each is trained for every seed and scored by `eval` on the val views (PSNR, SSIM, render time).
Finished runs and scores in --work are reused.

  /usr/bin/python3 bench/studies/official_training_360.py --minutes 4 --seeds 0,1,2
  python3 bench/studies/official_training_360.py --report-only
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import (M360_QUICK_32, UNBOUNDED_SCENE, add_budget_arguments, budget_markdown,  # noqa: E402
                          measure_budget, unbounded_scene)

RESULTS = report_md.results_folder("official_training_360")
SCRIPT = "bench/studies/official_training_360.py"
OFFICIAL = (" --set data_loss=charbonnier --set loss_channel_mean=true --set opaque_background=true "
            "--set grad_max_norm=1e-3 --set adam_epsilon=1e-6")
# (key, label, train arguments)
MODELS = [
    ("m360_32", "mip-NeRF 360 at quick's size (the scene's choice): squared error, channel sum", M360_QUICK_32),
    ("m360_32_official", "the same with 360.gin's training: Charbonnier, channel mean, opaque background, clipping",
     M360_QUICK_32 + OFFICIAL),
]


def add_arguments(parser):
    add_budget_arguments(parser, "/tmp/mipnerf-official-training-360", 4.0, 4, "4: 64x48", "the capture holds out 5",
                         [m[0] for m in MODELS])


def measure(args):
    return measure_budget(args, "official_training_360", RESULTS, MODELS, unbounded_scene, UNBOUNDED_SCENE)


def write_markdown(record):
    return budget_markdown(record, SCRIPT, "official_training_360.json",
                           "mip-NeRF 360's training pieces at the quick preset's size, at equal training time",
                           [("360.gin's training minus mip-NeRF's", "m360_32_official", "m360_32")])


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "official_training_360", SCRIPT, add_arguments, measure, write_markdown)
