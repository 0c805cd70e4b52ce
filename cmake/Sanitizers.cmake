# The sanitizer build and the fuzz targets (README, "Sanitizers and fuzzing"). One extra build folder pays for both:
#   cmake -S . -B build-sanitize -DCMAKE_CXX_COMPILER=clang++ -DMIPNERF_SANITIZE=ON -DMIPNERF_FUZZ=ON
# MIPNERF_SANITIZE: every host target (library, CLI, tests, benchmarks) with AddressSanitizer and
#   UndefinedBehaviorSanitizer; a UBSan finding stops the program (no recovery), so it fails its test.
# MIPNERF_FUZZ: the libFuzzer targets of tests/fuzz (clang only), each also a short CTest entry (label `fuzz`). The
#   files that read outside data (host/io, host/data, host/core, the training settings and checkpoints) get
#   libFuzzer's coverage instrumentation; the rest of the library does not, so the other tests pay nothing for it.
option(MIPNERF_SANITIZE "Build all host code with AddressSanitizer + UndefinedBehaviorSanitizer" OFF)
option(MIPNERF_FUZZ "Build the libFuzzer targets of tests/fuzz (needs clang; use with MIPNERF_SANITIZE)" OFF)
# MIPNERF_TSAN: every host target with ThreadSanitizer (scripts/test-tsan.sh: the `tsan` stage builds and runs only the
#   tests whose code starts threads, label `threads`); any data race or lock-order report fails its test. It cannot be
#   combined with AddressSanitizer, hence a build folder of its own. -O1: the races are in the order of our own
#   accesses, which -O1 keeps; the library compiles in about half the time it takes at -O3 under the instrumentation.
option(MIPNERF_TSAN "Build all host code with ThreadSanitizer" OFF)
if(MIPNERF_TSAN AND MIPNERF_SANITIZE)
  message(FATAL_ERROR "MIPNERF_TSAN and MIPNERF_SANITIZE exclude each other (ThreadSanitizer cannot run with "
    "AddressSanitizer): configure a build folder for each")
endif()
if(MIPNERF_TSAN)
  add_compile_options(-fsanitize=thread -O1 -g1)
  add_link_options(-fsanitize=thread)
endif()

if(MIPNERF_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
  if(CMAKE_BUILD_TYPE STREQUAL "Release")
    # Keep line numbers in the sanitizers' reports.
    add_compile_options(-g1)
  endif()
endif()

if(MIPNERF_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "MIPNERF_FUZZ needs clang's libFuzzer, but the C++ compiler is ${CMAKE_CXX_COMPILER_ID} "
      "(${CMAKE_CXX_COMPILER}). Configure a fresh build folder with -DCMAKE_CXX_COMPILER=clang++ (Debian packages "
      "'clang' and 'libclang-rt-dev'), e.g. scripts/test-sanitize.sh.")
  endif()
  if(NOT MIPNERF_SANITIZE)
    message(WARNING "MIPNERF_FUZZ without MIPNERF_SANITIZE: the fuzz targets find crashes and hangs but not the "
      "memory errors and undefined behaviour that AddressSanitizer and UBSan would report")
  endif()
endif()

# mipnerf_fuzz_instrument(sources...): libFuzzer's coverage instrumentation for these files (no-op without MIPNERF_FUZZ).
function(mipnerf_fuzz_instrument)
  if(MIPNERF_FUZZ)
    set_property(SOURCE ${ARGN} APPEND PROPERTY COMPILE_OPTIONS -fsanitize=fuzzer-no-link)
  endif()
endfunction()
