// kernels/mlp.cl against its double mirrors in host/ref/mlp.hpp, on views with offsets and padded rows.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>

#include "mlp_checks.hpp"
#include "ops/mlp.hpp"
#include "ref/mlp.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

constexpr double kFloatEps = 5.9604644775390625e-08;  // float32 unit roundoff, 2^-24

}  // namespace

TEST_CASE("mlp kernels: bias + activation forward, with and without ReLU, NaN kept") {
  auto& ctx = test::test_context();
  ops::MlpKernels kernels(ctx);
  std::mt19937 rng(11);
  const size_t rows = 77, cols = 37, ld = 41, offset = 5, bias_offset = 3;
  for (bool relu : {false, true}) {
    auto z = test::random_floats(offset + rows * ld, rng);
    z[offset + 2 * ld + 1] = std::numeric_limits<float>::quiet_NaN();
    const auto params = test::random_floats(bias_offset + cols, rng);
    auto z_dev = test::device_copy(ctx, z, "z");
    const auto params_dev = test::device_copy(ctx, params, "params");
    kernels.bias_act_fwd(ocl::view(z_dev, ld, offset), rows, cols, params_dev, bias_offset, relu);
    const auto out = z_dev.download(ctx);
    auto expected = test::as_double(z);
    const auto params_d = test::as_double(params);
    ref::mlp_bias_act_fwd(expected.data(), offset, ld, rows, cols, params_d.data(), bias_offset, relu);
    CHECK(std::isnan(out[offset + 2 * ld + 1]));  // a NaN stays visible through ReLU
    expected[offset + 2 * ld + 1] = 0.0;
    auto out_checked = out;
    out_checked[offset + 2 * ld + 1] = 0.0f;
    // One float addition: |error| ≤ u·|sum| ≤ u·2 for values in [−1, 1]; padding between rows is untouched.
    test::check_close(out_checked, expected, 0, out.size(), 0.0, 2.0 * kFloatEps * 2.0, "bias_act_fwd");
    CHECK(out[offset + cols] == z[offset + cols]);
  }
}

TEST_CASE("mlp kernels: per-ray view term added to every sample of its ray") {
  auto& ctx = test::test_context();
  ops::MlpKernels kernels(ctx);
  std::mt19937 rng(12);
  const size_t rays = 9, samples = 7, rows = rays * samples, cols = 19, ld = 20, offset = 2, bias_offset = 1;
  const auto z = test::random_floats(offset + rows * ld, rng);
  const auto params = test::random_floats(bias_offset + cols, rng);
  const auto ray_term = test::random_floats(rays * cols, rng);
  auto z_dev = test::device_copy(ctx, z, "z");
  const auto params_dev = test::device_copy(ctx, params, "params");
  const auto ray_dev = test::device_copy(ctx, ray_term, "ray term");
  kernels.bias_ray_relu_fwd(ocl::view(z_dev, ld, offset), rows, cols, params_dev, bias_offset, ray_dev, samples);
  auto expected = test::as_double(z);
  const auto params_d = test::as_double(params), ray_d = test::as_double(ray_term);
  ref::mlp_bias_ray_relu_fwd(expected.data(), offset, ld, rows, cols, params_d.data(), bias_offset, ray_d.data(),
                             samples);
  // Two float additions of values in [−1, 1]: |error| ≤ 2·u·3.
  test::check_close(z_dev.download(ctx), expected, 0, z.size(), 0.0, 6.0 * kFloatEps, "bias_ray_relu_fwd");
  CHECK_THROWS_AS(kernels.bias_ray_relu_fwd(ocl::view(z_dev, ld, offset), rows - 1, cols, params_dev, bias_offset,
                                            ray_dev, samples),
                  Error);
}

TEST_CASE("mlp kernels: activation backward with per-block column sums, then their accumulation") {
  auto& ctx = test::test_context();
  ops::MlpKernels kernels(ctx);
  std::mt19937 rng(13);
  const size_t rows = 150, cols = 33, ld = 35, offset = 4, act_ld = 34, act_offset = 1;
  for (size_t rows_per_block : {size_t{64}, size_t{10}, size_t{1}}) {
    for (bool relu : {false, true}) {
      INFO("rows_per_block " << rows_per_block << " relu " << relu);
      const auto dz = test::random_floats(offset + rows * ld, rng);
      const auto act = test::random_floats(act_offset + rows * act_ld, rng, -1.0f, 1.0f);  // about half masked
      const size_t blocks = ops::MlpKernels::blocks_for(rows, rows_per_block);
      auto dz_dev = test::device_copy(ctx, dz, "dz");
      const auto act_dev = test::device_copy(ctx, act, "act");
      ocl::DeviceArray<float> partials_dev(ctx, blocks * cols, "partials");
      const ocl::MatrixView act_view = ocl::view(act_dev, act_ld, act_offset);
      kernels.act_bwd_partial(ocl::view(dz_dev, ld, offset), relu ? &act_view : nullptr, rows, cols, rows_per_block,
                              partials_dev);
      const auto grad0 = test::random_floats(7 + cols, rng);
      auto grad_dev = test::device_copy(ctx, grad0, "grad");
      kernels.sum_partials(partials_dev, blocks, cols, grad_dev, 7);

      auto dz_ref = test::as_double(dz);
      const auto act_d = test::as_double(act);
      std::vector<double> partials_ref(blocks * cols);
      ref::mlp_act_bwd_partial(dz_ref.data(), offset, ld, act_d.data(), act_offset, act_ld, rows, cols,
                               rows_per_block, relu, partials_ref.data());
      auto grad_ref = test::as_double(grad0);
      ref::mlp_sum_partials(partials_ref.data(), blocks, cols, grad_ref.data(), 7);
      // Masking is exact; a float sum of n values in [−1, 1] errs by at most n·u·n, and the full column
      // sum (partials, then across blocks) by at most rows·u·rows + 1 ulp for the accumulation.
      test::check_close(dz_dev.download(ctx), dz_ref, 0, dz.size(), 0.0, 0.0, "masked dz");
      test::check_close(partials_dev.download(ctx), partials_ref, 0, partials_ref.size(), 0.0,
                        rows_per_block * rows_per_block * kFloatEps, "partials");
      test::check_close(grad_dev.download(ctx), grad_ref, 0, grad_ref.size(), 0.0,
                        (rows * rows + 2.0) * kFloatEps, "accumulated column sums");
    }
  }
}
