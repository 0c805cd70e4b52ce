// The MLP's configuration, flat parameter layout and Glorot-uniform initialisation.
#include <doctest/doctest.h>

#include <cmath>

#include "core/error.hpp"
#include "mlp/mlp_config.hpp"

using namespace mipnerf;

TEST_CASE("mlp config: the paper's layout, layer by layer") {
  const mlp::MlpConfig config;  // defaults: 96 → 8×256, skip after index 4, view 27 → 128 → 3
  const auto layout = mlp::parameter_layout(config);
  REQUIRE(layout.trunk.size() == 8);
  CHECK(layout.trunk[0].in == 96);
  for (size_t i = 1; i < 8; ++i) {
    // The official rule i % 4 == 0 and i > 0 concatenates the features after layer index 4, so layer 5 reads
    // 256 + 96 values and every other layer 256.
    CHECK(layout.trunk[i].in == (i == 5 ? 256u + 96u : 256u));
    CHECK(layout.trunk[i].out == 256);
  }
  CHECK(layout.density.in == 256);
  CHECK(layout.density.out == 1);
  CHECK(layout.bottleneck.in == 256);
  CHECK(layout.bottleneck.out == 256);
  CHECK(layout.view.in == 256 + 27);
  CHECK(layout.view.out == 128);
  CHECK(layout.rgb.in == 128);
  CHECK(layout.rgb.out == 3);
  // Total by hand: trunk 96·256+256 + 4·(256·256+256) + (352·256+256) + 2·(256·256+256), density 257,
  // bottleneck 65792, view 283·128+128, rgb 128·3+3.
  const size_t expected =
      (96 * 256 + 256) + 4 * 65792 + (352 * 256 + 256) + 2 * 65792 + 257 + 65792 + (283 * 128 + 128) + (128 * 3 + 3);
  CHECK(layout.total == expected);
  // Layers are contiguous, weights then biases, in all() order.
  size_t offset = 0;
  for (const auto* layer : layout.all()) {
    CHECK(layer->weight_offset == offset);
    CHECK(layer->bias_offset == offset + layer->in * layer->out);
    offset += layer->parameter_count();
  }
  CHECK(offset == layout.total);
}

TEST_CASE("mlp config: without view dependence the view branch does not exist") {
  mlp::MlpConfig config;
  config.view_dependence = false;
  config.input_width = 63;  // the NeRF baseline's PE with identity
  const auto layout = mlp::parameter_layout(config);
  CHECK(layout.all().size() == 8 + 2);  // trunk, density, rgb
  CHECK(layout.rgb.in == 256);
  CHECK(layout.view.out == 0);
  CHECK(layout.bottleneck.out == 0);
  CHECK(layout.trunk[5].in == 256 + 63);
}

TEST_CASE("mlp config: bad configurations are refused with the field named") {
  mlp::MlpConfig config;
  config.width = 0;
  CHECK_THROWS_WITH_AS(config.validate(), doctest::Contains("width"), Error);
  config = mlp::MlpConfig{};
  config.depth = 5;  // a skip after index 4 would be after the last layer
  CHECK_THROWS_WITH_AS(config.validate(), doctest::Contains("skip_layer"), Error);
  config.skip_layer = 0;  // no skips at all
  CHECK_NOTHROW(config.validate());
  config = mlp::MlpConfig{};
  config.view_width = 0;
  CHECK_THROWS_WITH_AS(config.validate(), doctest::Contains("view_width"), Error);
  config.view_dependence = false;  // then the view sizes do not matter
  CHECK_NOTHROW(config.validate());
}

TEST_CASE("mlp config: uniform weights (Glorot's and He's), zero biases, a pure function of the seed") {
  for (const bool he : {false, true}) {
    mlp::MlpConfig config;
    config.seed = 7;
    config.weight_init = he ? mlp::WeightInit::he_uniform : mlp::WeightInit::glorot_uniform;
    CAPTURE(he);
    const auto layout = mlp::parameter_layout(config);
    const auto params = mlp::initial_parameters(config);
    REQUIRE(params.size() == layout.total);
    for (const auto* layer : layout.all()) {
      // jax.nn.initializers: glorot_uniform = variance_scaling(1, fan_avg, uniform): a = √(3/((in+out)/2));
      // he_uniform = variance_scaling(2, fan_in, uniform): a = √(3·2/in).
      const double limit = he ? std::sqrt(6.0 / static_cast<double>(layer->in))
                              : std::sqrt(6.0 / static_cast<double>(layer->in + layer->out));
      const size_t n = layer->in * layer->out;
      double sum = 0.0, sum_sq = 0.0, max_abs = 0.0;
      for (size_t i = 0; i < n; ++i) {
        const double w = params[layer->weight_offset + i];
        sum += w;
        sum_sq += w * w;
        max_abs = std::max(max_abs, std::abs(w));
      }
      INFO(layer->name);
      CHECK(max_abs <= limit);
      if (n >= 1000) {
        // U(−a, a): mean 0 and variance a²/3. With n ≥ 1000 draws the sample mean's standard deviation is
        // a/√(3n) ≤ 0.019·a and the variance's relative one √(0.8/n) ≤ 0.029; 5 of each bounds a fluke.
        CHECK(std::abs(sum / n) <= 5.0 * limit / std::sqrt(3.0 * n));
        CHECK(std::abs(sum_sq / n / (limit * limit / 3.0) - 1.0) <= 5.0 * std::sqrt(0.8 / n));
        CHECK(max_abs >= 0.99 * limit);
      }
      for (size_t c = 0; c < layer->out; ++c) CHECK(params[layer->bias_offset + c] == 0.0f);
    }
    CHECK(mlp::initial_parameters(config) == params);
    config.seed = 8;
    CHECK(mlp::initial_parameters(config) != params);
  }
}
