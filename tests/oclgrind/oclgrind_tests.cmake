# Every kernel test again under oclgrind (Debian package `oclgrind`), the OpenCL simulator that checks what a real
# device does not: out-of-bounds accesses, data races, uninitialised reads, API misuse (run_under_oclgrind.cmake).
# `ctest -L oclgrind` runs them alone, `ctest -LE oclgrind` leaves them out (the quick PoCL run).
# Included by tests/CMakeLists.txt; without oclgrind installed there are no such tests and a configure message.
find_program(MIPNERF_OCLGRIND oclgrind)
if(NOT MIPNERF_OCLGRIND)
  message(STATUS "oclgrind not found: the kernel tests under oclgrind are left out (Debian package 'oclgrind')")
  return()
endif()

# Each entry lists the kernels it launched in MIPNERF_LAUNCH_LOGS; after the last of them, a check requires every
# kernel of kernels/*.cl in the union (below), so a kernel no entry runs fails the stage instead of passing unchecked.
set(MIPNERF_LAUNCH_LOGS "${CMAKE_CURRENT_BINARY_DIR}/oclgrind-launches")
add_test(NAME "oclgrind: clear the kernel launch lists" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_LAUNCH_LOGS}")
set_tests_properties("oclgrind: clear the kernel launch lists" PROPERTIES LABELS oclgrind
  FIXTURES_SETUP oclgrind_launches)
add_test(NAME "oclgrind: every kernel of kernels/ ran under the simulator" COMMAND ${CMAKE_COMMAND}
  "-DKERNELS=${CMAKE_SOURCE_DIR}/kernels" "-DLOGS=${MIPNERF_LAUNCH_LOGS}"
  -P "${CMAKE_CURRENT_SOURCE_DIR}/oclgrind/check_kernels_ran.cmake")
set_tests_properties("oclgrind: every kernel of kernels/ ran under the simulator" PROPERTIES LABELS oclgrind
  FIXTURES_CLEANUP oclgrind_launches)

# mipnerf_add_oclgrind_test(name executable filter label uninitialized [canary]); MIPNERF_OCLGRIND_EXCLUDE, when set,
# is a filter of test cases to leave out. The tests run on oclgrind's platform, checked (MIPNERF_TEST_PLATFORM).
function(mipnerf_add_oclgrind_test name exe filter label uninitialized)
  set(canary OFF)
  if(ARGN)
    set(canary ON)
  endif()
  string(MAKE_C_IDENTIFIER "${label}_${name}" log_name)
  add_test(NAME "${label}: ${name}" COMMAND ${CMAKE_COMMAND} "-DOCLGRIND=${MIPNERF_OCLGRIND}"
    "-DEXE=$<TARGET_FILE:${exe}>" "-DFILTER=${filter}" "-DUNINITIALIZED=${uninitialized}"
    "-DEXCLUDE=${MIPNERF_OCLGRIND_EXCLUDE}" "-DCANARY=${canary}" "-DLAUNCH_LOG=${MIPNERF_LAUNCH_LOGS}/${log_name}.txt"
    -P "${CMAKE_CURRENT_SOURCE_DIR}/oclgrind/run_under_oclgrind.cmake")
  set_tests_properties("${label}: ${name}" PROPERTIES LABELS ${label} TIMEOUT 1800
    ENVIRONMENT "MIPNERF_TEST_DEVICE=platform=Oclgrind;MIPNERF_TEST_PLATFORM=Oclgrind")
  if(label STREQUAL "oclgrind" AND NOT canary)
    set_tests_properties("${label}: ${name}" PROPERTIES FIXTURES_REQUIRED oclgrind_launches)
  endif()
endfunction()

# Every kernel test (tests/ops: the ray-math stages; tests/mlp: the MLP's element-wise kernels and Adam, whose
# products are CLBlast's; tests/data and tests/core: the batch sampler and the RNG; tests/cl: buffers, program
# building, the profiler's events), one entry per stage so they
# spread over the cores. Label `oclgrind` (in the README's test command, a few minutes on 2 cores): API misuse,
# races, out-of-bounds accesses, and uninitialised reads for the stages whose tests are small enough under that
# plugin. With -DMIPNERF_OCLGRIND_UNINITIALIZED_ALL=ON, entries labelled `uninitialized_all` check the other stages
# for uninitialised reads too (about 25 minutes more; not in CI).
option(MIPNERF_OCLGRIND_UNINITIALIZED_ALL "Also run the slow stages' kernel tests under oclgrind's uninitialised-value check" OFF)
set(fast_stages activations gaussian rays specialisations "stage list")
set(slow_stages encode concat-pe "loss stage" render resample sample)
# Every stage of the one stage list (host/ops/stage_list.cpp) has its entry here, checked when CMake configures.
file(READ "${CMAKE_SOURCE_DIR}/host/ops/stage_list.cpp" stage_list_source)
string(REGEX MATCHALL "{StageId::[a-z_]+,[ \n]*\"[a-z -]+\"" listed_stages "${stage_list_source}")
if(NOT listed_stages)
  message(FATAL_ERROR "tests/oclgrind: found no stage in host/ops/stage_list.cpp (its {StageId::..., \"name\"} rows)")
endif()
foreach(entry IN LISTS listed_stages)
  string(REGEX REPLACE ".*\"([a-z -]+)\"$" "\\1" listed "${entry}")
  if(NOT listed IN_LIST fast_stages AND NOT listed IN_LIST slow_stages)
    message(FATAL_ERROR "tests/oclgrind/oclgrind_tests.cmake: stage '${listed}' of host/ops/stage_list.cpp has no "
      "oclgrind entry: add it to fast_stages or slow_stages")
  endif()
endforeach()
foreach(stage IN LISTS fast_stages)
  mipnerf_add_oclgrind_test("${stage} kernels" test_ops "${stage}:*" oclgrind ON)
endforeach()
foreach(stage IN LISTS slow_stages)
  mipnerf_add_oclgrind_test("${stage} kernels" test_ops "${stage}:*" oclgrind OFF)
  if(MIPNERF_OCLGRIND_UNINITIALIZED_ALL)
    mipnerf_add_oclgrind_test("${stage} kernels" test_ops "${stage}:*" uninitialized_all ON)
  endif()
endforeach()
# CTest starts the costliest tests first; without a previous run (a clean checkout) it knows only COST. Measured
# 2026-11-26 on 2 cores with another build running: render 136 s (its largest batches at a tenth under the
# simulator, test::batch_for_device; ~370 s before), encode 105 s, rays 88 s, resample 49 s. Render 179 s on
# 2026-11-28 (the same conditions) with the weights backward's tests added.
set(MIPNERF_OCLGRIND_COSTS render=179 encode=105 rays=88 resample=49)
foreach(entry IN LISTS MIPNERF_OCLGRIND_COSTS)
  string(REPLACE "=" ";" entry "${entry}")
  list(GET entry 0 stage)
  list(GET entry 1 cost)
  set_tests_properties("oclgrind: ${stage} kernels" PROPERTIES COST ${cost})
endforeach()
# Without the uninitialised-read check: these tests read buffers set by clEnqueueFillBuffer (Adam's zeroed
# moments, filled inputs), and oclgrind 21.10's plugin does not count a fill as a write (a kernel reading a filled
# buffer is reported, the same kernel reading an uploaded one is not: checked by hand), so it reports every read.
mipnerf_add_oclgrind_test("mlp and adam kernels" test_mlp "mlp kernels:*,adam:*" oclgrind OFF)
# The kernels outside the ray-math stages and the MLP: the batch sampler's index gather (kernels/batch.cl, in both
# batching modes, and feeding the ray kernel) and the Philox generator (the RNG tests' device draws). The sampler's
# statistical tests (chi-square over many draws: 60 s and 23 s under the simulator) run the same kernel as the exact
# comparison with the CPU mirror, which is what runs here.
mipnerf_add_oclgrind_test("batch sampler kernels" test_data
  "batch sampler: the device equals the CPU mirror*,device dataset:*" oclgrind ON)
# The sampler feeding the ray kernel, in a process of its own: run after the mirror comparison in one process,
# oclgrind 21.10 reports rays_fwd's reads of the batch (camera and pixel ids the sampler wrote in full) as
# uninitialised for ~250 rays, while the same test alone, or after the device-dataset tests, reports nothing, and
# every ray's origin, direction and radius match the reference in that very run. Not understood (a tiny kernel pair
# of the sampler's 64-bit arithmetic and a branch on its result reports nothing); noted in docs/testing.md.
mipnerf_add_oclgrind_test("batch sampler and ray kernels" test_data "batch sampler + ray kernel*" oclgrind ON)
mipnerf_add_oclgrind_test("rng kernels" test_core "rng:*" oclgrind ON)
# Zip-NeRF's grid encoding (issue 46: not yet a stage of the model, so not in the stage list): its gathers and its
# atomic scatter, whose compare-and-swap loop oclgrind's race check sees.
mipnerf_add_oclgrind_test("grid encoding kernels" test_ops "grid encoding:*" oclgrind ON)
# Zip-NeRF's interval features (multisamples, every level's lookups, the scale feature, the scatter, the level scales
# and the weight decay): the kernels --model zipnerf runs.
mipnerf_add_oclgrind_test("zip feature kernels" test_ops "zip features:*" oclgrind ON)
# The proposal losses of Zip-NeRF / mip-NeRF 360 (issues 45 and 46: not yet stages of the model): the spline
# interlevel loss's three-list walk and the distortion loss's prefix and suffix sweeps, forward and backward. Their
# comparisons with the reference and hard cases only; the finite-difference cases relaunch the same kernels ~100 times.
mipnerf_add_oclgrind_test("proposal loss kernels" test_ops
  "spline interlevel: forward*,spline interlevel: hard*,distortion: forward*" oclgrind ON)
# mip-NeRF 360's outer interlevel loss (its window walks, forward and backward) and the max-dilation of proposal
# histograms (its three-list merge and window): the kernels --model mipnerf --set sampler=proposal adds.
mipnerf_add_oclgrind_test("mip-NeRF 360 proposal kernels" test_ops
  "outer interlevel: forward*,dilate: the kernel*" oclgrind ON)
# mip-NeRF 360's contraction of Gaussians and its ray warps (standalone stages; the model contracts inside the
# contracted IPE below): the forward and backward over the hard cases (inside, on and beside the sphere, far out,
# rank-1 covariances) and both warps. The finite-difference case relaunches the forward ~150 times and is left out.
mipnerf_add_oclgrind_test("contraction kernels" test_ops
  "contract gaussians: forward*,contract gaussians: backward kernel*,ray warp: kernels*" oclgrind ON)
# mip-NeRF 360's encoding (the contracted Gaussian's IPE on the icosahedron's directions, in lanes of 8 with a partial
# last group): the random and hard rays, with a sincos per degree and every 4 degrees.
mipnerf_add_oclgrind_test("contracted IPE kernel" test_ops "contracted IPE: the kernel equals*" oclgrind ON)
# Zip-NeRF's proposal sampler (the graph's Sampling::proposal): its one-ray closed-form cases, the clipped domain, the
# ray with no non-empty interval and the s → t warp (small launches; the 500-ray envelope test stays on PoCL).
mipnerf_add_oclgrind_test("proposal sampler" test_ops
  "sample_intervals: closed-form*,sample_intervals: edges are clipped*,sample_intervals: s to t*" oclgrind ON)
# The two program tests that make the OpenCL API fail on purpose (a build error, an unknown kernel) are left out:
# --check-api reports exactly those failures.
set(MIPNERF_OCLGRIND_EXCLUDE "program: a compile error*,program: an unknown kernel*")
mipnerf_add_oclgrind_test("runtime" test_cl "buffers:*,program:*,profiler:*" oclgrind OFF)
set(MIPNERF_OCLGRIND_EXCLUDE "")

# The check must be able to fail: a kernel that writes one element past its buffer (tests/oclgrind/canary.cpp, a
# program of its own, run only here) is reported, and this entry passes only on that very report (CANARY mode).
add_executable(oclgrind_canary oclgrind/canary.cpp)
target_link_libraries(oclgrind_canary PRIVATE mipnerf_test_support)
mipnerf_add_oclgrind_test("an out-of-bounds write is reported" oclgrind_canary "" oclgrind OFF 1)
