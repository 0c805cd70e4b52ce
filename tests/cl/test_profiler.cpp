// The stage profiler: commands recorded under the innermost stage, only between begin_step and end_step, host time
// and FLOPs added to the current stage, and the refusal of a queue made without profiling.
#include <doctest/doctest.h>

#include <thread>

#include "cl/buffer.hpp"
#include "cl/launch.hpp"
#include "cl/profiler.hpp"
#include "core/error.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

void scale(ocl::Context& ctx, ocl::DeviceArray<float>& x, ocl::DeviceArray<float>& y) {
  auto& kernel = ctx.program({"common.cl", "util.cl"}).kernel("scale_f32");
  set_args(kernel, "scale_f32", x, y, static_cast<cl_uint>(x.size()));
  ocl::launch_1d(ctx, kernel, x.size(), "scale_f32");
}

}  // namespace

TEST_CASE("profiler: commands go to the innermost stage, only while a step is recorded") {
  ocl::Context ctx(test::test_context().device_info(), true);
  ocl::StageProfiler profiler;
  ctx.set_profiler(&profiler);
  ocl::DeviceArray<float> x(ctx, 1 << 16, "x"), y(ctx, 1 << 16, "y");

  x.fill(ctx, 1.0f);  // before begin_step: not recorded
  profiler.begin_step();
  {
    ocl::StageScope outer(ctx, "outer");
    x.fill(ctx, 2.0f);
    {
      ocl::StageScope inner(ctx, "inner");
      scale(ctx, x, y);
      scale(ctx, y, x);
      profiler.add_flops(1e6);
    }
    ocl::copy(ctx, x, 0, y, 0, x.size());
    {
      ocl::StageScope host(ctx, "host work");
      const ocl::HostTimer timer(ctx);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  scale(ctx, x, y);  // outside every stage
  profiler.end_step(ctx);
  x.fill(ctx, 3.0f);  // after end_step: not recorded

  const ocl::StageProfile& p = profiler.profile();
  CHECK(p.steps == 1);
  REQUIRE(p.stages.size() == 4);
  CHECK(p.stages[0].stage == "outer");  // in the order they first ran
  CHECK(p.stages[0].commands == 2);     // the fill and the copy
  CHECK(p.stages[1].stage == "inner");
  CHECK(p.stages[1].commands == 2);
  CHECK(p.stages[1].flops == 1e6);
  CHECK(p.stages[1].seconds > 0.0);
  CHECK(p.stages[2].stage == "host work");
  CHECK(p.stages[2].seconds >= 0.019);
  CHECK(p.stages[3].stage == "not in a stage");
  CHECK(p.stages[3].commands == 1);
  CHECK(p.stage_seconds() <= p.wall_seconds);
  CHECK(p.seconds_with_prefix("in") == p.stages[1].seconds);
  CHECK(y.download(ctx)[0] == 2.0f);  // the commands ran as usual (scale_f32 copies by default)

  profiler.reset();
  CHECK(profiler.profile().steps == 0);
  CHECK(profiler.profile().stages.empty());
  ctx.set_profiler(nullptr);
}

TEST_CASE("profiler: a queue made without profiling is refused, saying how to open one") {
  ocl::Context ctx(test::test_context().device_info(), false);
  ocl::StageProfiler profiler;
  CHECK_THROWS_WITH_AS(ctx.set_profiler(&profiler), doctest::Contains("open it with ContextOptions::profiling"), Error);
  CHECK(ctx.profiler() == nullptr);
  CHECK_THROWS_WITH_AS(profiler.end_step(ctx), doctest::Contains("end_step without begin_step"), Error);
}
