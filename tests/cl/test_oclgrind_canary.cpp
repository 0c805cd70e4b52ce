// A kernel with a deliberate out-of-bounds write, for tests/oclgrind to prove that its check reports one. It runs
// only when MIPNERF_OCLGRIND_CANARY=1 (under oclgrind); everywhere else the case passes without launching anything.
#include <doctest/doctest.h>

#include <cstdlib>
#include <cstring>

#include "cl/buffer.hpp"
#include "cl/launch.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

TEST_CASE("oclgrind canary: a kernel that writes one element past its buffer") {
  const char* canary = std::getenv("MIPNERF_OCLGRIND_CANARY");
  if (canary == nullptr || std::strcmp(canary, "1") != 0) return;
  auto& ctx = test::test_context();
  const std::vector<ocl::SourceFile> files = {
      {"canary.cl", "__kernel void past_the_end(__global float* y, const uint n) {\n"
                    "  if (get_global_id(0) == 0) y[n] = 1.0f;  // one past the last element\n"
                    "}\n"}};
  auto& kernel = ctx.program_from_sources(files).kernel("past_the_end");
  ocl::DeviceArray<float> y(ctx, 16, "y");
  ocl::set_args(kernel, "past_the_end", y, static_cast<cl_uint>(16));
  ocl::launch_1d(ctx, kernel, 1, "past_the_end");
  ctx.finish();
}
