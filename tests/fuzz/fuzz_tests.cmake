# The libFuzzer targets (MIPNERF_FUZZ, clang only; cmake/Sanitizers.cmake), one per reader of outside data, each a
# short CTest entry (label `fuzz`): run_fuzz_test.cmake copies the committed seed corpus tests/fuzz/corpus/<target>
# (test fixtures, and every input that once crashed a reader: regress-*) into the build folder and fuzzes from it
# for MIPNERF_FUZZ_SECONDS; any crash, sanitizer report, hang or huge allocation fails the entry. The long runs:
# scripts/fuzz.sh (bench/results/fuzz/fuzz.md). Included by tests/CMakeLists.txt, whose folder the paths are relative to.
set(MIPNERF_FUZZ_SECONDS 12 CACHE STRING "How long each fuzz target's CTest entry fuzzes, in seconds")
set(MIPNERF_FUZZ_TARGETS blender transforms_json multiscale llff colmap png jpeg camera_path config checkpoint view)
# The targets without a dictionary of their own (fuzz/dictionaries/<target>.dict) that read JSON share json.dict.
set(MIPNERF_FUZZ_JSON_TARGETS blender transforms_json multiscale camera_path)

add_library(mipnerf_fuzz_support STATIC fuzz/fuzz_support.cpp)
target_link_libraries(mipnerf_fuzz_support PUBLIC mipnerf)
target_compile_options(mipnerf_fuzz_support PRIVATE -fsanitize=fuzzer-no-link)

foreach(target IN LISTS MIPNERF_FUZZ_TARGETS)
  add_executable(fuzz_${target} fuzz/fuzz_${target}.cpp)
  target_link_libraries(fuzz_${target} PRIVATE mipnerf_fuzz_support)
  target_compile_options(fuzz_${target} PRIVATE -fsanitize=fuzzer)
  target_link_options(fuzz_${target} PRIVATE -fsanitize=fuzzer)
  set(dictionary "")
  if(EXISTS "${CMAKE_CURRENT_SOURCE_DIR}/fuzz/dictionaries/${target}.dict")
    set(dictionary "${CMAKE_CURRENT_SOURCE_DIR}/fuzz/dictionaries/${target}.dict")
  elseif(target IN_LIST MIPNERF_FUZZ_JSON_TARGETS)
    set(dictionary "${CMAKE_CURRENT_SOURCE_DIR}/fuzz/dictionaries/json.dict")
  endif()
  add_test(NAME "fuzz: ${target}" COMMAND ${CMAKE_COMMAND} "-DEXE=$<TARGET_FILE:fuzz_${target}>"
    "-DCORPUS=${CMAKE_CURRENT_SOURCE_DIR}/fuzz/corpus/${target}" "-DWORK=${CMAKE_CURRENT_BINARY_DIR}/fuzz/${target}"
    "-DSECONDS=${MIPNERF_FUZZ_SECONDS}" "-DDICTIONARY=${dictionary}"
    -P "${CMAKE_CURRENT_SOURCE_DIR}/fuzz/run_fuzz_test.cmake")
  set_tests_properties("fuzz: ${target}" PROPERTIES LABELS fuzz TIMEOUT 300 ENVIRONMENT "${MIPNERF_TEST_ENV}")
endforeach()

# The COLMAP target completes a fuzzed file with the fixture model's other two (tests/data/fixtures/colmap).
target_compile_definitions(fuzz_colmap PRIVATE
  MIPNERF_FUZZ_COLMAP_FIXTURE="${CMAKE_CURRENT_SOURCE_DIR}/data/fixtures/colmap")

# The tool that wrote the checkpoint target's seeds (tests/fuzz/checkpoint_seeds.cpp): not a test, kept to remake them.
add_executable(fuzz_checkpoint_seeds fuzz/checkpoint_seeds.cpp)
target_link_libraries(fuzz_checkpoint_seeds PRIVATE mipnerf)
# The tool that wrote the JPEG target's seeds (tests/fuzz/jpeg_seeds.cpp), kept to remake them.
add_executable(fuzz_jpeg_seeds fuzz/jpeg_seeds.cpp)
target_link_libraries(fuzz_jpeg_seeds PRIVATE JPEG::JPEG)
