// Training configuration: presets and variants as data, parsing, validation, JSON round trip.
#include <doctest/doctest.h>

#include "core/error.hpp"
#include "train/config.hpp"

using namespace mipnerf;

TEST_CASE("config: the paper preset is exactly the paper's settings") {
  const auto c = train::resolve_config("paper", "mipnerf", {});
  CHECK(c.num_samples == 128);
  CHECK(c.num_levels == 2);
  CHECK(c.resample_padding == 0.01);
  CHECK(c.coarse_loss_mult == 0.1);
  CHECK(c.pos_min_deg == 0);
  CHECK(c.pos_max_deg == 16);  // L = 16 → 96 IPE features
  CHECK(c.view_max_deg == 4);  // degrees 0..3 + identity → 27 features
  CHECK(c.mlp_depth == 8);
  CHECK(c.mlp_width == 256);
  CHECK(c.mlp_skip == 4);
  CHECK(c.view_branch_width == 128);
  CHECK(c.density_activation == "softplus");
  CHECK(c.density_bias == -1.0);
  CHECK(c.rgb_padding == 0.001);
  CHECK(c.batch_size == 4096);
  CHECK(c.lr_init == 5e-4);
  CHECK(c.lr_final == 5e-6);
  CHECK(c.lr_warmup_steps == 2500);
  CHECK(c.lr_warmup_mult == 0.01);
  CHECK(c.background == "white");
  CHECK(c.pixel_center == 0.5);
  CHECK(c.single_mlp);
  CHECK(c.integrated_encoding);
}

TEST_CASE("config: order is defaults, preset, variant, explicit settings") {
  const auto c = train::resolve_config("tiny", "nerf", {{"pos_max_deg", "8"}, {"steps", "7"}});
  CHECK(c.num_samples == 16);  // from the preset
  CHECK(c.variant == "nerf");  // from the variant
  CHECK(!c.single_mlp);
  CHECK(c.pos_identity);
  CHECK(c.pos_max_deg == 8);  // explicit beats the variant's 10
  CHECK(c.steps == 7);        // explicit beats the preset's 300
  for (const auto& [name, bundle] : train::presets()) {
    for (const auto& [variant, v] : train::variants()) CHECK_NOTHROW(train::resolve_config(name, variant, {}));
  }
}

TEST_CASE("config: unknown names and bad values are refused with what is accepted") {
  CHECK_THROWS_WITH_AS(train::resolve_config("nosuch", "mipnerf", {}), doctest::Contains("paper"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "nosuch", {}), doctest::Contains("nerf"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"nosuch", "1"}}),
                       doctest::Contains("unknown setting 'nosuch'"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"background", "green"}}),
                       doctest::Contains("white | black | none"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"batch_size", "12x"}}),
                       doctest::Contains("an integer"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"lr_init", "nan"}}),
                       doctest::Contains("finite"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"randomized", "maybe"}}),
                       doctest::Contains("true or false"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"batch_size", "0"}}),
                       doctest::Contains("batch_size"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "nerf", {{"num_samples", "7"}}),
                       doctest::Contains("even"), Error);
}

TEST_CASE("config: JSON round trip keeps every setting, and differences are listed") {
  auto c = train::resolve_config("quick", "mipnerf-no-ipe", {{"seed", "18446744073709551615"}, {"near", "0.25"}});
  const auto text = train::to_json(c);
  const auto back = train::from_json(text, "test.json");
  CHECK(train::differences(c, back).empty());
  CHECK(back.seed == 18446744073709551615ull);
  CHECK(back.near == 0.25);
  auto other = back;
  other.batch_size = 17;
  const auto diff = train::differences(c, other);
  REQUIRE(diff.size() == 1);
  CHECK(diff[0] == "batch_size: 512 -> 17");
  CHECK_THROWS_WITH_AS(train::from_json("{\"bogus\": 1}", "cfg.json"), doctest::Contains("cfg.json"), Error);
  CHECK_THROWS_WITH_AS(train::from_json("{oops", "cfg.json"), doctest::Contains("malformed"), Error);
}
