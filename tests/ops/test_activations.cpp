// Activations (kernels/activations.cl): forward and backward against the double reference, the backward against
// finite differences, and saturation at ±1e4.
#include <doctest/doctest.h>

#include "kernel_checks.hpp"
#include "ops/activations.hpp"
#include "ref/activations.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct Activated {
  std::vector<float> density, rgb, d_raw_density, d_raw_rgb;
};

Activated run_device(const ActivationOptions& options, const std::vector<float>& raw_density,
                     const std::vector<float>& raw_rgb, const std::vector<float>& d_density,
                     const std::vector<float>& d_rgb,
                     ops::ActivationItems items = ops::ActivationItems::device_default) {
  auto& ctx = test::test_context();
  const size_t rows = raw_density.size();
  auto raw_density_dev = test::upload(ctx, raw_density, "raw_density");
  auto raw_rgb_dev = test::upload(ctx, raw_rgb, "raw_rgb");
  auto d_density_dev = test::upload(ctx, d_density, "d_density");
  auto d_rgb_dev = test::upload(ctx, d_rgb, "d_rgb");
  ocl::DeviceArray<float> density(ctx, rows, "density"), rgb(ctx, 3 * rows, "rgb");
  ocl::DeviceArray<float> d_raw_density(ctx, rows, "d_raw_density"), d_raw_rgb(ctx, 3 * rows, "d_raw_rgb");
  ops::Activations stage(ctx, options, items);
  const ops::ActivationInputs in{raw_density_dev, raw_rgb_dev, rows};
  stage.fwd(in, {density, rgb});
  stage.bwd(in, {d_density_dev, d_rgb_dev}, {d_raw_density, d_raw_rgb});
  return {density.download(ctx), rgb.download(ctx), d_raw_density.download(ctx), d_raw_rgb.download(ctx)};
}

std::vector<ActivationOptions> all_variants() {
  ActivationOptions mipnerf;  // softplus(raw − 1), widened sigmoid ε = 0.001
  ActivationOptions nerf;
  nerf.density = DensityActivation::relu;
  nerf.density_bias = 0.0f;
  nerf.rgb_padding = 0.0f;
  return {mipnerf, nerf};
}

// The device's forward and backward against the double reference on the given rows, for every variant and every
// way of giving out work-items (an item per colour value, per row, per vector of 16 values).
void check_against_reference(const std::vector<float>& raw_density, const std::vector<float>& raw_rgb,
                             const std::vector<float>& d_density, const std::vector<float>& d_rgb) {
  const size_t rows = raw_density.size();
  for (const auto items :
       {ops::ActivationItems::per_value, ops::ActivationItems::per_row, ops::ActivationItems::per_vector}) {
    for (const auto& options : all_variants()) {
      INFO("density activation " << static_cast<int>(options.density) << ", an item per "
                                 << (items == ops::ActivationItems::per_row     ? "row"
                                     : items == ops::ActivationItems::per_value ? "colour value"
                                                                                : "vector"));
      const auto dev = run_device(options, raw_density, raw_rgb, d_density, d_rgb, items);
      // Every way of giving out items runs the same float operations per value (activations.cl): bit for bit the
      // per-value items' results.
      const auto per_value =
          run_device(options, raw_density, raw_rgb, d_density, d_rgb, ops::ActivationItems::per_value);
      CHECK(dev.density == per_value.density);
      CHECK(dev.rgb == per_value.rgb);
      CHECK(dev.d_raw_density == per_value.d_raw_density);
      CHECK(dev.d_raw_rgb == per_value.d_raw_rgb);
      std::vector<double> density, rgb, d_raw_density, d_raw_rgb;
      ref::activations_fwd(options, test::to_double(raw_density), test::to_double(raw_rgb), density, rgb, rows);
      ref::activations_bwd(options, test::to_double(raw_density), test::to_double(raw_rgb), test::to_double(d_density),
                           test::to_double(d_rgb), d_raw_density, d_raw_rgb, rows);
      // Tolerances. Each value is a handful of float operations on e = exp_nonpositive(−|x|) and log1p_unit(e)
      // (kernels/common.cl: both within 3 ulp by their derivations): 16 roundoffs relative to the result bound that
      // with margin. On top, the argument
      // x = raw + bias is rounded once (|Δx| ≤ u·|x|), which moves f(x) by |f'(x)|·u·|x|: softplus' = sigmoid,
      // sigmoid' = e/(1 + e)² (e = e^−|x|), and the sigmoid's own derivative for its gradient,
      // |d/dx sigmoid'(x)| ≤ sigmoid'(x). (Softplus of very negative x, ≈ e^x, keeps its relative accuracy
      // because log1p(e^x) has no cancellation.) The widened sigmoid subtracts ε from (1 + 2ε)·σ: for σ → 0
      // that cancels, so its absolute error is bounded by the terms' sizes, 16u·((1 + 2ε)·σ + ε).
      const double pad = options.rgb_padding;
      const auto x_of = [&](size_t i) { return static_cast<double>(raw_density[i]) + options.density_bias; };
      const auto argument_error = [&](size_t i, double slope) { return kUnitRoundoff * std::abs(x_of(i)) * slope; };
      const auto sigmoid_grad = [](double x) {
        const double e = std::exp(-std::abs(x));
        return e / ((1 + e) * (1 + e));
      };
      const bool relu = options.density == DensityActivation::relu;
      MIPNERF_CHECK_CLOSE("density", dev.density, density, [&](size_t i) {
        return 16 * kUnitRoundoff * std::abs(density[i]) +
               argument_error(i, relu ? 1.0 : ref::density_activation_grad(options, raw_density[i])) + 1e-38;
      });
      MIPNERF_CHECK_CLOSE("rgb", dev.rgb, rgb,
                          [&](size_t i) { return 16 * kUnitRoundoff * (std::abs(rgb[i]) + 2 * pad) + 1e-38; });
      MIPNERF_CHECK_CLOSE("d_raw_density", dev.d_raw_density, d_raw_density, [&](size_t i) {
        return 16 * kUnitRoundoff * std::abs(d_raw_density[i]) +
               std::abs(d_density[i]) * argument_error(i, relu ? 0.0 : sigmoid_grad(x_of(i))) + 1e-38;
      });
      MIPNERF_CHECK_CLOSE("d_raw_rgb", dev.d_raw_rgb, d_raw_rgb,
                          [&](size_t i) { return 16 * kUnitRoundoff * std::abs(d_raw_rgb[i]) + 1e-38; });
    }
  }
}

}  // namespace

TEST_CASE("activations: forward and backward match the CPU reference on 30,005 random rows") {
  std::mt19937 rng(7);
  // Not a multiple of 16 rows, nor 3·rows: the per-vector items' last colour and last density item are partial.
  const size_t rows = test::batch_for_device(30000) + 5;
  std::vector<float> raw_density(rows), raw_rgb(3 * rows), d_density(rows), d_rgb(3 * rows);
  std::normal_distribution<float> wide(0.0f, 8.0f), unit(0.0f, 1.0f);
  for (size_t i = 0; i < rows; ++i) {
    raw_density[i] = wide(rng);
    d_density[i] = unit(rng);
    for (int c = 0; c < 3; ++c) {
      raw_rgb[3 * i + c] = wide(rng);
      d_rgb[3 * i + c] = unit(rng);
    }
  }
  check_against_reference(raw_density, raw_rgb, d_density, d_rgb);
}

TEST_CASE("activations: every binade of raw values from 2^-40 to 2^7, both signs, matches the CPU reference") {
  // exp_nonpositive and log1p_unit cover their whole range here: exp of −|x| from −1 to about −128 (down to the
  // denormals and 0), log1p of values from 1 down to 0; 64 mantissas per binade (6 on the oclgrind simulator), each
  // sign, and raw = 0.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> mantissa(1.0f, 2.0f);
  std::vector<float> raw{0.0f};
  const size_t per_binade = test::batch_for_device(64, 6);
  for (int exponent = -40; exponent <= 6; ++exponent) {
    for (size_t k = 0; k < per_binade; ++k) {
      const float x = std::ldexp(mantissa(rng), exponent);
      raw.push_back(x);
      raw.push_back(-x);
    }
  }
  std::vector<float> raw_rgb(3 * raw.size()), d_density(raw.size(), 1.0f), d_rgb(3 * raw.size(), 1.0f);
  for (size_t i = 0; i < raw.size(); ++i) {
    for (int c = 0; c < 3; ++c) raw_rgb[3 * i + c] = raw[(i + 97 * c) % raw.size()];
  }
  check_against_reference(raw, raw_rgb, d_density, d_rgb);
}

TEST_CASE("activations: the reference backward matches central finite differences of the reference forward") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> raw_dist(-12.0, 12.0);
  for (const auto& options : all_variants()) {
    double worst = 0.0;
    for (int trial = 0; trial < 2000; ++trial) {
      double x = raw_dist(rng);
      // ReLU has a kink at −bias: keep finite differences away from it (the derivative is not defined there).
      if (options.density == DensityActivation::relu && std::abs(x + options.density_bias) < 1e-3) continue;
      const double h = 1e-5;
      const double fd_density =
          (ref::density_activation(options, x + h) - ref::density_activation(options, x - h)) / (2 * h);
      const double fd_rgb = (ref::rgb_activation(options, x + h) - ref::rgb_activation(options, x - h)) / (2 * h);
      // Central differences: truncation h²/6·|f'''| ≤ 1e-11 for these smooth functions (|f'''| ≤ 1), rounding
      // 1e-16/h = 1e-11; 1e-8 leaves margin.
      worst = std::max({worst, std::abs(fd_density - ref::density_activation_grad(options, x)),
                        std::abs(fd_rgb - ref::rgb_activation_grad(options, x))});
    }
    INFO("worst |finite difference − analytic| = " << worst);
    CHECK(worst < 1e-8);
  }
}

TEST_CASE("activations: the device backward matches finite differences of the reference forward") {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> raw_dist(-12.0f, 12.0f);
  const size_t rows = 10000;
  std::vector<float> raw_density(rows), raw_rgb(3 * rows), ones(rows, 1.0f), ones3(3 * rows, 1.0f);
  for (auto& x : raw_density) x = raw_dist(rng);
  for (auto& x : raw_rgb) x = raw_dist(rng);
  for (const auto& options : all_variants()) {
    const auto dev = run_device(options, raw_density, raw_rgb, ones, ones3);
    std::vector<double> fd_density(rows), fd_rgb(3 * rows);
    for (size_t i = 0; i < rows; ++i) {
      const double x = raw_density[i], h = 1e-5;
      fd_density[i] = (ref::density_activation(options, x + h) - ref::density_activation(options, x - h)) / (2 * h);
      for (int c = 0; c < 3; ++c) {
        const double y = raw_rgb[3 * i + c];
        fd_rgb[3 * i + c] = (ref::rgb_activation(options, y + h) - ref::rgb_activation(options, y - h)) / (2 * h);
      }
    }
    // Float32 derivative (16u relative, as above) plus the finite difference's own error (≤ 1e-8, see the
    // previous test); ReLU's kink is never hit by a float within 1e-5 of −bias in this sample (checked).
    for (size_t i = 0; i < rows; ++i) {
      if (options.density == DensityActivation::relu) REQUIRE(std::abs(raw_density[i] + options.density_bias) > 1e-5);
    }
    MIPNERF_CHECK_CLOSE("d density / d raw", dev.d_raw_density, fd_density,
                        [&](size_t i) { return 16 * kUnitRoundoff * std::abs(fd_density[i]) + 1e-8; });
    MIPNERF_CHECK_CLOSE("d rgb / d raw", dev.d_raw_rgb, fd_rgb,
                        [&](size_t i) { return 16 * kUnitRoundoff * std::abs(fd_rgb[i]) + 1e-8; });
  }
}

TEST_CASE("activations: saturated inputs at plus and minus 1e4 give finite values and gradients") {
  const std::vector<float> raw = {1e4f, -1e4f, 3e38f, -3e38f, 88.0f, -88.0f, 0.0f};
  std::vector<float> raw_rgb(3 * raw.size()), ones(raw.size(), 1.0f), ones3(3 * raw.size(), 1.0f);
  for (size_t i = 0; i < raw.size(); ++i) raw_rgb[3 * i] = raw_rgb[3 * i + 1] = raw_rgb[3 * i + 2] = raw[i];
  for (const auto& options : all_variants()) {
    const auto dev = run_device(options, raw, raw_rgb, ones, ones3);
    CHECK(test::all_finite(dev.density));
    CHECK(test::all_finite(dev.rgb));
    CHECK(test::all_finite(dev.d_raw_density));
    CHECK(test::all_finite(dev.d_raw_rgb));
    const float eps = options.rgb_padding;
    // raw = 1e4: density = raw + bias exactly (softplus(x) = x + log1p(e^−x), e^−x = 0), gradient 1.
    CHECK(dev.density[0] == 1e4f + options.density_bias);
    CHECK(dev.d_raw_density[0] == 1.0f);
    // raw = −1e4: density 0, gradient 0 (e^−10001 underflows; the true values are below any float).
    CHECK(dev.density[1] == 0.0f);
    CHECK(dev.d_raw_density[1] == 0.0f);
    // Colours saturate at 1 + ε and −ε with zero gradient.
    CHECK(dev.rgb[0] == doctest::Approx(1.0f + eps).epsilon(1e-7));
    CHECK(dev.rgb[3] == doctest::Approx(-eps).epsilon(1e-7));
    CHECK(dev.d_raw_rgb[0] == 0.0f);
    CHECK(dev.d_raw_rgb[3] == 0.0f);
    // At ±88 the sigmoid gradient e^−88 ≈ 6e-39 is still representable (a denormal at worst) and not NaN.
    CHECK(dev.d_raw_rgb[12] >= 0.0f);
    CHECK(dev.d_raw_rgb[15] >= 0.0f);
  }
}
