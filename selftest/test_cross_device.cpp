// A few whole training steps on the device under test against the same steps on another CPU device (when the
// machine has one; selftest/main.cpp leaves this check out otherwise and says so).
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

#include "cl/context.hpp"
#include "cross_device.hpp"
#include "support/temp_scene.hpp"
#include "support/test_context.hpp"
#include "support/train_fixtures.hpp"
#include "train/config.hpp"
#include "train/trainer.hpp"

using namespace mipnerf;

namespace {

// The batch losses of `steps` tiny-preset steps on `ctx`, from the same seed and data as every other call.
std::vector<double> losses_of(ocl::Context& ctx, const std::string& scene, const std::string& name, int steps) {
  const auto config = train::resolve_config("tiny", "mipnerf",
                                            {{"steps", std::to_string(steps)},
                                             {"batch_size", "256"},
                                             {"log_every", "1"},
                                             {"checkpoint_every", "1000"},
                                             {"val_views", "1"}});
  const std::string out = test::fresh_run_dir(name);
  train::Trainer trainer(ctx, config, scene, out, false);
  std::vector<double> losses;
  train::TrainHooks hooks;
  hooks.on_step = [&](const train::StepReport& r) { losses.push_back(r.loss); };
  trainer.run(hooks);
  std::filesystem::remove_all(out);
  return losses;
}

}  // namespace

TEST_CASE("training: three steps agree with another CPU device") {
  auto& ctx = test::test_context();
  const auto other_device = selftest::other_cpu_device(ctx.device_info());
  REQUIRE_MESSAGE(other_device.has_value(), "no other CPU device: main.cpp should have left this check out");
  ocl::Context other(*other_device);
  const std::string scene = test::write_temp_scene("selftest-scene", {16, 6, 1, 1, 1});
  const int steps = 3;
  const auto here = losses_of(ctx, scene, "selftest-here", steps);
  const auto there = losses_of(other, scene, "selftest-there", steps);
  REQUIRE(here.size() == static_cast<size_t>(steps));
  REQUIRE(there.size() == here.size());
  // The same float32 step on two implementations differs by rounding in sums over thousands of terms, and Adam
  // normalises gradient components whose rounding differs: 1e-3 relative on each step's loss leaves room for that
  // and none for a wrong kernel (a wrong stage moves the loss by O(1)).
  for (int s = 0; s < steps; ++s) {
    CAPTURE(s);
    CAPTURE(here[s]);
    CAPTURE(there[s]);
    REQUIRE(std::isfinite(here[s]));
    CHECK(std::abs(here[s] - there[s]) <= 1e-3 * std::abs(there[s]));
  }
  std::filesystem::remove_all(scene);
}
