# Runs a test executable's cases under oclgrind and fails on any report.
#   -DOCLGRIND=path -DEXE=path -DFILTER=doctest test-case filter -DUNINITIALIZED=ON|OFF [-DEXCLUDE=filter]
#   [-DLAUNCH_LOG=file: the kernels launched are listed there]
#   [-DCANARY=ON]: the other way round, for the canary (tests/oclgrind/canary.cpp, FILTER empty): passes only when oclgrind
#   reports the canary's own invalid write in its kernel, so oclgrind failing to start, or failing for any other
#   reason, fails it.
# Checks: --check-api (OpenCL API misuse), --data-races (inside and across work-groups) and, always on,
# out-of-bounds accesses; with UNINITIALIZED also --uninitialized (reads of memory nobody wrote). That plugin
# (oclgrind 21.10) needs two concessions: kernels built with -cl-opt-disable (LLVM's optimiser emits `freeze`
# instructions it cannot interpret: "Unsupported instruction: freeze", the kernel stops with its outputs unwritten),
# and -DMIPNERF_SEPARATE_SIN_COS (it cannot follow sincos's private pointer: "Work item needed to access private
# memory"; kernels/encode.cl then calls sin and cos). It also runs 5-20x slower, so the test sizes decide where it
# fits in CI (tests/oclgrind/oclgrind_tests.cmake).
set(checks --check-api --data-races)
if(UNINITIALIZED)
  list(APPEND checks --uninitialized --build-options "-cl-opt-disable -DMIPNERF_SEPARATE_SIN_COS")
endif()
set(exclude "")
if(EXCLUDE)
  set(exclude "--test-case-exclude=${EXCLUDE}")
endif()
set(filter "")
if(FILTER)
  set(filter "--test-case=${FILTER}")
endif()
# The kernels this entry launches, for the check that every kernel ran under the simulator (oclgrind_tests.cmake).
if(LAUNCH_LOG)
  get_filename_component(log_folder "${LAUNCH_LOG}" DIRECTORY)
  file(MAKE_DIRECTORY "${log_folder}")
  file(REMOVE "${LAUNCH_LOG}")
  set(ENV{MIPNERF_KERNEL_LAUNCH_LOG} "${LAUNCH_LOG}")
endif()
execute_process(COMMAND "${OCLGRIND}" ${checks} "${EXE}" ${filter} ${exclude}
  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(CANARY)
  if(NOT "${out}${err}" MATCHES "Invalid write of size 4 at global memory address[^\n]*\n[^\n]*Kernel: past_the_end")
    message(FATAL_ERROR "oclgrind did not report the canary's out-of-bounds write in kernel past_the_end (exit ${status})")
  endif()
  message(STATUS "oclgrind reported the canary's out-of-bounds write, as it must")
  return()
endif()
# oclgrind's reports (it keeps running after most of them, so the exit status alone would miss them).
if("${out}${err}" MATCHES "(Invalid (read|write)[^\n]*|[A-Za-z-]+ data race[^\n]*|Uninitiali[sz]ed value[^\n]*|OpenCL runtime error[^\n]*|OCLGRIND FATAL ERROR[^\n]*|Oclgrind - [^\n]*)")
  message(FATAL_ERROR "oclgrind reported: ${CMAKE_MATCH_1}")
endif()
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${EXE} --test-case=${FILTER} failed under oclgrind (exit ${status})")
endif()
