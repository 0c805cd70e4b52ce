# cmake -P script: proves that a sanitizer report fails a CLI test. Runs tests/cli/run_checked.cmake (the runner of
# every CLI test) on `mipnerf-cl devices`, which passes on its own, with MIPNERF_TEST_PLANT_FAULT=FAULT (the sanitizer
# build's planted fault, cli/planted_fault.hpp), and requires the runner to fail naming the report.
#   -DEXE=mipnerf-cl -DRUNNER=run_checked.cmake -DREPORT=regex -DFAULT=leak|overflow -DREPORT_TEXT=regex
# With FAULT=leak, LSAN_OPTIONS=exitcode=0 keeps the exit status 0, so only the report itself can fail the runner.
# The inner output is not echoed: its report would fail this test through FAIL_REGULAR_EXPRESSION.
set(ENV{MIPNERF_TEST_PLANT_FAULT} "${FAULT}")
if(FAULT STREQUAL "leak")
  set(ENV{LSAN_OPTIONS} "$ENV{LSAN_OPTIONS}:exitcode=0")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" "-DCOMMAND=${EXE}|devices" "-DEXPECT=<- selected" "-DREPORT=${REPORT}"
  -P "${RUNNER}" RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(status EQUAL 0)
  message(FATAL_ERROR "the runner passed a run with a planted ${FAULT}: a sanitizer report would go unnoticed")
endif()
if(NOT "${out}${err}" MATCHES "a sanitizer reported \\(")
  message(FATAL_ERROR "the runner failed, but not on the sanitizer report (exit ${status})")
endif()
if(NOT "${out}${err}" MATCHES "${REPORT_TEXT}")
  message(FATAL_ERROR "the planted ${FAULT} did not produce the expected report text '${REPORT_TEXT}'")
endif()
message(STATUS "the runner failed on the planted ${FAULT}'s report, as it must")
