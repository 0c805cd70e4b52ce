# Shortens the from-scratch build a new user waits for (scripts/quickstart.sh builds the executable alone; figures in
# README.md, "Quick start"): the library compiles as unity batches of MIPNERF_UNITY_BATCH files, so the headers and
# templates its files share (nlohmann/json, the OpenCL C++ bindings, the standard library) are parsed, instantiated
# and optimised once per batch instead of once per file: a third less CPU time. Precompiled headers were measured
# too and saved ~1% of it (the time goes into -O3 code generation, not parsing), so they are not used.
# A batch recompiles whole when one of its files changes, so a developer's one-file rebuild costs a batch's worth:
# -DMIPNERF_UNITY_BATCH=0 turns unity builds off for such a build folder, and is the check that each file includes
# what it uses (a batch hides a missing include behind its neighbours'). The test command's three builds all batch
# since 2026-12-02: the thread-sanitizer build compiled every library file on its own for that check, which cost a
# third of its CPU time, and the command was over its 45 minutes (CI: 3,077 s). The AddressSanitizer build still
# compiles the fuzz-instrumented readers (~60 files: host/core, io, data, the settings and checkpoint readers, the
# viewer's handler) on their own: per-file options do not survive a batch.
set(mipnerf_unity_default 16)
set(MIPNERF_UNITY_BATCH ${mipnerf_unity_default} CACHE STRING "Files per unity-build batch of the library (0: none)")

# Files left out of the unity batches (each still compiled on its own). host/data/formats/: every format's file
# defines the same local names (detect, add_traits, effects) by design, so a new format is a copy of a row's file.
# A new clash shows as a "redefinition of ... {anonymous}::" error in the
# unity build: rename the local name (or list the file here).
file(GLOB MIPNERF_UNITY_EXCLUDED CONFIGURE_DEPENDS "${CMAKE_CURRENT_LIST_DIR}/../host/data/formats/*.cpp")

# mipnerf_unity_build(target [batch]): the target's files in unity batches of MIPNERF_UNITY_BATCH files (or of
# `batch`, for a target whose few files would otherwise make one batch and leave a core idle) when it is not 0.
function(mipnerf_unity_build target)
  if(MIPNERF_UNITY_BATCH GREATER 0)
    set(batch ${MIPNERF_UNITY_BATCH})
    if(ARGC GREATER 1)
      set(batch ${ARGV1})
    endif()
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${batch})
    set_source_files_properties(${MIPNERF_UNITY_EXCLUDED} TARGET_DIRECTORY ${target} PROPERTIES
      SKIP_UNITY_BUILD_INCLUSION ON)
  endif()
endfunction()
