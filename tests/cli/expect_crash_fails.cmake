# cmake -P script: proves that a crash fails an error test. Runs tests/cli/run_checked.cmake (the runner of every CLI
# test) as mipnerf_add_cli_error_test does (EXIT nonzero, ONE_LINE, EXPECT the message) on a command that prints the
# expected one-line error and then dies as a mutated error path would: by a signal (SIGSEGV, SIGABRT), or with a
# status above 125 (the shell's 126/127 for a program that could not run, 128 + n for a signal). The runner must fail
# each one, naming why.
#   -DRUNNER=run_checked.cmake -DSHELL=/bin/sh
set(message "mipnerf-cl: error: the message the test expects")
foreach(ending "kill -SEGV $$" "kill -ABRT $$" "exit 134" "exit 127" "exit 126" "exit 255")
  execute_process(COMMAND "${CMAKE_COMMAND}" "-DCOMMAND=${SHELL}|-c|echo '${message}' >&2 && ${ending}" "-DEXIT=nonzero"
    "-DONE_LINE=ON" "-DEXPECT=the message the test expects" -P "${RUNNER}"
    RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(status EQUAL 0)
    message(FATAL_ERROR "the runner passed an error test whose program ended with `${ending}`: a crash would pass")
  endif()
  if(NOT "${out}${err}" MATCHES "expected an error exit status \\(1\\.\\.125\\)")
    message(FATAL_ERROR "the runner failed on `${ending}`, but not on its exit status:\n${out}${err}")
  endif()
  message(STATUS "`${ending}` after the expected message fails the error test, as it must")
endforeach()
# And the same command exiting 1 passes: the runner fails the crashes above, not every command.
execute_process(COMMAND "${CMAKE_COMMAND}" "-DCOMMAND=${SHELL}|-c|echo '${message}' >&2 && exit 1" "-DEXIT=nonzero"
  "-DONE_LINE=ON" "-DEXPECT=the message the test expects" -P "${RUNNER}" RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the runner failed an error test that exited 1 with the expected message")
endif()
