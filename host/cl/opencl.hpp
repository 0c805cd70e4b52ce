// Includes the OpenCL C++ bindings with the project's settings: OpenCL 1.2 API, no binding exceptions
// (every status is checked by mipnerf::ocl::check, which names the call and the status).
#pragma once

#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#endif
#include <CL/opencl.hpp>
