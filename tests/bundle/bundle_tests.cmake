# The bundle a device machine runs (scripts/bundle.sh, docs/devices.md), label `bundle`: this build packed into a
# temporary folder outside it, then run from there with a clean environment on PoCL through the bundle's own ICD
# file (tests/bundle/test_bundle.sh), so the bundle and its launcher cannot rot between the sessions lent a GPU.
# Release builds only: a sanitizer build's executables are not what a bundle carries. The `intel` stage leaves it out
# (scripts/test.sh): it runs on PoCL by construction, whatever the stage's platform.
if(NOT MIPNERF_SANITIZE AND NOT MIPNERF_TSAN)
  set(name "bundle: the packed executables run outside the build with a clean environment, on PoCL through the bundle's ICD file")
  add_test(NAME "${name}" COMMAND bash "${CMAKE_CURRENT_SOURCE_DIR}/bundle/test_bundle.sh" "${CMAKE_BINARY_DIR}")
  set_tests_properties("${name}" PROPERTIES LABELS bundle TIMEOUT 300 ENVIRONMENT "${MIPNERF_TEST_ENV}")
endif()
