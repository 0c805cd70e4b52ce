# Finds every dependency; a missing one stops the configure step with the Debian package to install.
# scripts/install-deps.sh installs all of them at once.

macro(mipnerf_require found_var what debian_package)
  if(NOT ${found_var})
    message(FATAL_ERROR
      "mipnerf-cl: ${what} was not found. Install the Debian package '${debian_package}' "
      "(or run scripts/install-deps.sh, which installs every dependency).")
  endif()
endmacro()

find_package(Threads REQUIRED)

find_package(OpenCL QUIET)
mipnerf_require(OpenCL_FOUND "the OpenCL ICD loader and C headers" "ocl-icd-opencl-dev opencl-c-headers")

find_path(MIPNERF_OPENCL_HPP CL/opencl.hpp)
mipnerf_require(MIPNERF_OPENCL_HPP "the OpenCL C++ bindings (CL/opencl.hpp)" "opencl-clhpp-headers")
if(NOT TARGET OpenCL::HeadersCpp)
  add_library(OpenCL::HeadersCpp INTERFACE IMPORTED)
  set_target_properties(OpenCL::HeadersCpp PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${MIPNERF_OPENCL_HPP}")
endif()

find_package(CLBlast QUIET)
mipnerf_require(CLBlast_FOUND "CLBlast" "libclblast-dev")

find_package(CLI11 CONFIG QUIET)
mipnerf_require(CLI11_FOUND "CLI11" "libcli11-dev")

find_package(nlohmann_json CONFIG QUIET)
mipnerf_require(nlohmann_json_FOUND "nlohmann/json" "nlohmann-json3-dev")

find_package(OpenEXR CONFIG QUIET)
mipnerf_require(OpenEXR_FOUND "OpenEXR" "libopenexr-dev")

find_package(ZLIB QUIET)
mipnerf_require(ZLIB_FOUND "zlib" "zlib1g-dev")

find_package(PNG QUIET)
mipnerf_require(PNG_FOUND "libpng" "libpng-dev")

find_package(JPEG QUIET)
mipnerf_require(JPEG_FOUND "libjpeg" "libjpeg-dev")

# PLplot draws `mipnerf-cl plot`'s curves (io/line_plot): SVG with its built-in driver, PNG with its cairo driver
# (plplot-driver-cairo, checked when a PNG is asked for). Optional (MIPNERF_PLPLOT=AUTO, the default: when found):
# without it everything but `plot` builds and runs, and `plot` says what to install.
set(MIPNERF_PLPLOT AUTO CACHE STRING "Build `plot` with PLplot: AUTO (when found), ON (required) or OFF")
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND AND NOT MIPNERF_PLPLOT STREQUAL "OFF")
  pkg_check_modules(PLPLOT QUIET IMPORTED_TARGET plplot)
endif()
if(MIPNERF_PLPLOT STREQUAL "ON")
  mipnerf_require(PLPLOT_FOUND "PLplot" "libplplot-dev")
endif()
if(NOT PLPLOT_FOUND)
  message(STATUS "PLplot left out: `mipnerf-cl plot` will say to install libplplot-dev and rebuild")
endif()

# FFmpeg (libavformat, libavcodec with Debian's libx264 encoder, libswscale, libavutil) writes `render --video`'s
# H.264 MP4 (io/video). Optional like PLplot (MIPNERF_VIDEO=AUTO, the default: when found): without it everything
# else builds and runs, and --video says which packages to install.
set(MIPNERF_VIDEO AUTO CACHE STRING "Build `render --video` with FFmpeg: AUTO (when found), ON (required) or OFF")
if(PkgConfig_FOUND AND NOT MIPNERF_VIDEO STREQUAL "OFF")
  pkg_check_modules(FFMPEG QUIET IMPORTED_TARGET libavformat libavcodec libswscale libavutil)
endif()
if(MIPNERF_VIDEO STREQUAL "ON")
  mipnerf_require(FFMPEG_FOUND "FFmpeg's libraries" "libavformat-dev libavcodec-dev libswscale-dev libavutil-dev")
endif()
if(NOT FFMPEG_FOUND)
  message(STATUS "FFmpeg left out: `mipnerf-cl render --video` will say to install libavformat-dev libavcodec-dev "
    "libswscale-dev libavutil-dev and rebuild")
endif()

# cpp-httplib (Debian's libcpp-httplib-dev, a compiled library with its header) serves `mipnerf-cl view` (view/http_server).
if(PkgConfig_FOUND)
  pkg_check_modules(HTTPLIB QUIET IMPORTED_TARGET cpp-httplib)
endif()
mipnerf_require(HTTPLIB_FOUND "cpp-httplib" "libcpp-httplib-dev")

if(MIPNERF_BUILD_TESTS)
  find_package(doctest CONFIG QUIET)
  mipnerf_require(doctest_FOUND "doctest" "doctest-dev")
endif()
