#!/usr/bin/env python3
"""mip-NeRF 360's proposal sampling for the mip-NeRF model against the paper's coarse/fine, at equal training time, on
a real capture.

Issue 45: "for bounded scenes, proposal sampling is an option of its own (sampler = proposal), so its time-to-accuracy
can be compared with the paper's coarse/fine on the same scene". The paper (mip-NeRF 360, section 3) reports the
proposal MLP alone at 2.66x less training time for equal quality, with its official shapes on a TPU: a 4x256 proposal
MLP evaluated at 2 x 64 samples, the 8x1024 NeRF MLP at 32. On two CPU cores the proposal MLP's share matters; the
rows below keep the `quick` preset's NeRF MLP (4x128, 32 samples) and vary the proposal rounds.

The capture: ../shared/data/llff/flower (34 phone photos, factor 8: 504x378, NDC, its 5 held-out views). The runs,
each `train --preset quick --minutes M` (the step count fixed by the tool's timed warm-up and recorded), seeds 0..2,
scored by `eval` on the held-out views:
  - cf: the paper's coarse/fine (the default: 32 + 32 samples through the one MLP, lambda = 0.1);
  - prop: proposal sampling with 2 rounds of 64 samples through proposal MLPs of 4x64, the outer interlevel loss and
    the official dilation, the NeRF level's 32 samples through the MLP;
  - prop32: the same with rounds of 32 samples (a cheaper step).
The official 4x256 proposal MLP costs 0.52 s/step here against 0.15 for coarse/fine (measured once, 30 steps): not
a CPU setting, so not a row. Finished runs and scores in --work are reused.

  python3 bench/studies/proposal_sampling.py --minutes 3 --seeds 0,1,2
  python3 bench/studies/proposal_sampling.py --report-only
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.cli_runs import (add_budget_arguments, budget_markdown, measure_budget)  # noqa: E402

RESULTS = report_md.results_folder("proposal_sampling")
SCRIPT = "bench/studies/proposal_sampling.py"
PROPOSAL = "--preset quick --set sampler=proposal --set proposal_mlp_width=64"
# (key, label, train arguments)
MODELS = [
    ("cf", "mip-NeRF quick, coarse/fine (the paper's sampling, the default)", "--preset quick"),
    ("prop", "mip-NeRF quick + proposal sampling (2 rounds x 64 samples, proposal MLPs 4x64)", PROPOSAL),
    ("prop32", "mip-NeRF quick + proposal sampling (2 rounds x 32 samples, proposal MLPs 4x64)",
     PROPOSAL + " --set proposal_samples=32"),
]


def add_arguments(parser):
    parser.add_argument("--data", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                       "../../../shared/data/llff/flower"), help="the LLFF capture")
    add_budget_arguments(parser, "/tmp/mipnerf-proposal", 3.0, 8, "8: 504x378", "flower holds out 5",
                         [m[0] for m in MODELS])


def measure(args):
    return measure_budget(args, "proposal_sampling", RESULTS, MODELS, args.data,
                          "LLFF flower (real, 34 phone photos), factor {factor}, its {views} held-out views")


def write_markdown(record):
    return budget_markdown(record, SCRIPT, "proposal_sampling.json",
                           "mip-NeRF with mip-NeRF 360's proposal sampling against coarse/fine, at equal training "
                           "time", [(f"{key} minus coarse/fine", key, "cf") for key in ("prop", "prop32")])


if __name__ == "__main__":
    report_md.study_main(__doc__, RESULTS, "proposal_sampling", SCRIPT, add_arguments, measure, write_markdown)
