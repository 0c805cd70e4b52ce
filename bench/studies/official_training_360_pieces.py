#!/usr/bin/env python3
"""Which of mip-NeRF 360's training pieces costs what at the quick preset's size: each one alone, at equal time.

bench/studies/official_training_360.py measured 360.gin's training as a whole (Charbonnier's data term as a per-channel
mean, an opaque background, the gradient clipped to norm 1e-3 with Adam's epsilon at 1e-6) against mip-NeRF's at the
quick preset's size on the built-in 360-degree capture: -2.93 dB at 4 minutes, every seed. This study adds each piece
alone to the scene's choice (m360_32 there, the base row here), side by side in one run, through the command-line
tool with `train --minutes M` (the step count fixed by the tool's timed warm-up, recorded):
  - base: proposal rounds of 32 on 4x64 density MLPs, the contracted IPE on 21 directions, the distortion loss 0.01,
    mip-NeRF's squared error summed over channels, a see-through background, no clipping;
  - charb: Charbonnier's data term sqrt(r^2 + 0.001^2), still summed over channels;
  - mean: the squared error as a per-channel mean (the data term weighs a third as much against the interlevel and
    distortion losses);
  - opaque: the last interval infinitely thick (the weights sum to 1);
  - clip: the gradient clipped to norm 1e-3 and Adam's epsilon 1e-6.
The capture is the tool's own `make-scene --unbounded` at `--set factor=4` (64x48; every 8th view held out). Each is
trained for every seed and scored by `eval` on the val views. Finished runs and scores in --work are reused.

  /usr/bin/python3 bench/studies/official_training_360_pieces.py --minutes 3 --seeds 0,1,2
  python3 bench/studies/official_training_360_pieces.py --report-only
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import (M360_QUICK_32, UNBOUNDED_SCENE, add_budget_arguments, budget_markdown,  # noqa: E402
                          measure_budget, unbounded_scene)

RESULTS = report_md.results_folder("official_training_360_pieces")
SCRIPT = "bench/studies/official_training_360_pieces.py"
# (key, label, train arguments)
MODELS = [
    ("base", "mip-NeRF 360 at quick's size (the scene's choice): squared error summed over channels",
     M360_QUICK_32),
    ("charb", "+ Charbonnier's data term (padding 0.001), summed over channels",
     M360_QUICK_32 + " --set data_loss=charbonnier"),
    ("mean", "+ the data term as a per-channel mean", M360_QUICK_32 + " --set loss_channel_mean=true"),
    ("opaque", "+ an opaque background", M360_QUICK_32 + " --set opaque_background=true"),
    ("clip", "+ the gradient clipped to norm 1e-3, Adam's epsilon 1e-6",
     M360_QUICK_32 + " --set grad_max_norm=1e-3 --set adam_epsilon=1e-6"),
]


def add_arguments(parser):
    add_budget_arguments(parser, "/tmp/mipnerf-official-training-360-pieces", 3.0, 4, "4: 64x48",
                         "the capture holds out 5", [m[0] for m in MODELS])


def measure(args):
    return measure_budget(args, "official_training_360_pieces", RESULTS, MODELS, unbounded_scene, UNBOUNDED_SCENE)


def write_markdown(record):
    return budget_markdown(record, SCRIPT, "official_training_360_pieces.json",
                           "mip-NeRF 360's training pieces one at a time, at the quick preset's size and equal time",
                           [("{label} minus the base", key, "base") for key, _, _ in MODELS[1:]])


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "official_training_360_pieces", SCRIPT, add_arguments, measure,
                         write_markdown)
