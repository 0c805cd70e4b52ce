# Runs one fuzz target briefly over a copy of its committed corpus and fails on any crash.
#   -DEXE=fuzz target -DCORPUS=committed corpus folder -DWORK=scratch folder (emptied) -DSECONDS=time
#   [-DDICTIONARY=libFuzzer dictionary]
# The limits are the project's: 2 GiB of RSS and of any single allocation, 10 s per input, inputs up to 64 KiB (the
# viewer's largest body; libFuzzer's default of 4 KiB is below a PNG bomb and a full JPEG). An entry that ran fewer
# than MIN_RUNS inputs (default 1,000) fails: a target that cannot start, or is too slow to fuzz, checks nothing.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}/corpus")
file(GLOB seeds "${CORPUS}/*")
if(NOT seeds)
  message(FATAL_ERROR "${CORPUS}: the seed corpus is empty")
endif()
file(COPY ${seeds} DESTINATION "${WORK}/corpus")
set(dictionary "")
if(DICTIONARY)
  set(dictionary "-dict=${DICTIONARY}")
endif()
if(NOT MIN_RUNS)
  set(MIN_RUNS 1000)
endif()
execute_process(COMMAND "${EXE}" "${WORK}/corpus" -max_total_time=${SECONDS} -rss_limit_mb=2048
  -malloc_limit_mb=2048 -timeout=10 -max_len=65536 -print_final_stats=1 "-artifact_prefix=${WORK}/" ${dictionary}
  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
# libFuzzer's progress lines, the last few and its final statistics, then the verdict.
string(REGEX MATCHALL "#[0-9]+[^\n]*\n" progress "${err}")
list(LENGTH progress lines)
if(lines GREATER 4)
  math(EXPR first "${lines} - 4")
  list(SUBLIST progress ${first} 4 progress)
endif()
string(REGEX MATCHALL "stat::[^\n]*\n" stats "${err}")
string(JOIN "" summary ${progress} ${stats})
message("${summary}")
file(GLOB artifacts "${WORK}/crash-*" "${WORK}/leak-*" "${WORK}/timeout-*" "${WORK}/oom-*" "${WORK}/slow-unit-*")
if(NOT status EQUAL 0 OR artifacts)
  message("${out}${err}")
  message(FATAL_ERROR "${EXE}: the fuzzer found a defect (exit ${status}); the input: ${artifacts}")
endif()
string(REGEX MATCH "stat::number_of_executed_units: ([0-9]+)" executed "${err}")
if(NOT executed)
  message(FATAL_ERROR "${EXE}: libFuzzer reported no count of executed inputs")
endif()
if(CMAKE_MATCH_1 LESS MIN_RUNS)
  message(FATAL_ERROR "${EXE}: ran ${CMAKE_MATCH_1} inputs in ${SECONDS} s, fewer than ${MIN_RUNS}: too few to "
    "count as fuzzed")
endif()
message(STATUS "${CMAKE_MATCH_1} inputs run")
