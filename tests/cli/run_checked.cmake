# cmake -P script: runs one command and checks all of what it did, for the tests of the executable (cli_tests.cmake).
#   -DCOMMAND=program|arg|...   the command, its arguments separated by '|'
#   -DEXPECT=regex              the output (stdout and stderr merged, in order) must match it (optional)
#   -DEXIT=0|nonzero            the exit status it must have (default 0); nonzero means an error exit, 1..125: a
#                               signal or a status above 125 (a crash, a program that could not run) fails
#   -DONE_LINE=ON               stderr must be exactly one line (the CLI's errors), matched by EXPECT alone
#   -DREPORT=regex              a sanitizer report's first line (tests/CMakeLists.txt); any match fails
# CTest's PASS_REGULAR_EXPRESSION would make CTest ignore the exit status, and a line printed before a crash, a
# non-zero exit or a sanitizer report would pass: here each of them fails the test, naming which.
string(REPLACE "|" ";" command "${COMMAND}")
string(REPLACE "@SEMICOLON@" ";" EXPECT "${EXPECT}")  # cli_tests.cmake's encoding of a ';' in the pattern
if(NOT DEFINED EXIT OR EXIT STREQUAL "")
  set(EXIT 0)
endif()
if(ONE_LINE)
  execute_process(COMMAND ${command} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(output "${out}${err}")
else()
  execute_process(COMMAND ${command} RESULT_VARIABLE status OUTPUT_VARIABLE output ERROR_VARIABLE output)
endif()
message("${output}")
string(REPLACE ";" " " shown "${command}")
if(REPORT AND output MATCHES "${REPORT}")
  message(FATAL_ERROR "a sanitizer reported (${CMAKE_MATCH_0}) in: ${shown}")
endif()
if(EXIT STREQUAL "nonzero")
  # An error the program reports exits 1..125; a crash is not one. CMake gives a signal as text ("Segmentation
  # fault", "Child aborted"), and 126..255 are the shell's "cannot run", "not found" and 128 + signal.
  if(NOT status MATCHES "^[0-9]+$")
    message(FATAL_ERROR "expected an error exit status (1..125), but the program died: '${status}', from: ${shown}")
  elseif(status EQUAL 0)
    message(FATAL_ERROR "expected a non-zero exit status, got 0, from: ${shown}")
  elseif(status GREATER 125)
    message(FATAL_ERROR "expected an error exit status (1..125), got ${status} (a crash, or a program that could "
      "not run), from: ${shown}")
  endif()
elseif(NOT "${status}" STREQUAL "${EXIT}")
  message(FATAL_ERROR "expected exit status ${EXIT}, got '${status}', from: ${shown}")
endif()
if(ONE_LINE)
  string(STRIP "${err}" stripped)
  string(FIND "${stripped}" "\n" newline)
  if(NOT newline EQUAL -1)
    message(FATAL_ERROR "expected one line on stderr, got:\n${err}")
  endif()
  set(output "${stripped}")
endif()
if(DEFINED EXPECT AND NOT EXPECT STREQUAL "" AND NOT output MATCHES "${EXPECT}")
  message(FATAL_ERROR "the output does not match '${EXPECT}'")
endif()
