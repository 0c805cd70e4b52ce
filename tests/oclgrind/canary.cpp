// oclgrind's canary: launches a kernel that writes one element past its buffer, so tests/oclgrind can prove that its
// check reports an out-of-bounds write (run_under_oclgrind.cmake, CANARY mode). Not a doctest case: outside oclgrind
// it would check nothing, so it runs only there.
// doctest's implementation only because the test support library (skip.cpp) refers to it; no doctest case here.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <iostream>

#include "cl/buffer.hpp"
#include "cl/launch.hpp"
#include "support/test_context.hpp"

int main() {
  using namespace mipnerf;
  try {
    auto& ctx = test::test_context();
    const std::vector<ocl::SourceFile> files = {
        {"canary.cl",
         "__kernel void past_the_end(__global float* y, const uint n) {\n"
         "  if (get_global_id(0) == 0) y[n] = 1.0f;  // one past the last element\n"
         "}\n"}};
    auto& kernel = ctx.program_from_sources(files).kernel("past_the_end");
    ocl::DeviceArray<float> y(ctx, 16, "y");
    ocl::set_args(kernel, "past_the_end", y, static_cast<cl_uint>(16));
    ocl::launch_1d(ctx, kernel, 1, "past_the_end");
    ctx.finish();
  } catch (const std::exception& e) {
    std::cerr << "canary: " << e.what() << "\n";
    test::release_test_context();
    return 1;
  }
  test::release_test_context();
  return 0;
}
