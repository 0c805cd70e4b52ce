# A copy of a run (its summary.json and checkpoints) whose val renders are recorded at another rate, so that
# `render`'s estimate of a tiny job says what a long one would (the hint to shorten it) without rendering for long.
# Usage: cmake -DRUN=folder -DOUT=folder -DRATE=seconds_per_megapixel -P forge_render_rate.cmake
file(REMOVE_RECURSE "${OUT}")
file(MAKE_DIRECTORY "${OUT}")
file(COPY "${RUN}/checkpoints" DESTINATION "${OUT}")
file(READ "${RUN}/summary.json" summary)
string(JSON summary SET "${summary}" val render_seconds_per_megapixel "${RATE}")
file(WRITE "${OUT}/summary.json" "${summary}")
