# The sanitizer build (MIPNERF_SANITIZE) proves its own check: a planted leak and a planted heap overflow in the
# executable each fail the CLI runner with the sanitizer's report (expect_report_fails.cmake). Included by
# tests/CMakeLists.txt after cli/cli_tests.cmake.
foreach(fault_text "leak;LeakSanitizer: detected memory leaks" "overflow;AddressSanitizer: heap-buffer-overflow")
  list(GET fault_text 0 fault)
  list(GET fault_text 1 text)
  add_test(NAME "sanitize: a planted ${fault} fails the CLI test that saw it" COMMAND ${CMAKE_COMMAND}
    "-DEXE=$<TARGET_FILE:mipnerf-cl>" "-DRUNNER=${CMAKE_CURRENT_SOURCE_DIR}/cli/run_checked.cmake"
    "-DREPORT=${MIPNERF_SANITIZER_REPORT}" "-DFAULT=${fault}" "-DREPORT_TEXT=${text}"
    -P "${CMAKE_CURRENT_SOURCE_DIR}/sanitize/expect_report_fails.cmake")
  set_tests_properties("sanitize: a planted ${fault} fails the CLI test that saw it" PROPERTIES
    ENVIRONMENT "${MIPNERF_TEST_ENV}" LABELS sanitize)
endforeach()
