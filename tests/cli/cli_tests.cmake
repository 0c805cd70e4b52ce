# The CLI's tests through the real executable (included by tests/CMakeLists.txt, whose folder the paths below are
# relative to): every user-facing error is one line and a non-zero exit; the quick-start path, train, render, eval and
# bench end to end.
# Every test here runs through tests/cli/run_checked.cmake, which checks the exit status, the output and the absence
# of any sanitizer report together (CTest's PASS_REGULAR_EXPRESSION alone would ignore the exit status).
#
# mipnerf_add_checked_test(name [EXPECT regex] [EXIT 0|nonzero] COMMAND program args...): `program` may be a target
# (mipnerf-cl); the test passes when the command exits with EXIT (default 0), its output (stdout and stderr merged)
# matches EXPECT, and no sanitizer reported.
# A ';' in EXPECT is a list separator to CMake: PARSE_ARGV keeps the pattern whole, and it travels to the runner as
# @SEMICOLON@ (run_checked.cmake puts the ';' back). Unparsed, `a; b` was checked as `a` alone.
function(mipnerf_add_checked_test name)
  cmake_parse_arguments(PARSE_ARGV 1 T "ONE_LINE" "EXPECT;EXIT" "COMMAND")
  string(REPLACE ";" "@SEMICOLON@" T_EXPECT "${T_EXPECT}")
  list(GET T_COMMAND 0 program)
  if(TARGET "${program}")
    list(REMOVE_AT T_COMMAND 0)
    list(INSERT T_COMMAND 0 "$<TARGET_FILE:${program}>")
  endif()
  string(REPLACE ";" "|" joined "${T_COMMAND}")
  add_test(NAME "${name}" COMMAND ${CMAKE_COMMAND} "-DCOMMAND=${joined}" "-DEXPECT=${T_EXPECT}" "-DEXIT=${T_EXIT}"
    "-DONE_LINE=${T_ONE_LINE}" "-DREPORT=${MIPNERF_SANITIZER_REPORT}" -P "${CMAKE_CURRENT_SOURCE_DIR}/cli/run_checked.cmake")
  set_tests_properties("${name}" PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV}")
endfunction()

# The CLI's user-facing errors: mipnerf_add_cli_error_test(name PATTERN regex ARGS args...) expects a non-zero exit
# and exactly one line on stderr, matching the regex.
function(mipnerf_add_cli_error_test name)
  cmake_parse_arguments(PARSE_ARGV 1 T "" "PATTERN" "ARGS")
  string(REPLACE ";" "@SEMICOLON@" pattern "${T_PATTERN}")
  mipnerf_add_checked_test("cli: ${name}" ONE_LINE EXIT nonzero EXPECT "${pattern}" COMMAND mipnerf-cl ${T_ARGS})
endfunction()

# An error test must fail when the program crashes after printing the expected line (a signal, or a status above
# 125): tests/cli/expect_crash_fails.cmake drives the runner with such commands.
add_test(NAME "cli: an error test fails when the program crashes after its message" COMMAND ${CMAKE_COMMAND}
  "-DRUNNER=${CMAKE_CURRENT_SOURCE_DIR}/cli/run_checked.cmake" "-DSHELL=/bin/sh"
  -P "${CMAKE_CURRENT_SOURCE_DIR}/cli/expect_crash_fails.cmake")

# The executable runs on the platform the test stage asked for (MIPNERF_TEST_PLATFORM; scripts/test.sh sets it with
# MIPNERF_DEVICE and MIPNERF_TEST_DEVICE), so a CLI test never passes on another OpenCL implementation.
add_test(NAME "cli: the executable selects a device of the stage's platform" COMMAND ${CMAKE_COMMAND}
  "-DEXE=$<TARGET_FILE:mipnerf-cl>" -P "${CMAKE_CURRENT_SOURCE_DIR}/cli/check_platform.cmake")
set_tests_properties("cli: the executable selects a device of the stage's platform" PROPERTIES
  ENVIRONMENT "${MIPNERF_TEST_ENV}")

mipnerf_add_checked_test("cli: devices lists a device" EXPECT "\\[0\\] .*compute units"
  COMMAND mipnerf-cl devices)
mipnerf_add_checked_test("cli: devices says why it selects a device" EXPECT "\\[0\\] [^\n]*<- selected \\(--device '0'\\)"
  COMMAND mipnerf-cl devices --device 0)
mipnerf_add_cli_error_test("unknown device" PATTERN "--device 'nosuch' matches no OpenCL device.*\\[0\\]"
  ARGS devices --device nosuch)
mipnerf_add_cli_error_test("unknown subcommand" PATTERN "nosuch" ARGS nosuch)

# Datasets (host/data): every kind of bad input is one line on stderr and a non-zero exit, through the real
# executable. The inputs are small committed files under tests/data/fixtures.
set(MIPNERF_DATA_FIXTURES "${CMAKE_CURRENT_SOURCE_DIR}/data/fixtures")
mipnerf_add_cli_error_test("dataset inspect: missing folder" PATTERN "nowhere: no such file or folder"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/nowhere")
mipnerf_add_cli_error_test("dataset inspect: folder without a dataset" PATTERN "cli: no dataset here: expected transforms_train.json \\(Blender\\), metadata.json \\(multiscale Blender\\), transforms.json or poses_bounds.npy with images/ \\(an LLFF capture\\)"
  ARGS dataset inspect "${CMAKE_CURRENT_SOURCE_DIR}/cli")
# What is there decides the hint (host/data/formats/no_dataset.cpp): datasets in subfolders, photos without poses
# (from-photos), a COLMAP workspace (import-colmap), an empty folder (make-scene), a slip in the name (did you mean).
mipnerf_add_cli_error_test("dataset inspect: a folder of datasets names them" PATTERN "fixtures: no dataset here, but its subfolders differing_sizes, distortion, malformed_json, mirrored_pose and [0-9]+ more hold one each: give one of them, e.g. .*fixtures/differing_sizes$"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}")
mipnerf_add_cli_error_test("dataset inspect: a folder of photos suggests from-photos" PATTERN "textureless: 4 photos \\(PNG or JPEG\\) but no camera poses. make a dataset of them with `mipnerf-cl dataset from-photos .*fixtures/textureless OUT` \\(COLMAP\\), then train on OUT$"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/textureless")
mipnerf_add_cli_error_test("train: a folder of photos suggests from-photos" PATTERN "textureless: 4 photos \\(PNG or JPEG\\) but no camera poses. make a dataset of them with `mipnerf-cl dataset from-photos .*fixtures/textureless OUT` \\(COLMAP\\), then train on OUT$"
  ARGS train --data "${MIPNERF_DATA_FIXTURES}/textureless" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: a COLMAP workspace suggests import-colmap" PATTERN "colmap: a COLMAP model \\(.*colmap/sparse\\) but no dataset. import it with `mipnerf-cl dataset import-colmap .*colmap/sparse .*colmap/images OUT`, then train on OUT$"
  ARGS train --data "${MIPNERF_DATA_FIXTURES}/colmap" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: a mistyped --data names the folder meant" PATTERN "fixtures/vaild: no such file or folder. did you mean '.*fixtures/valid'\\?$"
  ARGS train --data "${MIPNERF_DATA_FIXTURES}/vaild" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("dataset inspect: a mistyped folder on the way names the one meant" PATTERN "fixturs/valid: no such file or folder. did you mean '.*fixtures/valid'\\?$"
  ARGS dataset inspect "${CMAKE_CURRENT_SOURCE_DIR}/data/fixturs/valid")
mipnerf_add_cli_error_test("dataset inspect: a missing folder on the way is named" PATTERN "nowhere/valid: no such file or folder. no 'nowhere' in .*tests/data$"
  ARGS dataset inspect "${CMAKE_CURRENT_SOURCE_DIR}/data/nowhere/valid")
add_test(NAME "cli: an empty folder: make it" COMMAND ${CMAKE_COMMAND} -E make_directory "${CMAKE_CURRENT_BINARY_DIR}/cli-empty")
set_tests_properties("cli: an empty folder: make it" PROPERTIES FIXTURES_SETUP cli_empty)
mipnerf_add_cli_error_test("train: an empty --data folder suggests make-scene" PATTERN "cli-empty: an empty folder. put a dataset there, or write the built-in procedural scene into it with `mipnerf-cl make-scene .*cli-empty`$"
  ARGS train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-empty" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
set_tests_properties("cli: train: an empty --data folder suggests make-scene" PROPERTIES FIXTURES_REQUIRED cli_empty)
mipnerf_add_cli_error_test("dataset inspect: missing image" PATTERN "missing_image/train/r_0.png: no such file \\(listed by .*missing_image/transforms_train.json: frames\\[0\\]\\)"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/missing_image")
mipnerf_add_cli_error_test("dataset inspect: malformed JSON" PATTERN "malformed_json/transforms_train.json: malformed JSON at line 4, column 31: "
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/malformed_json")
mipnerf_add_cli_error_test("dataset inspect: missing key" PATTERN "missing_key/transforms_train.json: frames\\[0\\]: missing key 'transform_matrix'"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/missing_key")
mipnerf_add_cli_error_test("dataset inspect: non-rigid pose" PATTERN "frames\\[0\\]: the pose's rotation is not orthonormal"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/nonrigid_pose")
mipnerf_add_cli_error_test("dataset inspect: mirrored pose" PATTERN "frames\\[0\\]: the pose's rotation has determinant -1 instead of \\+1"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/mirrored_pose")
mipnerf_add_cli_error_test("dataset inspect: non-finite pose" PATTERN "nonfinite_pose/transforms_train.json: malformed JSON at line 1, column 88: .*non-finite"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/nonfinite_pose")
mipnerf_add_cli_error_test("dataset inspect: unreadable PNG" PATTERN "unreadable_png/train/r_0.png: unreadable PNG \\(not a PNG file"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/unreadable_png")
mipnerf_add_cli_error_test("dataset inspect: truncated PNG" PATTERN "truncated_png/train/r_0.png: unreadable PNG \\(the file is truncated\\)"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/truncated_png")
mipnerf_add_cli_error_test("dataset inspect: images of differing size" PATTERN "differing_sizes/train/r_1.png: the image is 4x2 but .*r_0.png is 4x4"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/differing_sizes")
mipnerf_add_checked_test("cli: dataset inspect: a lens camera prints its model and largest distortion" EXPECT "lens: OPENCV \\(k1 -0.12.*largest distortion 0\\.12[0-9]* px"
  COMMAND mipnerf-cl dataset inspect "${MIPNERF_DATA_FIXTURES}/distortion")
mipnerf_add_cli_error_test("dataset inspect: scales that do not divide the size" PATTERN "r_0.png: 4x4 is not divisible by 8 for 4 scales"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/valid" --scales 4)
mipnerf_add_cli_error_test("dataset inspect: unknown background" PATTERN "--background 'green': expected white \\| black \\| none"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/valid" --background green)
mipnerf_add_cli_error_test("make-multiscale: output folder is the input" PATTERN "the output folder must differ from the input folder"
  ARGS make-multiscale "${MIPNERF_DATA_FIXTURES}/valid" "${MIPNERF_DATA_FIXTURES}/valid")
mipnerf_add_cli_error_test("make-scene: size not divisible for the scales" PATTERN "--size 60 is not divisible by 8 for 4 scales"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --size 60 --scales 4)
# The quick-start path: make-scene, then inspect what it wrote (multiscale), in order.
mipnerf_add_checked_test("cli: make-scene writes a small scene" EXPECT "wrote .*cli-scene: 3 train, 1 val, 1 test views at 16x16; multiscale \\(2 scales\\)"
  COMMAND mipnerf-cl make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-scene"
  --size 16 --views 3 --val-views 1 --test-views 1 --scales 2 --samples 2)
set_tests_properties("cli: make-scene writes a small scene" PROPERTIES FIXTURES_SETUP cli_scene)
mipnerf_add_checked_test("cli: dataset inspect shows scales and the look-at centre" EXPECT "scale 1 \\(/2\\): 3 images 8x8, focal x [0-9.]+ px, focal y [0-9.]+ px, lossmult 4.*look-at centre \\(closest to all optical axes\\): \\(0.000, 0.000, 0.000\\), in front of 6/6 cameras"
  COMMAND mipnerf-cl dataset inspect
  "${CMAKE_CURRENT_BINARY_DIR}/cli-scene/multiscale")
set_tests_properties("cli: dataset inspect shows scales and the look-at centre" PROPERTIES FIXTURES_REQUIRED cli_scene)

# The forward-facing scene in the LLFF layout, trained as its data calls for (NDC, cylinders, black background), and
# its spiral rendered.
mipnerf_add_checked_test("cli: make-scene --forward-facing writes an LLFF capture" EXPECT "an LLFF capture of 20 views at 64x48 \\(images/, images_4/, poses_bounds.npy\\)"
  COMMAND mipnerf-cl make-scene
  "${CMAKE_CURRENT_BINARY_DIR}/cli-llff" --forward-facing --size 64 --samples 1)
set_tests_properties("cli: make-scene --forward-facing writes an LLFF capture" PROPERTIES FIXTURES_SETUP cli_llff)
# Nearly parallel optical axes need not meet in front of the cameras: a forward-facing capture shows its viewing
# direction and the spread of its axes, and no pose-convention warning (this grid's axes do meet, in front).
mipnerf_add_checked_test("cli: dataset inspect of a forward-facing capture shows where it looks" EXPECT "distance from the origin [^\n]*\n  viewing direction \\(the mean optical axis\\): \\(-?0.0[0-9]+, -?0.0[0-9]+, -1.000\\), every axis within [0-9].[0-9] degrees of it: a forward-facing capture, whose axes need not meet\n  look-at centre [^\n]*in front of 17/17 cameras[^\n]*\n  mean colour"
  COMMAND mipnerf-cl dataset inspect "${CMAKE_CURRENT_BINARY_DIR}/cli-llff" --factor 4)
set_tests_properties("cli: dataset inspect of a forward-facing capture shows where it looks" PROPERTIES FIXTURES_REQUIRED cli_llff FAIL_REGULAR_EXPRESSION "WARNING")
add_test(NAME "cli: train on an LLFF capture: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${CMAKE_CURRENT_BINARY_DIR}/cli-llff-run")
set_tests_properties("cli: train on an LLFF capture: clear the run folder" PROPERTIES FIXTURES_SETUP cli_llff_clean)
mipnerf_add_checked_test("cli: train on an LLFF capture chooses NDC, cylinders, black" EXPECT "scene: forward-facing LLFF → NDC rays, cylinders, black background.*trained 4 steps"
  COMMAND mipnerf-cl train
  --data "${CMAKE_CURRENT_BINARY_DIR}/cli-llff" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-llff-run" --preset tiny --factor 4
  --steps 4 --val_views 1)
set_tests_properties("cli: train on an LLFF capture chooses NDC, cylinders, black" PROPERTIES FIXTURES_REQUIRED "cli_llff;cli_llff_clean" FIXTURES_SETUP cli_llff_run)
mipnerf_add_checked_test("cli: render --path spiral of an LLFF run" EXPECT "rendered 3 frames of the spiral of .*cli-llff \\(16x12\\)"
  COMMAND mipnerf-cl render
  --checkpoint "${CMAKE_CURRENT_BINARY_DIR}/cli-llff-run" --path spiral --frames 3)
set_tests_properties("cli: render --path spiral of an LLFF run" PROPERTIES FIXTURES_REQUIRED cli_llff_run)
# The same forward-facing scene behind an OPENCV lens, as import-colmap writes such a capture (a transforms.json:
# LLFF holds pinholes): trained in NDC with cylinders through its lens tables, as the LLFF capture is, and its spiral.
set(MIPNERF_LENS_FORWARD "${CMAKE_CURRENT_BINARY_DIR}/cli-lens-forward")
mipnerf_add_checked_test("cli: make-scene --forward-facing --lens writes a transforms.json"
  EXPECT "a transforms.json of 12 forward-facing views at 32x24 behind an OPENCV lens \\(images/, transforms.json\\)"
  COMMAND mipnerf-cl make-scene "${MIPNERF_LENS_FORWARD}" --forward-facing --size 32 --grid 4x3 --factor 1 --samples 1
  --lens OPENCV:-0.1,0.02,0.001,-0.0005)
set_tests_properties("cli: make-scene --forward-facing --lens writes a transforms.json" PROPERTIES
  FIXTURES_SETUP cli_lens_forward)
add_test(NAME "cli: train behind a lens in NDC: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_LENS_FORWARD}-run")
set_tests_properties("cli: train behind a lens in NDC: clear the run folder" PROPERTIES FIXTURES_SETUP cli_lens_forward_clean)
mipnerf_add_checked_test("cli: a forward-facing capture behind a lens trains in NDC through its lens"
  EXPECT "transforms.json: the NDC world of a forward-facing capture: scaled by [0-9.e+-]+ so that its nearest depth, [0-9.e+-]+, becomes 4/3, and recentred on the average camera\n.*scene: transforms.json of forward-facing photos → NDC rays, cylinders, black background, raw view directions, density noise 1.*trained 2 steps"
  COMMAND mipnerf-cl train --data "${MIPNERF_LENS_FORWARD}" --out "${MIPNERF_LENS_FORWARD}-run" --preset tiny
  --steps 2 --val_views 1)
set_tests_properties("cli: a forward-facing capture behind a lens trains in NDC through its lens" PROPERTIES
  FIXTURES_REQUIRED "cli_lens_forward;cli_lens_forward_clean" FIXTURES_SETUP cli_lens_forward_run)
mipnerf_add_checked_test("cli: render --path spiral of a run behind a lens"
  EXPECT "rendered 3 frames of the spiral of .*cli-lens-forward/transforms.json \\(through a pinhole of its focal length: undistorted\\) \\(32x24\\)"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_LENS_FORWARD}-run" --path spiral --frames 3)
set_tests_properties("cli: render --path spiral of a run behind a lens" PROPERTIES FIXTURES_REQUIRED cli_lens_forward_run)
# train --minutes (host/train/step_budget.*): what it refuses, and a budget run on the LLFF capture whose recorded
# steps a --resume keeps (the warm-up, the steps and the resume themselves: tests/train/test_step_budget.cpp).
mipnerf_add_cli_error_test("train: --minutes must be positive" PATTERN "--minutes 0: the training budget must be a positive number of minutes"
  ARGS train --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad" --minutes 0)
mipnerf_add_cli_error_test("train: --minutes with --steps is refused" PATTERN "--minutes and steps \\(5, from --steps, --set or --config\\) both fix the run's step count: give one of them"
  ARGS train --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad" --minutes 1 --steps 5)
mipnerf_add_cli_error_test("train: --minutes with --resume of a run is refused" PATTERN "--minutes sizes a new run, but .*cli-llff-run holds one at step 4 of its recorded 4 steps, which --resume continues: drop --minutes"
  ARGS train --out "${CMAKE_CURRENT_BINARY_DIR}/cli-llff-run" --resume --minutes 1)
set_tests_properties("cli: train: --minutes with --resume of a run is refused" PROPERTIES FIXTURES_REQUIRED cli_llff_run)
add_test(NAME "cli: train --minutes: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${CMAKE_CURRENT_BINARY_DIR}/cli-minutes-run")
set_tests_properties("cli: train --minutes: clear the run folder" PROPERTIES FIXTURES_SETUP cli_minutes_clean)
mipnerf_add_checked_test("cli: train --minutes sizes the steps by a warm-up and says so" EXPECT "time budget 0.1 min: warm-up of 1 cold step \\([0-9.]+ s\\) and [0-9]+ timed steps \\([0-9.]+ s\\) measured [0-9.]+ s/step. [0-9]+ steps fill the [0-9.]+ s left.*trained [0-9]+ steps"
  COMMAND mipnerf-cl train
  --data "${CMAKE_CURRENT_BINARY_DIR}/cli-llff" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-minutes-run" --preset tiny --factor 4
  --minutes 0.1 --val_views 1)
set_tests_properties("cli: train --minutes sizes the steps by a warm-up and says so" PROPERTIES FIXTURES_REQUIRED "cli_llff;cli_minutes_clean" FIXTURES_SETUP cli_minutes_run)
mipnerf_add_cli_error_test("make-scene: a Blender option with --forward-facing" PATTERN "--views applies to the Blender scene, not --forward-facing"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --forward-facing --views 3)
mipnerf_add_cli_error_test("make-scene: bad --grid" PATTERN "--grid '5by4': expected COLUMNSxROWS"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --forward-facing --grid 5by4)
mipnerf_add_cli_error_test("make-scene: bad --grid-width" PATTERN "--grid-width must be 0.01 to 4 \\(scene units"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --forward-facing --grid-width 0)

# The unbounded (360°) scene in the LLFF layout: train takes it for a 360° capture with no flag: spherified poses,
# cones, and for mip-NeRF the model of mip-NeRF 360 (contracted frustums IPE'd on 21 directions, proposal sampling
# spaced by the reciprocal); it trains a few steps, evaluates and renders an orbit from the checkpoint.
mipnerf_add_checked_test("cli: make-scene --unbounded writes a 360-degree LLFF capture"
  EXPECT "a 360-degree LLFF capture of 16 views at 64x48 \\(images/, images_4/, poses_bounds.npy\\)"
  COMMAND mipnerf-cl make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded" --unbounded --size 64 --views 16 --samples 1)
set_tests_properties("cli: make-scene --unbounded writes a 360-degree LLFF capture" PROPERTIES
  FIXTURES_SETUP cli_unbounded)
add_test(NAME "cli: train on the unbounded scene: clear the run folder"
  COMMAND ${CMAKE_COMMAND} -E rm -rf "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-run"
  "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-resample-run")
set_tests_properties("cli: train on the unbounded scene: clear the run folder" PROPERTIES
  FIXTURES_SETUP cli_unbounded_clean)
mipnerf_add_checked_test("cli: train on the unbounded scene takes it for a 360-degree capture"
  EXPECT "scene: 360° LLFF capture → spherified poses, world rays, cones, black background; mip-NeRF unbounded as mip-NeRF 360 \\(frustums contracted, IPE 0..11 on 21 directions, proposal sampling spaced in disparity from 0.2 to 1e6\\).*proposal-sampled 16 intervals \\(reciprocal s→t\\), IPE of contracted frustums degrees 0..11 on 21 directions.*trained 4 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded"
  --out "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-run" --preset tiny --factor 4 --steps 4 --val_views 1
  --set proposal_samples=16 --set num_samples=16 --set proposal_mlp_width=32)
set_tests_properties("cli: train on the unbounded scene takes it for a 360-degree capture" PROPERTIES
  FIXTURES_REQUIRED "cli_unbounded;cli_unbounded_clean" FIXTURES_SETUP cli_unbounded_mip)
mipnerf_add_checked_test("cli: unbounded mipnerf: eval" EXPECT "mean PSNR [0-9.]+ dB"
  COMMAND mipnerf-cl eval --checkpoint "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-run"
  --data "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded")
set_tests_properties("cli: unbounded mipnerf: eval" PROPERTIES FIXTURES_REQUIRED cli_unbounded_mip)
mipnerf_add_checked_test("cli: unbounded mipnerf: render an orbit" EXPECT "rendered 2 frames"
  COMMAND mipnerf-cl render --checkpoint "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-run" --path orbit --frames 2
  --size 16x12)
set_tests_properties("cli: unbounded mipnerf: render an orbit" PROPERTIES FIXTURES_REQUIRED cli_unbounded_mip)
# An explicit setting against the group keeps mip-NeRF 360 out, and train says which (the paper's mip-NeRF then).
mipnerf_add_checked_test("cli: unbounded mipnerf: sampler=resample keeps the spherified paper model"
  EXPECT "; mip-NeRF not unbounded as mip-NeRF 360 [^\n]*\\(given explicitly: sampler = resample\\).*level 0: stratified.*trained 2 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded"
  --out "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-resample-run" --preset tiny --factor 4 --steps 2 --val_views 1
  --set sampler=resample)
set_tests_properties("cli: unbounded mipnerf: sampler=resample keeps the spherified paper model" PROPERTIES
  FIXTURES_REQUIRED "cli_unbounded;cli_unbounded_clean")
# Zip-NeRF on it trains unbounded with no flag (the scene's choice for the zipnerf family: contraction, proposal
# sampling spaced by the power ladder), then evaluates and renders an orbit from the checkpoint (from near 0 to far
# 1e6, as it trained).
set(MIPNERF_UNBOUNDED_RUN "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-zip-run")
add_test(NAME "cli: unbounded zipnerf: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_UNBOUNDED_RUN}"
  "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-photos" "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-photos-run")
set_tests_properties("cli: unbounded zipnerf: clear the run folder" PROPERTIES FIXTURES_SETUP cli_unbounded_zip_clean)
mipnerf_add_checked_test("cli: unbounded zipnerf: train with contraction and the power ladder"
  EXPECT "scene: 360° LLFF capture → [^\n]*; Zip-NeRF unbounded \\(contraction, proposal sampling spaced by the power ladder from 0 to 1e6\\).*proposal-sampled 16 intervals \\(power ladder s→t\\).*points contracted \\(unbounded\\).*trained 4 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded"
  --out "${MIPNERF_UNBOUNDED_RUN}" --model zipnerf --preset tiny --factor 4 --steps 4 --val_views 1
  --set proposal_samples=16 --set num_samples=16 --set proposal_grid_max=128 --set grid_max=128
  --set grid_hash_log2=14)
set_tests_properties("cli: unbounded zipnerf: train with contraction and the power ladder" PROPERTIES
  FIXTURES_REQUIRED "cli_unbounded;cli_unbounded_zip_clean" FIXTURES_SETUP cli_unbounded_zip)
mipnerf_add_checked_test("cli: unbounded zipnerf: eval" EXPECT "mean PSNR [0-9.]+ dB"
  COMMAND mipnerf-cl eval --checkpoint "${MIPNERF_UNBOUNDED_RUN}" --data "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded")
set_tests_properties("cli: unbounded zipnerf: eval" PROPERTIES FIXTURES_REQUIRED cli_unbounded_zip)
mipnerf_add_checked_test("cli: unbounded zipnerf: render the capture's path" EXPECT "rendered 2 frames"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_UNBOUNDED_RUN}" --path orbit --frames 2 --size 16x12)
set_tests_properties("cli: unbounded zipnerf: render the capture's path" PROPERTIES FIXTURES_REQUIRED cli_unbounded_zip)
# Photos taken all around as a transforms.json (what `dataset from-photos` writes for them; here the frames and
# transforms.json of an orbit rendered from that run): an unbounded scene for Zip-NeRF too, trained in the world
# centred where its cameras look (data::world_around_cameras), which train says.
set(MIPNERF_UNBOUNDED_PHOTOS "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded-photos")
mipnerf_add_checked_test("cli: unbounded zipnerf: render an orbit of photos all around" EXPECT "rendered 9 frames"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_UNBOUNDED_RUN}" --path orbit --frames 9 --size 32x24
  --out "${MIPNERF_UNBOUNDED_PHOTOS}")
set_tests_properties("cli: unbounded zipnerf: render an orbit of photos all around" PROPERTIES
  FIXTURES_REQUIRED cli_unbounded_zip FIXTURES_SETUP cli_unbounded_photos)
mipnerf_add_checked_test("cli: unbounded zipnerf: a transforms.json of photos all around trains unbounded"
  EXPECT "transforms.json: the world for an unbounded run: centred on \\([^)]*\\) \\(where the cameras look\\) and scaled by [0-9.e+-]+, so the cameras sit at RMS distance 1 from the centre\n.*scene: transforms.json of photos taken all around \\(360°\\) → cones, black background; Zip-NeRF unbounded \\(contraction[^\n]*\n.*points contracted \\(unbounded\\).*trained 2 steps"
  COMMAND mipnerf-cl train --data "${MIPNERF_UNBOUNDED_PHOTOS}/transforms.json"
  --out "${MIPNERF_UNBOUNDED_PHOTOS}-run" --model zipnerf --preset tiny --steps 2 --val_views 1
  --set proposal_samples=16 --set num_samples=16 --set proposal_grid_max=128 --set grid_max=128
  --set grid_hash_log2=14)
set_tests_properties("cli: unbounded zipnerf: a transforms.json of photos all around trains unbounded" PROPERTIES
  FIXTURES_REQUIRED cli_unbounded_photos)
mipnerf_add_cli_error_test("train: unbounded without sampler=proposal" PATTERN "unbounded needs sampler=proposal"
  ARGS train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-unbounded" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-run"
  --model zipnerf --set sampler=resample --set unbounded=true)
set_tests_properties("cli: train: unbounded without sampler=proposal" PROPERTIES FIXTURES_REQUIRED cli_unbounded)
mipnerf_add_cli_error_test("make-scene: --unbounded with --forward-facing" PATTERN "--unbounded and --forward-facing are two different scenes: give one"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --unbounded --forward-facing)
mipnerf_add_cli_error_test("make-scene: a Blender option with --unbounded" PATTERN "--scales does not apply to --unbounded"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --unbounded --scales 2)
mipnerf_add_cli_error_test("make-scene: --texture without --unbounded" PATTERN "--texture applies to --unbounded"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --texture noise)
mipnerf_add_cli_error_test("make-scene: an unknown --texture" PATTERN "--texture: marble not in .checker,noise."
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --unbounded --texture marble)
mipnerf_add_cli_error_test("make-scene: too few --views for --unbounded" PATTERN "--views must be 8 to 400 \\(a full orbit\\)"
  ARGS make-scene "${CMAKE_CURRENT_BINARY_DIR}/cli-bad-scene" --unbounded --views 3)

# COLMAP import (host/data/colmap*, cli/cmd_dataset.cpp): the fixtures in tests/data/fixtures/colmap (written by its
# make_fixture.py): a text and a binary model of 3 PINHOLE views, and broken variants. One import is inspected and
# trained on through the real executable.
set(MIPNERF_COLMAP_FIXTURES "${MIPNERF_DATA_FIXTURES}/colmap")
set(MIPNERF_COLMAP_OUT "${CMAKE_CURRENT_BINARY_DIR}/cli-colmap")
add_test(NAME "cli: dataset import-colmap: clear its folders" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_COLMAP_OUT}"
  "${MIPNERF_COLMAP_OUT}-bin" "${MIPNERF_COLMAP_OUT}-run")
set_tests_properties("cli: dataset import-colmap: clear its folders" PROPERTIES FIXTURES_SETUP cli_colmap_clean)
mipnerf_add_checked_test("cli: dataset import-colmap imports a text model" EXPECT "imported 3 images \\(1 camera: PINHOLE\\) and 27 points from [^\n]*sparse \\(text\\) into [^\n]*cli-colmap/transforms.json\n.*is the origin, scaled by [0-9.]+ \\(the median camera 4 from it\\)\nnear [0-9.]+, far [0-9.]+ \\(from the points' depths\\)\ntrain on it: mipnerf-cl train --data [^\n]*cli-colmap/transforms.json"
  COMMAND mipnerf-cl dataset import-colmap
  "${MIPNERF_COLMAP_FIXTURES}/sparse" "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_COLMAP_OUT}")
set_tests_properties("cli: dataset import-colmap imports a text model" PROPERTIES FIXTURES_REQUIRED cli_colmap_clean FIXTURES_SETUP cli_colmap)
mipnerf_add_checked_test("cli: dataset import-colmap imports a binary model" EXPECT "imported 3 images .* \\(binary\\) into .*near 1, far 7 \\(as given\\)"
  COMMAND mipnerf-cl dataset import-colmap
  "${MIPNERF_COLMAP_FIXTURES}/sparse_bin" "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_COLMAP_OUT}-bin" --near 1 --far 7)
set_tests_properties("cli: dataset import-colmap imports a binary model" PROPERTIES FIXTURES_REQUIRED cli_colmap_clean)
mipnerf_add_checked_test("cli: dataset inspect shows an imported COLMAP model looking at the origin" EXPECT "split train: 2 images.*scale 0 \\(/1\\): 2 images 8x6, focal x 9 px, focal y 9 px.*distance from the origin 4\n.*look-at centre \\(closest to all optical axes\\): \\(0.000, 0.000, 0.000\\), in front of 2/2 cameras"
  COMMAND mipnerf-cl dataset
  inspect "${MIPNERF_COLMAP_OUT}/transforms.json")
set_tests_properties("cli: dataset inspect shows an imported COLMAP model looking at the origin" PROPERTIES FIXTURES_REQUIRED cli_colmap)
mipnerf_add_checked_test("cli: train on an imported COLMAP model" EXPECT "trained 4 steps"
  COMMAND mipnerf-cl train --data "${MIPNERF_COLMAP_OUT}/transforms.json"
  --out "${MIPNERF_COLMAP_OUT}-run" --preset tiny --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml")
set_tests_properties("cli: train on an imported COLMAP model" PROPERTIES FIXTURES_REQUIRED cli_colmap)
mipnerf_add_checked_test("cli: dataset import-colmap: a SIMPLE_RADIAL camera imports with its lens" EXPECT "imported 3 images \\(1 camera: SIMPLE_RADIAL\\)"
  COMMAND mipnerf-cl dataset import-colmap "${MIPNERF_COLMAP_FIXTURES}/distorted" "${MIPNERF_COLMAP_FIXTURES}/images" "${CMAKE_CURRENT_BINARY_DIR}/cli-colmap-lens")
mipnerf_add_cli_error_test("dataset import-colmap: a lens model not read" PATTERN "unknown_lens/cameras.txt:4: camera 1 is THIN_PRISM_FISHEYE, a model mipnerf-cl does not read .*run COLMAP's image_undistorter first"
  ARGS dataset import-colmap "${MIPNERF_COLMAP_FIXTURES}/unknown_lens" "${MIPNERF_COLMAP_FIXTURES}/images" "${CMAKE_CURRENT_BINARY_DIR}/cli-colmap-bad")
mipnerf_add_cli_error_test("dataset import-colmap: a missing image" PATTERN "colmap/images: 1 of the 4 images of .*missing/images.txt are missing: view_3.png$"
  ARGS dataset import-colmap "${MIPNERF_COLMAP_FIXTURES}/missing" "${MIPNERF_COLMAP_FIXTURES}/images" "${CMAKE_CURRENT_BINARY_DIR}/cli-colmap-bad")
mipnerf_add_cli_error_test("dataset import-colmap: a malformed camera line" PATTERN "malformed/cameras.txt:4: camera 1: PINHOLE takes 4 parameters, the line has 3$"
  ARGS dataset import-colmap "${MIPNERF_COLMAP_FIXTURES}/malformed" "${MIPNERF_COLMAP_FIXTURES}/images" "${CMAKE_CURRENT_BINARY_DIR}/cli-colmap-bad")
mipnerf_add_cli_error_test("dataset import-colmap: a folder without a model" PATTERN "colmap/images: no COLMAP sparse model: expected cameras, images and points3D \\(.bin or .txt\\), found none of them$"
  ARGS dataset import-colmap "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_COLMAP_FIXTURES}/images" "${CMAKE_CURRENT_BINARY_DIR}/cli-colmap-bad")
mipnerf_add_cli_error_test("dataset import-colmap: a missing argument" PATTERN "OUT is required"
  ARGS dataset import-colmap "${MIPNERF_COLMAP_FIXTURES}/sparse" "${MIPNERF_COLMAP_FIXTURES}/images")

# Training (host/train, cli/cmd_train.cpp): bad settings are one line; a short run on the fixture scene trains,
# writes its outputs, refuses to overwrite, and resumes.
# The runner checks a pattern whole, past its ';': this one matches up to the ';' only, so its check must fail
# (WILL_FAIL: the test passes when the runner fails).
mipnerf_add_cli_error_test("a pattern is checked whole, past a semicolon" PATTERN "unknown preset 'nosuch'; the presets are: none of these"
  ARGS train --preset nosuch)
set_tests_properties("cli: a pattern is checked whole, past a semicolon" PROPERTIES WILL_FAIL TRUE)
mipnerf_add_cli_error_test("train: unknown preset" PATTERN "unknown preset 'nosuch'; the presets are: fast, mipnerf360, paper, quick, small, tiny"
  ARGS train --preset nosuch --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: bad setting value" PATTERN "setting 'num_samples' = '12x': expected an integer"
  ARGS train --num_samples 12x --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: unknown value of an enum setting" PATTERN "setting 'ray_shape' = 'sphere': expected cone \\| cylinder"
  ARGS train --ray_shape sphere --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: unknown variant" PATTERN "unknown variant 'nosuch'; the variants are: mipnerf, mipnerf-concat-pe, mipnerf-no-area-loss, mipnerf-no-ipe, mipnerf-no-misc, mipnerf-two-mlps, nerf, nerf-area, nerf-area-center, nerf-area-center-misc"
  ARGS train --variant nosuch --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: unknown --set name" PATTERN "unknown setting 'sampels'. did you mean 'num_samples', 'sampler' or 'proposal_samples'\\? \\(mipnerf-cl train --help lists every setting\\)$"
  ARGS train --set sampels=3 --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: a mistyped setting names the one meant" PATTERN "unknown setting 'stpes'. did you mean 'steps'\\? \\(mipnerf-cl train --help lists every setting\\)$"
  ARGS train --set stpes=10 --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
# Setting flags: the dash form in --help (the underscore one still parses: the variant tests below use both), typed
# from the settings table; --factor the same in train and dataset inspect (type, help and rule).
mipnerf_add_checked_test("cli: train --help shows setting flags with dashes and their types" EXPECT "--data TEXT +Dataset folder: Blender, multiscale Blender, transforms.json or an LLFF capture.*--factor INT +\\[scene\\] box-downsample.*--val-every INT +\\[execution\\]"
  COMMAND mipnerf-cl train --help)
set_tests_properties("cli: train --help shows setting flags with dashes and their types" PROPERTIES FAIL_REGULAR_EXPRESSION "--val_every INT|VALUE")
mipnerf_add_checked_test("cli: dataset inspect --help lists LLFF captures and types --factor as train does" EXPECT "Load a dataset \\(Blender, multiscale Blender, transforms.json or an LLFF capture\\).*--factor INT +box-downsample the stored images by this power of two"
  COMMAND mipnerf-cl dataset inspect --help)
mipnerf_add_cli_error_test("train: a factor that is no power of two" PATTERN "invalid configuration: factor must be a power of two, 1 to 64$"
  ARGS train --factor 3 --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("dataset inspect: a factor that is no power of two, as train says it" PATTERN "invalid configuration: factor must be a power of two, 1 to 64$"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/valid" --factor 3)
mipnerf_add_cli_error_test("dataset inspect: a factor that is no number, as train says it" PATTERN "setting 'factor' = 'two': expected an integer$"
  ARGS dataset inspect "${MIPNERF_DATA_FIXTURES}/valid" --factor two)
mipnerf_add_checked_test("cli: dataset import-colmap --help names the seven camera models it reads" EXPECT "of SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE or FULL_OPENCV cameras"
  COMMAND mipnerf-cl dataset import-colmap --help)
mipnerf_add_cli_error_test("train: invalid combination" PATTERN "invalid configuration: lr_warmup_mult must be in"
  ARGS train --lr_warmup_mult 2 --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: sampler=proposal for the NeRF baseline says whose it is" PATTERN "invalid configuration: sampler=proposal is Zip-NeRF's and mip-NeRF 360's \\(density-only proposal networks on grids or on the IPE\\); the nerf model family samples points by resampling: keep sampler=resample, or train --model mipnerf or zipnerf$"
  ARGS train --variant nerf --set sampler=proposal --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
mipnerf_add_cli_error_test("train: missing data" PATTERN "nowhere: no such file or folder"
  ARGS train --data "${MIPNERF_DATA_FIXTURES}/nowhere" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
# An output folder that cannot be made: one line naming it, before anything runs (a file sits where a folder must be).
mipnerf_add_cli_error_test("train: an --out that cannot be created" PATTERN "--out .*cli_tests.cmake/run: cannot create this folder \\(Not a directory\\). give --out a folder you can write to$"
  ARGS train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${CMAKE_CURRENT_SOURCE_DIR}/cli/cli_tests.cmake/run" --preset tiny)
set_tests_properties("cli: train: an --out that cannot be created" PROPERTIES FIXTURES_REQUIRED cli_scene)
mipnerf_add_cli_error_test("train: an --out that is a file" PATTERN "--out .*cli_tests.cmake: cannot create this folder \\(a file of that name is in the way\\). give --out a folder you can write to$"
  ARGS train --out "${CMAKE_CURRENT_SOURCE_DIR}/cli/cli_tests.cmake" --preset tiny)
mipnerf_add_cli_error_test("train: unknown key in a config file" PATTERN "bogus_key"
  ARGS train --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/unknown_key.toml" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad")
add_test(NAME "cli: train output starts empty" COMMAND ${CMAKE_COMMAND} -E rm -rf "${CMAKE_CURRENT_BINARY_DIR}/cli-train")
set_tests_properties("cli: train output starts empty" PROPERTIES FIXTURES_SETUP cli_train_clean)
mipnerf_add_checked_test("cli: train a few steps from a config file" EXPECT "val PSNR [0-9.]+ dB, SSIM [0-9.]+ over 1 images; trained 4 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene"
  --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train" --preset tiny --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml")
set_tests_properties("cli: train a few steps from a config file" PROPERTIES FIXTURES_REQUIRED "cli_scene;cli_train_clean" FIXTURES_SETUP cli_train)
mipnerf_add_checked_test("cli: train records the variant in config.json" EXPECT "\"variant\": \"mipnerf\",[ \n]*\"variant_bundle\": \"mipnerf\""
  COMMAND ${CMAKE_COMMAND} -E cat
  "${CMAKE_CURRENT_BINARY_DIR}/cli-train/config.json")
set_tests_properties("cli: train records the variant in config.json" PROPERTIES FIXTURES_REQUIRED cli_train)
mipnerf_add_cli_error_test("train: refuses to overwrite a run" PATTERN "already holds checkpoints \\(newest: step 4\\): pass --resume"
  ARGS train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train" --preset tiny
       --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml")
set_tests_properties("cli: train: refuses to overwrite a run" PROPERTIES FIXTURES_REQUIRED cli_train)
mipnerf_add_checked_test("cli: train --resume continues to more steps" EXPECT "trained 6 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene"
  --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train" --preset tiny --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml"
  --resume --steps 6)
# The resume moves the run on to step 6, so it waits for the tests that read the step-4 run (DEPENDS orders them
# under ctest -j; without it the refusal could see step 6).
set_tests_properties("cli: train --resume continues to more steps" PROPERTIES FIXTURES_REQUIRED cli_train DEPENDS "cli: train: refuses to overwrite a run;cli: train records the variant in config.json")

add_test(NAME "cli: train --profile: clear its folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${CMAKE_CURRENT_BINARY_DIR}/cli-train-profile")
set_tests_properties("cli: train --profile: clear its folder" PROPERTIES FIXTURES_SETUP cli_train_profile_clean)
mipnerf_add_checked_test("cli: train --profile prints where a step's time goes" EXPECT "\\| gemm forward \\| [0-9.]+ \\| [0-9.]+ %.*GEMM-bound limit: [0-9]+ rays/s.*over 3 profiled step"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene"
  --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-profile" --preset tiny --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml" --profile)
set_tests_properties("cli: train --profile prints where a step's time goes" PROPERTIES FIXTURES_REQUIRED "cli_scene;cli_train_profile_clean" FIXTURES_SETUP cli_train_profile)
mipnerf_add_checked_test("cli: train --profile writes profile.md" EXPECT "# Training step by stage.*\\| encoding \\|.*GEMM-bound limit"
  COMMAND ${CMAKE_COMMAND} -E cat "${CMAKE_CURRENT_BINARY_DIR}/cli-train-profile/profile.md")
set_tests_properties("cli: train --profile writes profile.md" PROPERTIES FIXTURES_REQUIRED cli_train_profile)

# Render and eval (cli/cmd_render.cpp, cli/cmd_eval.cpp, host/eval): tests/eval trains a tiny model in-process and
# also runs the real executable for end-to-end checks of what it writes.
if(TARGET test_eval)
  add_dependencies(test_eval mipnerf-cl)
  target_compile_definitions(test_eval PRIVATE MIPNERF_CLI_PATH="$<TARGET_FILE:mipnerf-cl>")
endif()

# The quality tests (tests/quality) train through the real executable.
if(TARGET test_quality)
  add_dependencies(test_quality mipnerf-cl)
  target_compile_definitions(test_quality PRIVATE MIPNERF_CLI_PATH="$<TARGET_FILE:mipnerf-cl>")
endif()

# Crash consistency (tests/reliability) kills and limits the real executable.
if(TARGET test_reliability)
  add_dependencies(test_reliability mipnerf-cl)
  target_compile_definitions(test_reliability PRIVATE MIPNERF_CLI_PATH="$<TARGET_FILE:mipnerf-cl>")
endif()

# Data-parallel training and sharded rendering under mpirun (tests/mpi): the executable, mpirun (FindMPI's
# MPIEXEC_EXECUTABLE) and whether this build has MPI; without either the tests say they were skipped.
if(TARGET test_mpi)
  add_dependencies(test_mpi mipnerf-cl)
  target_compile_definitions(test_mpi PRIVATE MIPNERF_CLI_PATH="$<TARGET_FILE:mipnerf-cl>"
    MIPNERF_MPIRUN_PATH="${MPIEXEC_EXECUTABLE}")
  if(MIPNERF_HAVE_MPI)
    target_compile_definitions(test_mpi PRIVATE MIPNERF_TEST_HAVE_MPI=1)
  endif()
endif()
# A build without MPI, started by mpirun as two copies, refuses once with what to do (the sanitizer build has no MPI).
find_program(MIPNERF_MPIRUN NAMES mpirun mpiexec)
if(NOT MIPNERF_HAVE_MPI AND MIPNERF_MPIRUN)
  mipnerf_add_checked_test("cli: mpirun of a build without MPI refuses with what to do" EXIT nonzero EXPECT "built without MPI, but an MPI launcher started 2 copies of it.*rebuild, or run it without mpirun"
  COMMAND "${MIPNERF_MPIRUN}" -np 2 $<TARGET_FILE:mipnerf-cl> devices)
  set_tests_properties("cli: mpirun of a build without MPI refuses with what to do" PROPERTIES ENVIRONMENT "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1;OMPI_MCA_rmaps_base_oversubscribe=1" FAIL_REGULAR_EXPRESSION "(rank 1|error:.*error:)")
endif()

# mipnerf-cl render / eval through the executable: a model trained a few steps on the CLI scene, an orbit and an
# evaluation of the multiscale data from it, and every kind of bad input as one line and a non-zero exit.
set(MIPNERF_RENDER_RUN "${CMAKE_CURRENT_BINARY_DIR}/cli-render-run")
set(MIPNERF_RENDER_FIXTURES "${CMAKE_CURRENT_SOURCE_DIR}/eval/fixtures")
add_test(NAME "cli: render: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_RENDER_RUN}")
mipnerf_add_checked_test("cli: render: train a model to render" EXPECT "trained 4 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene"
  --out "${MIPNERF_RENDER_RUN}" --preset tiny --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml")
set_tests_properties("cli: render: clear the run folder" PROPERTIES FIXTURES_SETUP cli_render_clean)
set_tests_properties("cli: render: train a model to render" PROPERTIES FIXTURES_REQUIRED "cli_scene;cli_render_clean" FIXTURES_SETUP cli_render_model)
find_package(Python3 COMPONENTS Interpreter REQUIRED)
# Hostile datasets through the executable (tests/cli/test_hostile_inputs.py): decompression bombs (the fuzz corpus's
# PNG and JPEG regression seeds) and a file_path out of the dataset, each one line and exit 1 with bounded peak RSS.
add_test(NAME "cli: decompression bombs and paths out of a dataset are one line each, with bounded memory"
  COMMAND Python3::Interpreter "${CMAKE_CURRENT_SOURCE_DIR}/cli/test_hostile_inputs.py" --exe $<TARGET_FILE:mipnerf-cl>
  --corpus "${CMAKE_CURRENT_SOURCE_DIR}/fuzz/corpus" --work "${CMAKE_CURRENT_BINARY_DIR}/cli-hostile")
set_tests_properties("cli: decompression bombs and paths out of a dataset are one line each, with bounded memory"
  PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV}")

# `view` through its socket (tests/view/test_server.py, on a copy of the run): forged Host, Origin and content types,
# oversized and compressed bodies, many ranges, idle connections, simultaneous path starts and renders, the token off
# loopback, Ctrl-C. Label `threads`: the thread-sanitizer stage runs it on its own build of the executable.
add_test(NAME "cli: view answers forged, oversized and simultaneous requests, and wants its token off loopback"
  COMMAND Python3::Interpreter "${CMAKE_CURRENT_SOURCE_DIR}/view/test_server.py" --exe $<TARGET_FILE:mipnerf-cl>
  --run "${MIPNERF_RENDER_RUN}")
set_tests_properties("cli: view answers forged, oversized and simultaneous requests, and wants its token off loopback"
  PROPERTIES FIXTURES_REQUIRED cli_render_model LABELS "cli;threads" TIMEOUT 600 ENVIRONMENT "${MIPNERF_TEST_ENV}")
mipnerf_add_checked_test("cli: render an orbit from a training folder" EXPECT "rendered 4 frames of an orbit \\(24x24\\) from step 4 .*render_orbit"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_RENDER_RUN}"
  --path orbit --frames 4 --size 24x24 --format both)
set_tests_properties("cli: render an orbit from a training folder" PROPERTIES FIXTURES_REQUIRED cli_render_model)
mipnerf_add_checked_test("cli: eval scores every scale of multiscale data" EXPECT "\\| 1 \\(full\\) \\| 16x16 \\| 1 \\| [0-9.]+ \\| [0-9.]+ \\|.*\\| 1/2 \\| 8x8 \\| 1 \\| [0-9.]+ \\| – \\|.*mean PSNR [0-9.]+ dB.*eval_test/metrics.json"
  COMMAND mipnerf-cl eval --checkpoint "${MIPNERF_RENDER_RUN}"
  --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene/multiscale")
set_tests_properties("cli: eval scores every scale of multiscale data" PROPERTIES FIXTURES_REQUIRED cli_render_model)
# Zip-NeRF with proposal sampling (density-only proposal rounds, their own grids and networks): trained a few steps
# through the executable, then evaluated and rendered from its checkpoint (the renderer runs the rounds for weights).
set(MIPNERF_PROPOSAL_RUN "${CMAKE_CURRENT_BINARY_DIR}/cli-proposal-run")
add_test(NAME "cli: proposal: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_PROPOSAL_RUN}")
mipnerf_add_checked_test("cli: proposal: train --model zipnerf --set sampler=proposal" EXPECT "trained 4 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${MIPNERF_PROPOSAL_RUN}"
  --model zipnerf --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml" --set sampler=proposal
  --set proposal_samples=16 --set num_samples=16 --set proposal_grid_max=128 --set grid_max=128 --set grid_hash_log2=14)
set_tests_properties("cli: proposal: clear the run folder" PROPERTIES FIXTURES_SETUP cli_proposal_clean)
set_tests_properties("cli: proposal: train --model zipnerf --set sampler=proposal" PROPERTIES FIXTURES_REQUIRED "cli_scene;cli_proposal_clean" FIXTURES_SETUP cli_proposal_model)
mipnerf_add_checked_test("cli: proposal: eval a proposal-sampled model" EXPECT "mean PSNR [0-9.]+ dB"
  COMMAND mipnerf-cl eval --checkpoint "${MIPNERF_PROPOSAL_RUN}" --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene")
set_tests_properties("cli: proposal: eval a proposal-sampled model" PROPERTIES FIXTURES_REQUIRED cli_proposal_model)
mipnerf_add_checked_test("cli: proposal: render an orbit of a proposal-sampled model" EXPECT "rendered 2 frames of an orbit \\(16x16\\) from step 4"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_PROPOSAL_RUN}" --path orbit --frames 2 --size 16x16)
set_tests_properties("cli: proposal: render an orbit of a proposal-sampled model" PROPERTIES FIXTURES_REQUIRED cli_proposal_model)
# mip-NeRF with mip-NeRF 360's proposal sampling (IPE proposal rounds on their own MLPs, the outer interlevel loss,
# the dilation): the same path through the executable, the levels it logs, its checkpoint evaluated and rendered.
set(MIPNERF_MIP_PROPOSAL_RUN "${CMAKE_CURRENT_BINARY_DIR}/cli-mip-proposal-run")
add_test(NAME "cli: mip-NeRF proposal: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_MIP_PROPOSAL_RUN}")
mipnerf_add_checked_test("cli: mip-NeRF proposal: train --set sampler=proposal" EXPECT "level 1: proposal-sampled 16 intervals from the previous histogram dilated by 0.0[0-9]+, IPE degrees 0..[0-9]+, network 1, proposal round \\(density only. outer interlevel loss, mult 1\\).*trained 4 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${MIPNERF_MIP_PROPOSAL_RUN}"
  --config "${CMAKE_CURRENT_SOURCE_DIR}/train/fixtures/short.toml" --set sampler=proposal --set proposal_samples=16
  --set num_samples=16 --set proposal_mlp_depth=2 --set proposal_mlp_width=32)
set_tests_properties("cli: mip-NeRF proposal: clear the run folder" PROPERTIES FIXTURES_SETUP cli_mip_proposal_clean)
set_tests_properties("cli: mip-NeRF proposal: train --set sampler=proposal" PROPERTIES FIXTURES_REQUIRED "cli_scene;cli_mip_proposal_clean" FIXTURES_SETUP cli_mip_proposal_model)
mipnerf_add_checked_test("cli: mip-NeRF proposal: eval its checkpoint" EXPECT "mean PSNR [0-9.]+ dB"
  COMMAND mipnerf-cl eval --checkpoint "${MIPNERF_MIP_PROPOSAL_RUN}" --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene")
set_tests_properties("cli: mip-NeRF proposal: eval its checkpoint" PROPERTIES FIXTURES_REQUIRED cli_mip_proposal_model)
mipnerf_add_checked_test("cli: mip-NeRF proposal: render an orbit of its checkpoint" EXPECT "rendered 2 frames of an orbit \\(16x16\\) from step 4"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_MIP_PROPOSAL_RUN}" --path orbit --frames 2 --size 16x16)
set_tests_properties("cli: mip-NeRF proposal: render an orbit of its checkpoint" PROPERTIES FIXTURES_REQUIRED cli_mip_proposal_model)
# The errors. Those that need a model use the run above.
mipnerf_add_cli_error_test("render: missing checkpoint" PATTERN "nowhere: no checkpoint found \\(expected a .mnck file"
  ARGS render --checkpoint "${MIPNERF_RENDER_FIXTURES}/nowhere")
mipnerf_add_cli_error_test("render: not a checkpoint" PATTERN "not_a_checkpoint.mnck: not a mipnerf-cl checkpoint"
  ARGS render --checkpoint "${MIPNERF_RENDER_FIXTURES}/not_a_checkpoint.mnck")
mipnerf_add_cli_error_test("render: --checkpoint is required" PATTERN "--checkpoint is required"
  ARGS render --path orbit)
mipnerf_add_cli_error_test("eval: missing checkpoint" PATTERN "nowhere: no checkpoint found"
  ARGS eval --checkpoint "${MIPNERF_RENDER_FIXTURES}/nowhere")
mipnerf_add_cli_error_test("render: missing camera path file" PATTERN "nowhere.json: no such camera path file"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path "${MIPNERF_RENDER_FIXTURES}/nowhere.json")
# --path: a slip names the kind meant, a split name points to --split, a folder to its transforms.json.
mipnerf_add_cli_error_test("render: a mistyped path kind names the one meant" PATTERN "--path 'sprial': did you mean 'spiral'\\? \\(--path takes orbit, spiral or a camera path file. a split's cameras: --split\\)$"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path sprial)
mipnerf_add_cli_error_test("render: a split name as --path points to --split" PATTERN "--path 'test': a dataset split's cameras are rendered with --split test \\(--path takes orbit, spiral or a camera path file\\)$"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path test)
mipnerf_add_cli_error_test("render: a mistyped camera path file names the one meant" PATTERN "fixtures/two_keyframe_path.json: no such camera path file. did you mean '.*fixtures/two_keyframes_path.json'\\?$"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path "${MIPNERF_RENDER_FIXTURES}/two_keyframe_path.json")
# The output folder is made before the model renders anything: one line, no frame (and no estimate) before it.
mipnerf_add_cli_error_test("render: an --out that cannot be created fails before the first frame" PATTERN "--out .*cli_tests.cmake/render: cannot create this folder \\(Not a directory\\). give --out a folder you can write to$"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --frames 2 --size 8x8 --out "${CMAKE_CURRENT_SOURCE_DIR}/cli/cli_tests.cmake/render")
set_tests_properties("cli: render: an --out that cannot be created fails before the first frame" PROPERTIES FIXTURES_REQUIRED cli_render_model)
# Before the first frame: the frames, their size and the time they will take, at the rate of the run's val renders.
mipnerf_add_checked_test("cli: render estimates its time from the run's val renders before the first frame" EXPECT "rendering 3 frames of 20x20 \\(0.0012 MP\\): about [0-9hms]+ at [0-9.e+-]+ s/MP \\(the run's val renders on this device, [^\n]*cli-render-run/summary.json\\)\n.*rendered 3 frames of an orbit"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --frames 3 --size 20x20 --out "${MIPNERF_RENDER_RUN}/render_estimate")
set_tests_properties("cli: render estimates its time from the run's val renders before the first frame" PROPERTIES FIXTURES_REQUIRED cli_render_model)
# An estimate over five minutes of a path says what about half the size would take, even for --video (a run recorded
# at 10^6 s/MP: 2 frames of 42x42 are 58m48s; 20x20, not 21x21, 13m20s).
add_test(NAME "cli: render: a run recorded as slow" COMMAND ${CMAKE_COMMAND} -DRUN=${MIPNERF_RENDER_RUN}
  -DOUT=${CMAKE_CURRENT_BINARY_DIR}/cli-slow-run -DRATE=1000000 -P ${CMAKE_CURRENT_SOURCE_DIR}/cli/forge_render_rate.cmake)
set_tests_properties("cli: render: a run recorded as slow" PROPERTIES FIXTURES_REQUIRED cli_render_model FIXTURES_SETUP cli_slow_run)
mipnerf_add_checked_test("cli: render: a long estimate says what half the size would take" EXPECT "rendering 2 frames of 42x42 \\(0.00353 MP\\): about 58m48s at 1e\\+06 s/MP \\([^\n]*\\); --size 20x20 would take about 13m20s, fewer --frames less\n"
  COMMAND mipnerf-cl render --checkpoint "${CMAKE_CURRENT_BINARY_DIR}/cli-slow-run" --path orbit --frames 2 --size 42x42)
set_tests_properties("cli: render: a long estimate says what half the size would take" PROPERTIES FIXTURES_REQUIRED cli_slow_run)
# A checkpoint away from its run has no recorded rate: the estimate follows the first frame.
add_test(NAME "cli: render: a checkpoint away from its run" COMMAND ${CMAKE_COMMAND} -E copy
  "${MIPNERF_RENDER_RUN}/checkpoints/ckpt_000000004.mnck" "${CMAKE_CURRENT_BINARY_DIR}/cli-lone-checkpoint/model.mnck")
set_tests_properties("cli: render: a checkpoint away from its run" PROPERTIES FIXTURES_REQUIRED cli_render_model FIXTURES_SETUP cli_lone_checkpoint)
mipnerf_add_checked_test("cli: render without a recorded rate estimates its time after the first frame" EXPECT "rendering 3 frames of 20x20 \\(0.0012 MP\\): the time it takes follows its first frame\n.*the first frame took [0-9.e+-]+ s \\([0-9.e+-]+ s/MP\\): about [0-9hms]+ for all 3 frames\n.*rendered 3 frames of an orbit"
  COMMAND mipnerf-cl render --checkpoint "${CMAKE_CURRENT_BINARY_DIR}/cli-lone-checkpoint/model.mnck" --path orbit --frames 3 --size 20x20)
set_tests_properties("cli: render without a recorded rate estimates its time after the first frame" PROPERTIES FIXTURES_REQUIRED cli_lone_checkpoint)
mipnerf_add_cli_error_test("render: malformed camera path file" PATTERN "truncated_path.json: malformed JSON at line 3"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path "${MIPNERF_RENDER_FIXTURES}/truncated_path.json")
mipnerf_add_cli_error_test("render: camera path frame without a pose" PATTERN "pose_missing_path.json: frames\\[0\\]: missing key 'transform_matrix'"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path "${MIPNERF_RENDER_FIXTURES}/pose_missing_path.json")
mipnerf_add_cli_error_test("render: camera path without a size" PATTERN "no_size_path.json: frames\\[0\\]: no image size: give 'w' and 'h'"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path "${MIPNERF_RENDER_FIXTURES}/no_size_path.json")
mipnerf_add_cli_error_test("render: bad size" PATTERN "--size '12y4': expected WIDTHxHEIGHT in pixels"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --size 12y4)
mipnerf_add_cli_error_test("render: zero width" PATTERN "--size '0x4': width and height must be at least 1 pixel"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --size 0x4)
mipnerf_add_cli_error_test("render: negative scale" PATTERN "--scale -0.5.*: the scale factor must be positive"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --scale=-0.5)
mipnerf_add_cli_error_test("render: scale and size together" PATTERN "give --scale or a size \\(--size, --width, --height\\), not both"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --scale 2 --width 10)
mipnerf_add_cli_error_test("render: too many pixels" PATTERN "has more than 2\\^32 - 1 pixels"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --size 100000x100000)
mipnerf_add_cli_error_test("render: zero supersampling" PATTERN "--supersample must be at least 1 ray per pixel"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --supersample 0)
mipnerf_add_cli_error_test("render: unknown format" PATTERN "output format 'gif': expected png, exr or both"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --format gif)
mipnerf_add_cli_error_test("render: split and path together" PATTERN "give --split .* or --path .*, not both"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --split test --path orbit)
mipnerf_add_cli_error_test("render: orbit option without an orbit" PATTERN "--fov applies to --path orbit only"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --split test --fov 40)
mipnerf_add_cli_error_test("render: elevation out of range" PATTERN "orbit: the elevation must lie strictly between -90 and 90 degrees, got 95"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --elevation 95)
mipnerf_add_cli_error_test("render: unknown split" PATTERN "transforms_nosuch.json: no such file \\(this dataset has the splits: "
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --split nosuch)
mipnerf_add_cli_error_test("eval: missing data" PATTERN "nowhere: no such file or folder"
  ARGS eval --checkpoint "${MIPNERF_RENDER_RUN}" --data "${MIPNERF_DATA_FIXTURES}/nowhere")
mipnerf_add_cli_error_test("eval: zero views" PATTERN "--views must be at least 1"
  ARGS eval --checkpoint "${MIPNERF_RENDER_RUN}" --views 0)
# Memory: what cannot fit any device stops before the first allocation, naming the setting to lower.
mipnerf_add_cli_error_test("render: a chunk beyond the device's memory" PATTERN "--chunk \\(render_chunk_rays\\) = 1000000000 needs .*: lower --chunk"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --frames 1 --size 8x8 --chunk 1000000000)
mipnerf_add_cli_error_test("train: a batch beyond the device's memory" PATTERN "the batch arrays take [0-9]+ MiB: lower batch_size"
  ARGS train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-train-bad" --preset tiny
       --batch_size 2147483647)
set_tests_properties("cli: train: a batch beyond the device's memory" PROPERTIES FIXTURES_REQUIRED cli_scene)
mipnerf_add_checked_test("cli: render a camera path's frames as keyframes of a longer path" EXPECT "rendered 5 frames of the camera path .*two_keyframes_path.json \\(16x16\\)"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_RENDER_RUN}" --path "${MIPNERF_RENDER_FIXTURES}/two_keyframes_path.json"
  --frames 5 --out "${MIPNERF_RENDER_RUN}/render_keyframes")
set_tests_properties("cli: render a camera path's frames as keyframes of a longer path" PROPERTIES FIXTURES_REQUIRED cli_render_model)
mipnerf_add_cli_error_test("render: fewer frames than keyframes" PATTERN "1 frames for 2 keyframes would skip keyframes \\(give --frames of at least"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path "${MIPNERF_RENDER_FIXTURES}/two_keyframes_path.json" --frames 1)
mipnerf_add_cli_error_test("render: --frames without a path" PATTERN "--frames applies to --path"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --split test --frames 4)
mipnerf_add_cli_error_test("render: spiral of a Blender scene" PATTERN "--path spiral follows an LLFF capture's cameras"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path spiral)
foreach(name "render: spiral of a Blender scene" "render: fewer frames than keyframes" "render: a chunk beyond the device's memory" "render: malformed camera path file" "render: camera path frame without a pose"
             "render: camera path without a size" "render: too many pixels" "render: elevation out of range"
             "render: unknown split" "eval: missing data")
  set_tests_properties("cli: ${name}" PROPERTIES FIXTURES_REQUIRED cli_render_model)
endforeach()

# mipnerf-cl bench (cli/cmd_bench.cpp, host/bench): tests/bench runs the real executable with --quick on tiny sizes;
# bad options are one line and a non-zero exit before anything is measured.
if(TARGET test_bench)
  add_dependencies(test_bench mipnerf-cl)
  target_compile_definitions(test_bench PRIVATE MIPNERF_CLI_PATH="$<TARGET_FILE:mipnerf-cl>")
endif()
# Each also carries tiny sizes, so that a check that stopped working would cost seconds, not a full benchmark.
set(MIPNERF_BENCH_TINY --sections kernels --kernel-rays 16 --kernel-samples 2 --kernel-reps 1
    --out "${CMAKE_CURRENT_BINARY_DIR}/cli-bench-bad")
mipnerf_add_cli_error_test("bench: unknown section" PATTERN "--sections: unknown section 'gpu'; the sections are: gemm, kernels, train"
  ARGS bench ${MIPNERF_BENCH_TINY} --sections gemm,gpu)
mipnerf_add_cli_error_test("bench: unknown preset" PATTERN "--presets: unknown preset 'huge'; the presets are: fast, mipnerf360, paper, quick, small, tiny"
  ARGS bench --presets tiny,huge ${MIPNERF_BENCH_TINY})
mipnerf_add_cli_error_test("bench: zero warm steps" PATTERN "--steps and --paper-steps must be at least 1"
  ARGS bench --steps 0 ${MIPNERF_BENCH_TINY})
mipnerf_add_cli_error_test("bench: bad render size" PATTERN "--render-size '8by8': expected WIDTHxHEIGHT"
  ARGS bench --render-size 8by8 ${MIPNERF_BENCH_TINY})
mipnerf_add_cli_error_test("bench: malformed --set" PATTERN "--set 'batch_size': expected name=value"
  ARGS bench --set batch_size ${MIPNERF_BENCH_TINY})
mipnerf_add_cli_error_test("bench: unknown --set name" PATTERN "unknown setting 'sampels'"
  ARGS bench --set sampels=3 ${MIPNERF_BENCH_TINY})


# The quick start's `tune --if-missing` skips the search where CLBlast does not run the MLP (gemm_backend=auto picks
# the host BLAS on a CPU device that shares host memory, as PoCL's does), even with no tuning file at hand.
mipnerf_add_checked_test("cli: tune --if-missing skips where the host BLAS runs the MLP" EXPECT "tune: not needed: on .* the MLP's products run on the host BLAS"
  COMMAND ${CMAKE_COMMAND} -E env
  "XDG_CACHE_HOME=${CMAKE_CURRENT_BINARY_DIR}/cli-tune-empty-cache" $<TARGET_FILE:mipnerf-cl> tune --if-missing --minutes 1)

# tune ends by timing the whole network on each backend the device supports and records the faster for
# gemm_backend=auto (a time box of seconds: the parameter search is cut short, the measurement still runs).
mipnerf_add_checked_test("cli: tune records which backend gemm_backend=auto takes" EXPECT "gemm_backend=auto on this device: (host|clblast) \\(whole network, 1024 rows, forward \\+ backward: clblast [0-9.]+ s"
  COMMAND ${CMAKE_COMMAND} -E env
  "XDG_CACHE_HOME=${CMAKE_CURRENT_BINARY_DIR}/cli-tune-cache" $<TARGET_FILE:mipnerf-cl> tune --minutes 0.2 --rows 1024
  --kernel-rows 128 --width 128 --input-width 72 --view-branch-width 64 --output "${CMAKE_CURRENT_BINARY_DIR}/cli-tune-cache/t.json"
  --host-gemm-presets tiny --host-gemm-rounds 1)

# tune --host-gemm: the CPU GEMM library per product of the host MLP (every library built in, timed and checked),
# into the device's file; then --if-missing leaves a file that has the choice alone.
add_test(NAME "cli: tune --host-gemm: clear the cache" COMMAND ${CMAKE_COMMAND} -E rm -rf
  "${CMAKE_CURRENT_BINARY_DIR}/cli-tune-host-cache")
set_tests_properties("cli: tune --host-gemm: clear the cache" PROPERTIES FIXTURES_SETUP cli_tune_host_clean)
mipnerf_add_checked_test("cli: tune --host-gemm chooses a CPU GEMM library per product of the host MLP"
  EXPECT "forward 256x64x60 +openblas [0-9]+ .*-> (openblas|blis|onednn|libxsmm)\n.*library per product is in .*cli-tune-host-cache"
  COMMAND ${CMAKE_COMMAND} -E env "XDG_CACHE_HOME=${CMAKE_CURRENT_BINARY_DIR}/cli-tune-host-cache"
  $<TARGET_FILE:mipnerf-cl> tune --host-gemm --width 64 --input-width 60 --view-branch-width 32
  --host-gemm-presets tiny --host-gemm-rounds 1)
set_tests_properties("cli: tune --host-gemm chooses a CPU GEMM library per product of the host MLP"
  PROPERTIES FIXTURES_REQUIRED cli_tune_host_clean FIXTURES_SETUP cli_tune_host)
mipnerf_add_checked_test("cli: tune --host-gemm --if-missing keeps a file that has the choice"
  EXPECT "already chooses the host MLP's libraries; nothing to do"
  COMMAND ${CMAKE_COMMAND} -E env "XDG_CACHE_HOME=${CMAKE_CURRENT_BINARY_DIR}/cli-tune-host-cache"
  $<TARGET_FILE:mipnerf-cl> tune --host-gemm --if-missing)
set_tests_properties("cli: tune --host-gemm --if-missing keeps a file that has the choice"
  PROPERTIES FIXTURES_REQUIRED cli_tune_host)

# Val scores during training and their curves: train --set val_every writes val_log.csv, plot draws it as SVG and PNG.
add_test(NAME "cli: train with val_every: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf
  "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every")
set_tests_properties("cli: train with val_every: clear the run folder" PROPERTIES FIXTURES_SETUP cli_val_every_clean)
mipnerf_add_checked_test("cli: train with val_every scores val views during training" EXPECT "score val at step 3 \\(1 image\\) \\[#+\\] [0-9]+/[0-9]+ 100%.*score val at step 6 \\(1 image\\).*trained 6 steps"
  COMMAND mipnerf-cl train
  --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every" --preset tiny
  --steps 6 --set val_every=3 --val_views 1)
set_tests_properties("cli: train with val_every scores val views during training" PROPERTIES FIXTURES_REQUIRED "cli_scene;cli_val_every_clean" FIXTURES_SETUP cli_val_every)
# Each val render of a run has its ground truth and error image beside it (what `mipnerf-cl view` shows beside it).
add_test(NAME "cli: train writes each val render's ground truth and error image beside it"
  COMMAND ${CMAKE_COMMAND} -E md5sum "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every/val/000_scale0.png"
  "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every/val/000_scale0_gt.png"
  "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every/val/000_scale0_error.png")
set_tests_properties("cli: train writes each val render's ground truth and error image beside it"
  PROPERTIES FIXTURES_REQUIRED cli_val_every)
foreach(format svg png)
  mipnerf_add_checked_test("cli: plot draws a run's val curve as ${format}" EXPECT "wrote .*cli-val-every/curves.${format} \\(2 curves\\)"
  COMMAND mipnerf-cl plot
    "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every" "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every"
    --out "${CMAKE_CURRENT_BINARY_DIR}/cli-val-every/curves.${format}" --title "cli test")
  set_tests_properties("cli: plot draws a run's val curve as ${format}" PROPERTIES FIXTURES_REQUIRED cli_val_every)
endforeach()
mipnerf_add_cli_error_test("plot: a folder without val scores" PATTERN "cli-scene/val_log.csv: no val scores in this run folder; train with --set val_every=N"
  ARGS plot "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-plot-bad.svg")
mipnerf_add_cli_error_test("plot: an unknown picture format" PATTERN "cli-plot-bad.pdf: a plot is written as .svg or .png; '.pdf' is neither"
  ARGS plot "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-plot-bad.pdf")
mipnerf_add_cli_error_test("plot: an unknown x axis" PATTERN "--x: .*minutes.*not in"
  ARGS plot "${CMAKE_CURRENT_BINARY_DIR}/cli-scene" --out "${CMAKE_CURRENT_BINARY_DIR}/cli-plot-bad.svg" --x minutes)

# Every --variant trains through the executable (the bundle, not the model-family setting of the same name) and is
# recorded as variant_bundle.
foreach(variant mipnerf-no-ipe nerf-area-center-misc mipnerf-concat-pe)
  add_test(NAME "cli: train --variant ${variant}: clear the run folder" COMMAND ${CMAKE_COMMAND} -E rm -rf
    "${CMAKE_CURRENT_BINARY_DIR}/cli-variant-${variant}")
  set_tests_properties("cli: train --variant ${variant}: clear the run folder" PROPERTIES
    FIXTURES_SETUP cli_variant_clean_${variant})
  mipnerf_add_checked_test("cli: train --variant ${variant}" EXPECT "trained 2 steps"
  COMMAND mipnerf-cl train --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene"
    --out "${CMAKE_CURRENT_BINARY_DIR}/cli-variant-${variant}" --preset tiny --variant ${variant} --steps 2
    --val-views 1 --checkpoint-every 1000)
  set_tests_properties("cli: train --variant ${variant}" PROPERTIES FIXTURES_REQUIRED "cli_scene;cli_variant_clean_${variant}"
    FIXTURES_SETUP cli_variant_${variant})
endforeach()
# The setting flags above were spelt with dashes (--val-views, --checkpoint-every): they took effect.
mipnerf_add_checked_test("cli: train takes a setting flag spelt with dashes" EXPECT "\"checkpoint_every\": 1000,.*\"val_views\": 1,"
  COMMAND ${CMAKE_COMMAND} -E cat "${CMAKE_CURRENT_BINARY_DIR}/cli-variant-mipnerf-no-ipe/config.json")
set_tests_properties("cli: train takes a setting flag spelt with dashes" PROPERTIES FIXTURES_REQUIRED cli_variant_mipnerf-no-ipe)

# Photos end to end (issue 26). A forward-facing capture of JPEG photos trains as an LLFF capture (--factor 2
# box-downsamples the JPEGs: no images_2/), renders its spiral and is evaluated; `dataset inspect` shows the effects
# train chooses.
set(MIPNERF_JPEG_LLFF "${CMAKE_CURRENT_BINARY_DIR}/cli-jpeg-llff")
add_test(NAME "cli: JPEG LLFF: clear its folders" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_JPEG_LLFF}"
  "${MIPNERF_JPEG_LLFF}-run")
set_tests_properties("cli: JPEG LLFF: clear its folders" PROPERTIES FIXTURES_SETUP cli_jpeg_llff_clean)
mipnerf_add_checked_test("cli: make-scene --forward-facing --jpeg writes JPEG photos"
  EXPECT "an LLFF capture of 20 views at 64x48 \\(images/, poses_bounds.npy; JPEG\\)"
  COMMAND mipnerf-cl make-scene "${MIPNERF_JPEG_LLFF}" --forward-facing --jpeg --size 64 --factor 1 --samples 1)
set_tests_properties("cli: make-scene --forward-facing --jpeg writes JPEG photos" PROPERTIES
  FIXTURES_REQUIRED cli_jpeg_llff_clean FIXTURES_SETUP cli_jpeg_llff)
mipnerf_add_checked_test("cli: dataset inspect of a JPEG LLFF capture shows the effects train chooses"
  EXPECT "format LLFF \\(poses_bounds.npy\\), background black, factor 2\nscene: forward-facing LLFF → NDC rays, cylinders.*scale 0 \\(/1\\): 17 images 32x24"
  COMMAND mipnerf-cl dataset inspect "${MIPNERF_JPEG_LLFF}" --factor 2)
set_tests_properties("cli: dataset inspect of a JPEG LLFF capture shows the effects train chooses" PROPERTIES
  FIXTURES_REQUIRED cli_jpeg_llff)
mipnerf_add_checked_test("cli: train on a JPEG LLFF capture, factor 2 box-downsampled from the JPEGs"
  EXPECT "scene: forward-facing LLFF → NDC rays, cylinders.*val PSNR [0-9.]+ dB.*trained 4 steps"
  COMMAND mipnerf-cl train --data "${MIPNERF_JPEG_LLFF}" --out "${MIPNERF_JPEG_LLFF}-run" --preset tiny --factor 2
  --steps 4 --val_views 1)
set_tests_properties("cli: train on a JPEG LLFF capture, factor 2 box-downsampled from the JPEGs" PROPERTIES
  FIXTURES_REQUIRED cli_jpeg_llff FIXTURES_SETUP cli_jpeg_llff_run)
mipnerf_add_checked_test("cli: render the spiral of a JPEG LLFF run"
  EXPECT "rendered 2 frames of the spiral of .*cli-jpeg-llff \\(32x24\\)"
  COMMAND mipnerf-cl render --checkpoint "${MIPNERF_JPEG_LLFF}-run" --path spiral --frames 2)
mipnerf_add_checked_test("cli: eval a JPEG LLFF run on its held-out views"
  EXPECT "mean PSNR [0-9.]+ dB, SSIM [0-9.]+ over 3 images"
  COMMAND mipnerf-cl eval --checkpoint "${MIPNERF_JPEG_LLFF}-run")
set_tests_properties("cli: render the spiral of a JPEG LLFF run" "cli: eval a JPEG LLFF run on its held-out views"
  PROPERTIES FIXTURES_REQUIRED cli_jpeg_llff_run)

# COLMAP run from the tool (Debian `colmap`, installed by install-deps.sh --for-tests) on the forward-facing scene's
# JPEG photos: every view registers, the forward-facing cameras become an LLFF capture that trains in NDC with
# cylinders; the same model imported as transforms.json (JPEG photos referenced) trains, renders and evaluates too.
# Without colmap the tests report skipped (a failure under CI=true, where it is installed).
find_program(MIPNERF_COLMAP colmap)
set(MIPNERF_PHOTOS "${CMAKE_CURRENT_BINARY_DIR}/cli-photos")
set(photo_tests "cli: dataset from-photos registers a forward-facing JPEG capture as LLFF"
  "cli: train on a capture from photos in NDC with cylinders"
  "cli: import-colmap of JPEG photos as transforms.json" "cli: train on an imported transforms.json of JPEG photos"
  "cli: render and eval an imported transforms.json of JPEG photos"
  "cli: dataset from-photos of textureless photos finds no model, saying so"
  "cli: dataset from-photos maps a capture of small parallax with settings for small baselines"
  "cli: dataset from-photos registers photos taken all around as a 360-degree capture"
  "cli: train on photos taken all around: contracted, proposal-sampled"
  "cli: render the orbit of a run on photos taken all around")
if(MIPNERF_COLMAP)
  add_test(NAME "cli: photos: clear their folders" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_PHOTOS}"
    "${MIPNERF_PHOTOS}-dataset" "${MIPNERF_PHOTOS}-run" "${MIPNERF_PHOTOS}-transforms" "${MIPNERF_PHOTOS}-transforms-run"
    "${MIPNERF_PHOTOS}-textureless" "${MIPNERF_PHOTOS}-narrow" "${MIPNERF_PHOTOS}-narrow-dataset"
    "${MIPNERF_PHOTOS}-around" "${MIPNERF_PHOTOS}-around-dataset" "${MIPNERF_PHOTOS}-around-run")
  set_tests_properties("cli: photos: clear their folders" PROPERTIES FIXTURES_SETUP cli_photos_clean)
  mipnerf_add_checked_test("cli: photos: a forward-facing capture of 256x192 JPEGs"
    EXPECT "an LLFF capture of 20 views at 256x192"
    COMMAND mipnerf-cl make-scene "${MIPNERF_PHOTOS}" --forward-facing --jpeg --size 256 --factor 1 --samples 2)
  set_tests_properties("cli: photos: a forward-facing capture of 256x192 JPEGs" PROPERTIES
    FIXTURES_REQUIRED cli_photos_clean FIXTURES_SETUP cli_photos)
  mipnerf_add_checked_test("cli: dataset from-photos registers a forward-facing JPEG capture as LLFF"
    EXPECT "imported 20 images \\(1 camera: SIMPLE_PINHOLE\\).*layout: LLFF, forward-facing cameras.*train on it: mipnerf-cl train --data [^\n]*cli-photos-dataset"
    COMMAND mipnerf-cl dataset from-photos "${MIPNERF_PHOTOS}/images" "${MIPNERF_PHOTOS}-dataset" --max-features 2048)
  set_tests_properties("cli: dataset from-photos registers a forward-facing JPEG capture as LLFF" PROPERTIES
    FIXTURES_REQUIRED cli_photos FIXTURES_SETUP cli_photos_dataset TIMEOUT 900)
  mipnerf_add_checked_test("cli: train on a capture from photos in NDC with cylinders"
    EXPECT "scene: forward-facing LLFF → NDC rays, cylinders.*trained 4 steps"
    COMMAND mipnerf-cl train --data "${MIPNERF_PHOTOS}-dataset" --out "${MIPNERF_PHOTOS}-run" --preset tiny --factor 4
    --steps 4 --val_views 1)
  set_tests_properties("cli: train on a capture from photos in NDC with cylinders" PROPERTIES
    FIXTURES_REQUIRED cli_photos_dataset)
  mipnerf_add_checked_test("cli: import-colmap of JPEG photos as transforms.json"
    EXPECT "imported 20 images .*layout: transforms.json, asked for \\(--layout transforms\\)"
    COMMAND mipnerf-cl dataset import-colmap "${MIPNERF_PHOTOS}-dataset/colmap/sparse/0" "${MIPNERF_PHOTOS}/images"
    "${MIPNERF_PHOTOS}-transforms" --layout transforms)
  set_tests_properties("cli: import-colmap of JPEG photos as transforms.json" PROPERTIES
    FIXTURES_REQUIRED cli_photos_dataset FIXTURES_SETUP cli_photos_transforms)
  # The same forward-facing capture as a transforms.json trains in NDC as its LLFF import does.
  mipnerf_add_checked_test("cli: train on an imported transforms.json of JPEG photos"
    EXPECT "the NDC world of a forward-facing capture.*scene: transforms.json of forward-facing photos → NDC rays, cylinders, black background.*trained 4 steps"
    COMMAND mipnerf-cl train --data "${MIPNERF_PHOTOS}-transforms/transforms.json" --out "${MIPNERF_PHOTOS}-transforms-run"
    --preset tiny --factor 4 --steps 4 --val_views 1)
  set_tests_properties("cli: train on an imported transforms.json of JPEG photos" PROPERTIES
    FIXTURES_REQUIRED cli_photos_transforms FIXTURES_SETUP cli_photos_transforms_run)
  mipnerf_add_checked_test("cli: render and eval an imported transforms.json of JPEG photos"
    EXPECT "mean PSNR [0-9.]+ dB, SSIM [0-9.]+ over 3 images"
    COMMAND mipnerf-cl eval --checkpoint "${MIPNERF_PHOTOS}-transforms-run" --views 3)
  set_tests_properties("cli: render and eval an imported transforms.json of JPEG photos" PROPERTIES
    FIXTURES_REQUIRED cli_photos_transforms_run)
  mipnerf_add_checked_test("cli: dataset from-photos of textureless photos finds no model, saying so" EXIT nonzero
    EXPECT "error: COLMAP found no model: no two of the 4 photos share enough matching features \\(too little texture"
    COMMAND mipnerf-cl dataset from-photos "${MIPNERF_DATA_FIXTURES}/textureless" "${MIPNERF_PHOTOS}-textureless")
  set_tests_properties("cli: dataset from-photos of textureless photos finds no model, saying so" PROPERTIES
    FIXTURES_REQUIRED cli_photos_clean)
  # A forward-facing capture of small parallax (the camera grid 0.06 wide, 4 from the scene: neighbours 0.3° apart):
  # COLMAP's default mapper settings started models that stopped growing under 10 photos and were dropped, in each
  # of 5 runs; the settings for small baselines then registered all 12 (at worst after one more matching). ~20 s.
  # The test asks for the outcome, whichever way COLMAP's randomness goes (the small-baseline path itself is
  # checked deterministically with the stand-in COLMAP below).
  mipnerf_add_checked_test("cli: photos: a forward-facing capture of small parallax"
    EXPECT "an LLFF capture of 12 views at 256x192"
    COMMAND mipnerf-cl make-scene "${MIPNERF_PHOTOS}-narrow" --forward-facing --jpeg --size 256 --factor 1 --samples 2
    --grid 4x3 --grid-width 0.06)
  set_tests_properties("cli: photos: a forward-facing capture of small parallax" PROPERTIES
    FIXTURES_REQUIRED cli_photos_clean FIXTURES_SETUP cli_photos_narrow)
  mipnerf_add_checked_test("cli: dataset from-photos maps a capture of small parallax with settings for small baselines"
    EXPECT "imported 1[0-2] images \\(1 camera: SIMPLE_PINHOLE\\).*layout: LLFF"
    COMMAND mipnerf-cl dataset from-photos "${MIPNERF_PHOTOS}-narrow/images" "${MIPNERF_PHOTOS}-narrow-dataset"
    --max-features 2048)
  set_tests_properties("cli: dataset from-photos maps a capture of small parallax with settings for small baselines"
    PROPERTIES FIXTURES_REQUIRED cli_photos_narrow TIMEOUT 600)
  # Photos taken all around (issue 45): the unbounded scene with its noise texture (COLMAP put the checker's and
  # stripes' photos all on one side), 40 JPEGs of 256x192. Every photo registered in each of 6 runs (~22 s each on 2
  # cores); the test allows COLMAP's run-to-run variation to leave up to 4 out after its attempts, as above. The
  # import sees a 360-degree capture and writes a transforms.json, train contracts it with no setting, as a user's
  # photos around a thing would be, and the orbit renders.
  mipnerf_add_checked_test("cli: photos: 40 JPEGs taken all around"
    EXPECT "a 360-degree LLFF capture of 40 views at 256x192"
    COMMAND mipnerf-cl make-scene "${MIPNERF_PHOTOS}-around" --unbounded --texture noise --jpeg --factor 1)
  set_tests_properties("cli: photos: 40 JPEGs taken all around" PROPERTIES
    FIXTURES_REQUIRED cli_photos_clean FIXTURES_SETUP cli_photos_around)
  mipnerf_add_checked_test("cli: dataset from-photos registers photos taken all around as a 360-degree capture"
    EXPECT "imported (3[6-9]|40) images \\(1 camera: SIMPLE_PINHOLE\\).*layout: transforms.json, cameras looking from around the scene \\(a 360-degree capture\\)"
    COMMAND mipnerf-cl dataset from-photos "${MIPNERF_PHOTOS}-around/images" "${MIPNERF_PHOTOS}-around-dataset"
    --max-features 2048)
  set_tests_properties("cli: dataset from-photos registers photos taken all around as a 360-degree capture" PROPERTIES
    FIXTURES_REQUIRED cli_photos_around FIXTURES_SETUP cli_photos_around_dataset TIMEOUT 600)
  mipnerf_add_checked_test("cli: train on photos taken all around: contracted, proposal-sampled"
    EXPECT "scene: transforms.json of photos taken all around \\(360°\\) → cones[^\n]*mip-NeRF unbounded as mip-NeRF 360.*trained 4 steps"
    COMMAND mipnerf-cl train --data "${MIPNERF_PHOTOS}-around-dataset/transforms.json" --out "${MIPNERF_PHOTOS}-around-run"
    --preset tiny --factor 4 --steps 4 --val_views 1)
  set_tests_properties("cli: train on photos taken all around: contracted, proposal-sampled" PROPERTIES
    FIXTURES_REQUIRED cli_photos_around_dataset FIXTURES_SETUP cli_photos_around_run)
  mipnerf_add_checked_test("cli: render the orbit of a run on photos taken all around"
    EXPECT "rendered 2 frames of an orbit \\(64x48\\)"
    COMMAND mipnerf-cl render --checkpoint "${MIPNERF_PHOTOS}-around-run" --path orbit --frames 2)
  set_tests_properties("cli: render the orbit of a run on photos taken all around" PROPERTIES
    FIXTURES_REQUIRED cli_photos_around_run)
else()
  foreach(name IN LISTS photo_tests)
    add_test(NAME "${name}" COMMAND ${CMAKE_COMMAND} -E echo
      "skipped: COLMAP (Debian package 'colmap') was not found when the build was configured")
    set_tests_properties("${name}" PROPERTIES SKIP_REGULAR_EXPRESSION "skipped: COLMAP")
  endforeach()
endif()
# Matching and mapping run again while photos stay unregistered (COLMAP's result varies from run to run), through a stand-in
# for COLMAP whose first mapping registers 2 of the 3 fixture views and any later one all 3; with one attempt the
# incomplete model is what there is, and the tool says so.
set(MIPNERF_FAKE_COLMAP_OUT "${CMAKE_CURRENT_BINARY_DIR}/cli-fake-colmap")
mipnerf_add_checked_test("cli: dataset from-photos matches and maps again while photos stay unregistered, keeping the best run"
  EXPECT "COLMAP's mapper registered 2 of 3 photos; matching and mapping again \\(attempt 2 of 3[^\n]*\n.*imported 3 images"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
mipnerf_add_checked_test("cli: dataset from-photos with one mapper attempt reports the photos left out" EXIT nonzero
  EXPECT "error: COLMAP registered only 2 of 3 photos \\([^\n]*cli-fake-colmap-once/colmap/sparse/0\\)"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-once"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh" --mapper-attempts 1)
# A photo COLMAP registered without a sparse point in front of it (its pose unchecked; an LLFF capture cannot take its
# depth bounds): the run counts as incomplete and maps again; with one attempt the photo is left out, named.
mipnerf_add_checked_test("cli: dataset from-photos maps again when a registered photo sees no points"
  EXPECT "COLMAP's mapper registered 3 of 3 photos, 2 of them with sparse points in front; matching and mapping again \\(attempt 2 of 3[^\n]*\n.*imported 3 images"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-unseen"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
mipnerf_add_checked_test("cli: dataset from-photos leaves out a registered photo that sees no points, naming it"
  EXIT nonzero
  EXPECT "warning: COLMAP registered view_2.png but fewer than 2 of its sparse points lie in front of it: [^\n]*left out\n.*error: COLMAP registered only 2 of 3 photos"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-unseen-once"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh" --mapper-attempts 1)
set_tests_properties("cli: dataset from-photos maps again when a registered photo sees no points"
  "cli: dataset from-photos leaves out a registered photo that sees no points, naming it"
  PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV};FAKE_COLMAP_SCENARIO=unseen-view")
# A mapper that finds no pair of photos to start from (as COLMAP's defaults on a forward-facing capture of small
# parallax): the same matches are mapped again with the settings for small baselines (--Mapper.init_min_tri_angle),
# without matching again (the stand-in fails the run if it does); when even those find no pair, the error says so.
mipnerf_add_checked_test("cli: dataset from-photos maps again with settings for small baselines when no pair can start a model"
  EXPECT "found no pair of photos to start from with enough parallax[^\n]*: mapping the same matches again with settings for small baselines \\(Mapper.init_min_tri_angle 2.*registered 3 of 3 photos with the settings for small baselines\n.*imported 3 images"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-small-baseline"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
mipnerf_add_checked_test("cli: dataset from-photos says when no pair of photos can start a model, even for small baselines"
  EXIT nonzero
  EXPECT "error: COLMAP found no model: no pair of the 3 photos could start one, even with settings for small baselines: [^\n]*moving the camera sideways"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-no-pair"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
mipnerf_add_checked_test("cli: dataset from-photos says when no photos match"
  EXIT nonzero EXPECT "error: COLMAP found no model: no two of the 3 photos share enough matching features"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-no-matches"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
# COLMAP numbers its models in the order it starts them, and a later one can be the largest: the largest is imported
# and renumbered sparse/0 (the one `dataset import-colmap OUT/colmap/sparse/0` then reads), the other takes its number.
mipnerf_add_checked_test("cli: dataset from-photos imports the largest of COLMAP's models, renumbered sparse/0"
  EXPECT "imported 3 images [^\n]*cli-fake-colmap-two-models/colmap/sparse/0 \\(text\\)"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-two-models"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
set_tests_properties("cli: dataset from-photos imports the largest of COLMAP's models, renumbered sparse/0"
  PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV};FAKE_COLMAP_SCENARIO=two-models")
mipnerf_add_checked_test("cli: import-colmap of the model from-photos renumbered sparse/1 has the smaller model"
  EXPECT "imported 2 images [^\n]*cli-fake-colmap-two-models/colmap/sparse/1"
  COMMAND mipnerf-cl dataset import-colmap "${MIPNERF_FAKE_COLMAP_OUT}-two-models/colmap/sparse/1"
  "${MIPNERF_COLMAP_FIXTURES}/images" "${MIPNERF_FAKE_COLMAP_OUT}-two-models-other" --layout transforms)
set_tests_properties("cli: dataset from-photos imports the largest of COLMAP's models, renumbered sparse/0"
  PROPERTIES FIXTURES_SETUP cli_fake_two_models)
set_tests_properties("cli: import-colmap of the model from-photos renumbered sparse/1 has the smaller model"
  PROPERTIES FIXTURES_REQUIRED cli_fake_two_models)
set_tests_properties("cli: dataset from-photos maps again with settings for small baselines when no pair can start a model"
  PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV};FAKE_COLMAP_SCENARIO=forward-facing")
set_tests_properties("cli: dataset from-photos says when no pair of photos can start a model, even for small baselines"
  PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV};FAKE_COLMAP_SCENARIO=no-initial-pair")
set_tests_properties("cli: dataset from-photos says when no photos match"
  PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV};FAKE_COLMAP_SCENARIO=no-matches")
# Photos of another size than most (written into the build tree by tests/data/fixtures/photo_sizes/make_fixture.py: 3
# at 8x6, 2 at 16x12) are read from their headers before COLMAP runs, left out with a warning naming each and its
# size, and never given to COLMAP (the stand-in fails feature extraction unless its list is the 3); without a size
# held by more than half of the photos, one line refuses.
set(MIPNERF_PHOTO_SIZES "${CMAKE_CURRENT_BINARY_DIR}/cli-fixtures/photo_sizes")
add_test(NAME "cli: dataset from-photos: write the photo-size fixtures"
  COMMAND Python3::Interpreter -B "${CMAKE_CURRENT_SOURCE_DIR}/data/fixtures/photo_sizes/make_fixture.py" "${MIPNERF_PHOTO_SIZES}")
set_tests_properties("cli: dataset from-photos: write the photo-size fixtures" PROPERTIES FIXTURES_SETUP cli_photo_sizes)
mipnerf_add_checked_test("cli: dataset from-photos leaves out photos of another size than most, naming each"
  EXPECT "warning: 2 of 5 photos are not 8x6 like the others and are left out [^\n]*: wide_0.png \\(16x12\\), wide_1.png \\(16x12\\); resize them to 8x6 to include them\nmipnerf-cl: COLMAP on 3 photos \\(8x6\\).*imported 3 images"
  COMMAND mipnerf-cl dataset from-photos "${MIPNERF_PHOTO_SIZES}" "${MIPNERF_FAKE_COLMAP_OUT}-sizes"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
set_tests_properties("cli: dataset from-photos leaves out photos of another size than most, naming each"
  PROPERTIES ENVIRONMENT "${MIPNERF_TEST_ENV};FAKE_COLMAP_EXPECT_PHOTOS=view_0.png view_1.png view_2.png"
  FIXTURES_REQUIRED cli_photo_sizes)
mipnerf_add_cli_error_test("dataset from-photos: photos of two sizes, neither held by most" PATTERN "photo_sizes/no_majority: photos of 2 sizes and none held by more than half \\(2 at 8x6, 2 at 16x12\\); [^\n]*resize them to one"
  ARGS dataset from-photos "${MIPNERF_PHOTO_SIZES}/no_majority" "${CMAKE_CURRENT_BINARY_DIR}/cli-photos-bad"
  --colmap "${CMAKE_CURRENT_SOURCE_DIR}/cli/fake_colmap.sh")
set_tests_properties("cli: dataset from-photos: photos of two sizes, neither held by most"
  PROPERTIES FIXTURES_REQUIRED cli_photo_sizes)
mipnerf_add_cli_error_test("dataset from-photos: COLMAP missing" PATTERN "COLMAP was not found \\(`nosuch-colmap`\\): install the Debian package 'colmap'"
  ARGS dataset from-photos "${MIPNERF_DATA_FIXTURES}/textureless" "${CMAKE_CURRENT_BINARY_DIR}/cli-photos-bad" --colmap nosuch-colmap)
mipnerf_add_cli_error_test("dataset from-photos: too few photos" PATTERN "fixtures/valid: 0 photos \\(PNG or JPEG\\); COLMAP needs at least 3"
  ARGS dataset from-photos "${MIPNERF_DATA_FIXTURES}/valid" "${CMAKE_CURRENT_BINARY_DIR}/cli-photos-bad")
mipnerf_add_cli_error_test("dataset from-photos: unknown matcher" PATTERN "--matcher 'fast': expected exhaustive"
  ARGS dataset from-photos "${MIPNERF_DATA_FIXTURES}/textureless" "${CMAKE_CURRENT_BINARY_DIR}/cli-photos-bad" --matcher fast)
mipnerf_add_cli_error_test("dataset import-colmap: unknown layout" PATTERN "--layout 'nerf': expected auto, llff or transforms"
  ARGS dataset import-colmap "${MIPNERF_COLMAP_FIXTURES}/sparse" "${MIPNERF_COLMAP_FIXTURES}/images" "${CMAKE_CURRENT_BINARY_DIR}/cli-colmap-bad" --layout nerf)

# Renders as video (io/video, eval/render_job, cli/cmd_render.cpp): an orbit of the model above as an H.264 MP4 beside
# its PNG frames, and --video's bad input as one line. tests/eval (test_video_render.cpp) decodes such a video and
# compares every frame with the PNG of the same frame.
set(MIPNERF_VIDEO_OUT "${CMAKE_CURRENT_BINARY_DIR}/cli-video")
if(MIPNERF_HAVE_VIDEO)
  add_test(NAME "cli: render --video: clear its folder" COMMAND ${CMAKE_COMMAND} -E rm -rf "${MIPNERF_VIDEO_OUT}")
  set_tests_properties("cli: render --video: clear its folder" PROPERTIES FIXTURES_SETUP cli_video_clean)
  mipnerf_add_checked_test("cli: render --video writes an orbit as an MP4 beside its PNG frames"
    EXPECT "rendered 4 frames of an orbit \\(24x24\\) from step 4 [^\n]*; images in [^\n]*cli-video/orbit; video in [^\n]*cli-video/movie/orbit.mp4 \\(24 fps\\)"
    COMMAND mipnerf-cl render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --frames 4 --size 24x24 --format png
    --video "${MIPNERF_VIDEO_OUT}/movie/orbit.mp4" --fps 24 --out "${MIPNERF_VIDEO_OUT}/orbit")
  mipnerf_add_checked_test("cli: render --video --format none writes the video and no image"
    EXPECT "rendered 4 frames of an orbit \\(24x24\\) [^\n]*; records in [^\n]*cli-video/none; video in [^\n]*cli-video/none.mp4 \\(30 fps\\)"
    COMMAND mipnerf-cl render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --frames 4 --size 24x24 --format none
    --video "${MIPNERF_VIDEO_OUT}/none.mp4" --out "${MIPNERF_VIDEO_OUT}/none")
  mipnerf_add_cli_error_test("render: --video with --fps 0" PATTERN "bad/orbit.mp4: 0 frames per second: the frame rate must lie in \\(0, 1000.$"
    ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --video "${MIPNERF_VIDEO_OUT}/bad/orbit.mp4" --fps 0)
  mipnerf_add_cli_error_test("render: --video with --crf out of range" PATTERN "orbit.mp4: CRF 52: libx264's constant rate factor lies in 0..51"
    ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --video "${MIPNERF_VIDEO_OUT}/bad/orbit.mp4" --crf 52)
  mipnerf_add_cli_error_test("render: --video in a folder that cannot be made" PATTERN "not_a_checkpoint.mnck/orbit.mp4: cannot create its folder"
    ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --video "${MIPNERF_RENDER_FIXTURES}/not_a_checkpoint.mnck/orbit.mp4")
  mipnerf_add_cli_error_test("render: --video that is not an MP4" PATTERN "orbit.avi: a video is written as H.264 in an MP4 file: give a file name ending in .mp4"
    ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --video "${MIPNERF_VIDEO_OUT}/bad/orbit.avi")
  mipnerf_add_cli_error_test("render: --video of an odd size" PATTERN "orbit.mp4: frames of 25x24 pixels: H.264 video in 4:2:0 \\(yuv420p\\) needs an even width and height; render at an even size, e.g. 26x24"
    ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --frames 2 --size 25x24 --video "${MIPNERF_VIDEO_OUT}/bad/orbit.mp4")
  mipnerf_add_cli_error_test("render: --video of frames of differing sizes" PATTERN "test.mp4: frame 2 is 8x8 but frame 1 is 16x16: a video's frames share one size"
    ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --data "${CMAKE_CURRENT_BINARY_DIR}/cli-scene/multiscale" --video "${MIPNERF_VIDEO_OUT}/bad/test.mp4")
  set_tests_properties("cli: render --video writes an orbit as an MP4 beside its PNG frames"
    "cli: render --video --format none writes the video and no image" PROPERTIES FIXTURES_REQUIRED "cli_render_model;cli_video_clean")
  set_tests_properties("cli: render: --video of an odd size" "cli: render: --video of frames of differing sizes" PROPERTIES
    FIXTURES_REQUIRED "cli_render_model;cli_scene")
else()
  mipnerf_add_cli_error_test("render: --video without FFmpeg says what to install" PATTERN "orbit.mp4: this mipnerf-cl was built without FFmpeg, which encodes videos: install the Debian packages libavformat-dev libavcodec-dev libswscale-dev libavutil-dev"
    ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --video "${MIPNERF_VIDEO_OUT}/orbit.mp4")
endif()
mipnerf_add_cli_error_test("render: --format none without --video" PATTERN "--format none writes no images: give --video FILE.mp4 as well"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --format none)
mipnerf_add_cli_error_test("render: --fps without --video" PATTERN "--fps applies to --video only"
  ARGS render --checkpoint "${MIPNERF_RENDER_RUN}" --path orbit --fps 24)
