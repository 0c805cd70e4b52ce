# Shortens the from-scratch build a new user waits for (scripts/quickstart.sh builds the executable alone; figures in
# README.md, "Quick start"): the library compiles as unity batches of MIPNERF_UNITY_BATCH files, so the headers and
# templates its files share (nlohmann/json, the OpenCL C++ bindings, the standard library) are parsed, instantiated
# and optimised once per batch instead of once per file: a third less CPU time. Precompiled headers were measured
# too and saved ~1% of it (the time goes into -O3 code generation, not parsing), so they are not used.
# A batch recompiles whole when one of its files changes, so a developer's one-file rebuild costs a batch's worth:
# -DMIPNERF_UNITY_BATCH=0 turns unity builds off for such a build folder. The thread-sanitizer build
# (scripts/test-tsan.sh) defaults to off, so one build of the test command still compiles each library file on its own
# (a missing include shows there). The AddressSanitizer build batches too since 2026-12-01 (its library was most of
# the test command's longest build), but for the fuzz-instrumented readers: per-file options do not survive a batch.
if(MIPNERF_TSAN)
  set(mipnerf_unity_default 0)
else()
  set(mipnerf_unity_default 16)
endif()
set(MIPNERF_UNITY_BATCH ${mipnerf_unity_default} CACHE STRING "Files per unity-build batch of the library (0: none)")

# Files left out of the unity batches (each still compiled on its own). host/data/formats/: every format's file
# defines the same local names (detect, add_traits, effects) by design, so a new format is a copy of a row's file.
# A new clash shows as a "redefinition of ... {anonymous}::" error in the
# unity build: rename the local name (or list the file here).
file(GLOB MIPNERF_UNITY_EXCLUDED CONFIGURE_DEPENDS "${CMAKE_CURRENT_LIST_DIR}/../host/data/formats/*.cpp")

# mipnerf_unity_build(target): the target's files in unity batches, as MIPNERF_UNITY_BATCH says.
function(mipnerf_unity_build target)
  if(MIPNERF_UNITY_BATCH GREATER 0)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${MIPNERF_UNITY_BATCH})
    set_source_files_properties(${MIPNERF_UNITY_EXCLUDED} TARGET_DIRECTORY ${target} PROPERTIES
      SKIP_UNITY_BUILD_INCLUSION ON)
  endif()
endfunction()
