# cmake -P script: `mipnerf-cl devices` must exit 0 and mark one device as selected, and when MIPNERF_TEST_PLATFORM is
# set (scripts/test.sh, per stage), that device's platform must be the one named. -DEXE=path of mipnerf-cl.
execute_process(COMMAND "${EXE}" devices RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT status EQUAL 0)
  message(FATAL_ERROR "mipnerf-cl devices exited with ${status}")
endif()
# The selected device's block: its first line carries "<- selected", its second the platform.
if(NOT out MATCHES "<- selected[^\n]*\n    platform +([^\n]*) \\(")
  message(FATAL_ERROR "mipnerf-cl devices marks no device as selected")
endif()
set(platform "${CMAKE_MATCH_1}")
string(TOLOWER "${platform}" platform_lower)
string(TOLOWER "$ENV{MIPNERF_TEST_PLATFORM}" wanted)
if(wanted AND NOT platform_lower STREQUAL wanted)
  message(FATAL_ERROR "the executable selected a device of platform '${platform}', but this test stage asked for "
    "'$ENV{MIPNERF_TEST_PLATFORM}' (MIPNERF_DEVICE='$ENV{MIPNERF_DEVICE}')")
endif()
message(STATUS "selected platform: ${platform}")
