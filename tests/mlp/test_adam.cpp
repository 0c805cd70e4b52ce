// Adam on the device against its double reference (also with denormal moments, moments around 1e30 and gradients
// whose square overflows float32), the gradient statistics (norm, non-finite count), clipping, the optimiser state
// round trip, and the learning-rate schedule of supplement eq. 24 at key steps.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "core/error.hpp"
#include "mlp/adam.hpp"
#include "mlp_checks.hpp"
#include "ref/adam.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

constexpr double kU = 5.9604644775390625e-08;  // float32 unit roundoff, 2^-24

// Runs `steps` Adam updates on device and reference from the same start, fresh gradients each step.
void check_adam_against_reference(double grad_max_norm, unsigned seed) {
  auto& ctx = test::test_context();
  std::mt19937 rng(seed);
  const size_t n = 5000;
  mlp::AdamHyper hyper;
  hyper.grad_max_norm = grad_max_norm;
  mlp::Adam adam(ctx, n, hyper);
  const auto start = test::random_floats(n, rng);
  auto params_dev = test::device_copy(ctx, start, "params");
  ocl::DeviceArray<float> grads_dev(ctx, n, "grads");
  auto params = test::as_double(start);
  std::vector<double> m(n, 0.0), v(n, 0.0);
  const int steps = 6;
  double max_update = 0.0;
  for (int t = 1; t <= steps; ++t) {
    // Gradient magnitudes spread over 6 decades, some elements exactly zero.
    auto grads = test::random_floats(n, rng);
    for (size_t i = 0; i < n; ++i) grads[i] *= std::pow(10.0f, static_cast<float>(i % 7) - 4.0f) * (i % 11 != 0);
    grads_dev.upload(ctx, grads);
    const double lr = 1e-3 * t;
    const auto stats = adam.gradient_stats(grads_dev);
    adam.step(params_dev, grads_dev, lr, &stats);

    const auto g = test::as_double(grads);
    double norm_sq = 0.0;
    for (double x : g) norm_sq += x * x;
    const double scale = grad_max_norm > 0.0 ? std::min(1.0, grad_max_norm / (1e-7 + std::sqrt(norm_sq))) : 1.0;
    const double b1 = hyper.beta1, b2 = hyper.beta2;  // the kernel gets β and 1 − β each rounded to float
    const auto before = params;
    ref::adam_step(params.data(), g.data(), m.data(), v.data(), n, lr, b1, b2, 1 - b1, 1 - b2, hyper.epsilon,
                   1.0 / (1.0 - std::pow(b1, t)), 1.0 / (1.0 - std::pow(b2, t)), scale);
    for (size_t i = 0; i < n; ++i) max_update = std::max(max_update, std::abs(params[i] - before[i]));
  }
  CHECK(adam.step_count() == steps);
  // Each step rounds the parameter once (≤ u·|p| ≤ u for |p| ≤ 1 + updates) and computes the update with
  // ~10 float operations (relative error ≤ 10u of an update ≤ max_update); over `steps` steps:
  const double tolerance = steps * (2.0 * kU + 10.0 * kU * max_update);
  test::check_close(params_dev.download(ctx), params, 0, n, 0.0, tolerance, "parameters after Adam");
  const auto state = adam.state();
  // Moments: 3 rounded float operations per step (≤ 3u relative each), over 6 steps ≤ 18u ≈ 1.1e-6 of the
  // largest moment; 2e-6 relative.
  test::check_close(state.m, m, 0, n, 2e-6, 0.0, "first moments");
  test::check_close(state.v, v, 0, n, 2e-6, 0.0, "second moments");
  CHECK(max_update > 0.0);
}

}  // namespace

TEST_CASE("adam: device steps match the reference, with bias correction") {
  check_adam_against_reference(0.0, 31);
}

TEST_CASE("adam: global-norm clipping scales the gradient as the official code does") {
  // max norm far below the gradients' norm (≈ 0.1·√5000·…): every step is clipped.
  check_adam_against_reference(0.05, 32);
}

TEST_CASE("adam: denormal moments, moments around 1e30 and gradients whose square overflows match the reference") {
  // Three groups of 3000 parameters, each from a restored state, over 6 steps from t = 1 (the largest bias
  // corrections: inv_bias1 = 10, inv_bias2 = 1000):
  //  - denormal: m, v in 1e-45..1e-39 (float denormals), gradients 0 or ±1e-44..1e-38 (denormal too, whose
  //    squares underflow), so the moments stay denormal;
  //  - huge: m = ±1e30·(0.1..10), v = 1e30..1e36 with gradients 1e14..1e17 (v̂ = v·inv_bias2 beyond FLT_MAX at
  //    t = 1 once v > 3.4e35, while √v̂ is ~1e19);
  //  - overflowing squares: m = v = 0 and gradients ±(1.9e19..1e20), so g² > FLT_MAX while (1 − β2)·g² and v
  //    (≤ 6·1e37 after 6 steps) are representable.
  // The reference runs in double on the same float inputs (betas, lr and the float bias corrections the kernel
  // receives), so every difference is the kernel's float32 rounding; the bound is that rounding propagated
  // through the steps (below).
  auto& ctx = test::test_context();
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const size_t group = 3000, n = 3 * group;
  const int steps = 6;
  mlp::Adam adam(ctx, n);
  const mlp::AdamHyper hyper = adam.hyper();
  mlp::AdamState start;
  start.m.resize(n);
  start.v.resize(n);
  const auto sign = [&] { return unit(rng) < 0.5 ? -1.0 : 1.0; };
  const auto log_uniform = [&](double lo, double hi) { return std::exp(std::log(lo) + unit(rng) * std::log(hi / lo)); };
  for (size_t i = 0; i < group; ++i) {
    start.m[i] = static_cast<float>(sign() * log_uniform(1e-45, 1e-39));
    start.v[i] = static_cast<float>(log_uniform(1e-45, 1e-39));
    start.m[group + i] = static_cast<float>(sign() * 1e30 * log_uniform(0.1, 10.0));
    start.v[group + i] = static_cast<float>(log_uniform(1e30, 1e36));
  }
  adam.restore(start);  // step 0: the next update has t = 1
  const auto params0 = test::random_floats(n, rng);
  auto params_dev = test::device_copy(ctx, params0, "params");
  ocl::DeviceArray<float> grads_dev(ctx, n, "grads");

  // Per element, the float32 error of the kernel, propagated step by step in double next to the reference:
  //  - m = β1·m + (1 − β1)·g (1 − β1 exact): two products and a sum, ≤ 3u·(β1|m| + (1 − β1)|g|), earlier error × β1;
  //  - v = β2·v + ((1 − β2)·g)·g likewise, ≤ 3u·(β2·v + (1 − β2)·g²), earlier error × β2;
  //  - the update lr·(m·b1)/(√v·√b2 + ε): relative ≤ 21u (sqrt ≤ 3 ulp twice, division ≤ 2.5 ulp, four products
  //    and a sum) plus the moments' errors, e_m/|m| and e_v/(2v) (√ halves a relative error), as absolute terms;
  //  - the parameter's own rounding, u·|p|.
  // Each float operation may also lose up to half a denormal ulp (2^-150), or all of a value below FLT_MIN when the
  // device flushes denormals (CL_FP_DENORM is optional in OpenCL 1.2): `floor` per operation.
  cl_device_fp_config fp_config = 0;
  clGetDeviceInfo(ctx.raw_device(), CL_DEVICE_SINGLE_FP_CONFIG, sizeof(fp_config), &fp_config, nullptr);
  const double floor = (fp_config & CL_FP_DENORM) ? std::ldexp(1.0, -150) : std::ldexp(1.0, -126);
  auto params = test::as_double(params0);
  std::vector<double> m = test::as_double(start.m), v = test::as_double(start.v);
  std::vector<double> e_m(n, 0.0), e_v(n, 0.0), e_p(n, 0.0);
  const double b1 = hyper.beta1, b2 = hyper.beta2, eps = hyper.epsilon;
  for (int t = 1; t <= steps; ++t) {
    std::vector<float> grads(n);
    for (size_t i = 0; i < group; ++i) {
      grads[i] = i % 5 == 0 ? 0.0f : static_cast<float>(sign() * log_uniform(1e-44, 1e-38));
      grads[group + i] = static_cast<float>(sign() * log_uniform(1e14, 1e17));
      grads[2 * group + i] = static_cast<float>(sign() * log_uniform(1.9e19, 1e20));
    }
    for (size_t i = 2 * group; i < n; ++i) REQUIRE(std::isinf(grads[i] * grads[i]));  // the square overflows
    grads_dev.upload(ctx, grads);
    const float lr = 1e-3f;
    adam.step(params_dev, grads_dev, lr, nullptr);  // no clipping (gradient_stats' float norm overflows here)
    const double inv_bias1 = static_cast<float>(1.0 / (1.0 - std::pow(b1, t)));  // as Adam::step passes them
    const double inv_bias2 = static_cast<float>(1.0 / (1.0 - std::pow(b2, t)));
    const auto g = test::as_double(grads);
    const auto m_before = m, v_before = v;
    ref::adam_step(params.data(), g.data(), m.data(), v.data(), n, lr, b1, b2, 1 - b1, 1 - b2, eps, inv_bias1,
                   inv_bias2, 1.0);
    for (size_t i = 0; i < n; ++i) {
      e_m[i] = b1 * e_m[i] + 3 * kU * (b1 * std::abs(m_before[i]) + (1 - b1) * std::abs(g[i])) + 3 * floor;
      e_v[i] = b2 * e_v[i] + 3 * kU * (b2 * v_before[i] + (1 - b2) * g[i] * g[i]) + 3 * floor;
      const double denominator = std::sqrt(v[i]) * std::sqrt(inv_bias2) + eps;
      const double update = lr * std::abs(m[i]) * inv_bias1 / denominator;
      const double through_moments =
          lr * inv_bias1 * e_m[i] / denominator + update * std::min(1.0, e_v[i] / (2 * std::max(v[i], 1e-300)));
      e_p[i] += 21 * kU * update + through_moments + kU * std::abs(params[i]) + 7 * floor;
    }
  }
  const auto state = adam.state();
  const auto dev_params = params_dev.download(ctx);
  const std::string names[3] = {"denormal moments", "moments around 1e30", "gradients whose square overflows"};
  for (int k = 0; k < 3; ++k) {
    INFO(names[k]);
    struct Compared {
      std::string what;
      const std::vector<float>* device;
      const std::vector<double>* reference;
      const std::vector<double>* bound;
    };
    for (const Compared& c : {Compared{"m", &state.m, &m, &e_m}, Compared{"v", &state.v, &v, &e_v},
                              Compared{"params", &dev_params, &params, &e_p}}) {
      double worst_ratio = 0.0;
      size_t worst = k * group, non_finite = 0;
      for (size_t i = k * group; i < (k + 1) * group; ++i) {
        if (!std::isfinite((*c.device)[i])) ++non_finite;
        const double ratio = std::abs((*c.device)[i] - (*c.reference)[i]) / (2 * (*c.bound)[i]);  // twice the bound
        if (!(ratio <= worst_ratio)) {
          worst_ratio = ratio;
          worst = i;
        }
      }
      INFO(c.what << ": worst element " << worst - k * group << " device " << (*c.device)[worst] << " reference "
                  << (*c.reference)[worst] << " = " << worst_ratio << " x tolerance");
      if (std::getenv("MLP_TEST_VERBOSE")) {
        MESSAGE(names[k] << ", " << c.what << ": worst " << worst_ratio << " x tolerance");
      }
      CHECK(non_finite == 0);
      CHECK(worst_ratio <= 1.0);
    }
  }
  // The groups really are what they say: denormal moments stayed below FLT_MIN, the huge ones moved the parameters,
  // and the overflowing squares left v finite and near 6·(1 − β2)·g².
  for (size_t i = 0; i < group; ++i) REQUIRE(std::abs(m[i]) < std::ldexp(1.0, -126));
  for (size_t i = group; i < 2 * group; ++i) REQUIRE(std::abs(params[i] - params0[i]) > 1e-4);
  for (size_t i = 2 * group; i < n; ++i) REQUIRE(v[i] > 1e35);
}

TEST_CASE("adam: gradient statistics find the norm and every non-finite element") {
  auto& ctx = test::test_context();
  std::mt19937 rng(33);
  const size_t n = 100003;  // not a multiple of the 1024 slices
  mlp::Adam adam(ctx, n);
  auto grads = test::random_floats(n, rng);
  auto grads_dev = test::device_copy(ctx, grads, "grads");
  auto stats = adam.gradient_stats(grads_dev);
  double norm_sq = 0.0;
  for (float g : grads) norm_sq += static_cast<double>(g) * g;
  // Each slice sums ~98 squares in float (relative error ≤ 98·u ≈ 6e-6); 1e-5 relative.
  CHECK(stats.norm == doctest::Approx(std::sqrt(norm_sq)).epsilon(1e-5));
  CHECK(stats.non_finite == 0);
  CHECK(stats.finite());

  // The reference mirror agrees slice by slice.
  std::vector<double> sumsq(1024);
  std::vector<uint32_t> bad(1024);
  const auto g = test::as_double(grads);
  ref::grad_norm_partial(g.data(), n, sumsq.data(), bad.data(), 1024);
  double total = 0.0;
  for (double s : sumsq) total += s;
  CHECK(std::sqrt(total) == doctest::Approx(std::sqrt(norm_sq)).epsilon(1e-12));

  grads[5] = std::numeric_limits<float>::quiet_NaN();
  grads[77777] = std::numeric_limits<float>::infinity();
  grads[n - 1] = -std::numeric_limits<float>::infinity();
  grads_dev.upload(ctx, grads);
  stats = adam.gradient_stats(grads_dev);
  CHECK(stats.non_finite == 3);
  CHECK_FALSE(stats.finite());
  CHECK(std::isfinite(stats.norm));  // the finite elements still give a norm

  // A step with non-finite gradients is refused and changes nothing.
  auto params_dev = test::device_copy(ctx, std::vector<float>(n, 0.5f), "params");
  CHECK_THROWS_WITH_AS(adam.step(params_dev, grads_dev, 1e-3, &stats), doctest::Contains("skip this step"), Error);
  CHECK(adam.step_count() == 0);
  for (float p : params_dev.download(ctx)) REQUIRE(p == 0.5f);
}

TEST_CASE("adam: clipping without statistics is refused") {
  auto& ctx = test::test_context();
  mlp::AdamHyper hyper;
  hyper.grad_max_norm = 1.0;
  mlp::Adam adam(ctx, 10, hyper);
  ocl::DeviceArray<float> p(ctx, 10, "params"), g(ctx, 10, "grads");
  CHECK_THROWS_WITH_AS(adam.step(p, g, 1e-3, nullptr), doctest::Contains("gradient_stats"), Error);
  CHECK_THROWS_AS(mlp::Adam(ctx, 10, mlp::AdamHyper{1.0f, 0.999f, 1e-8f, 0.0}), Error);
}

TEST_CASE("adam: restoring a saved state continues the run bit for bit") {
  auto& ctx = test::test_context();
  std::mt19937 rng(34);
  const size_t n = 777;
  std::vector<std::vector<float>> grads;
  for (int i = 0; i < 5; ++i) grads.push_back(test::random_floats(n, rng));
  auto run = [&](mlp::Adam& adam, ocl::DeviceArray<float>& params, int first, int last) {
    ocl::DeviceArray<float> g(ctx, n, "grads");
    for (int s = first; s < last; ++s) {
      g.upload(ctx, grads[s]);
      adam.step(params, g, 1e-2, nullptr);
    }
  };
  mlp::Adam adam(ctx, n);
  auto params = test::device_copy(ctx, test::random_floats(n, rng), "params");
  run(adam, params, 0, 3);
  const mlp::AdamState saved = adam.state();
  const auto saved_params = params.download(ctx);
  CHECK(saved.step == 3);
  run(adam, params, 3, 5);
  const auto straight = params.download(ctx);

  mlp::Adam resumed(ctx, n);
  resumed.restore(saved);
  auto params2 = test::device_copy(ctx, saved_params, "params (resumed)");
  run(resumed, params2, 3, 5);
  CHECK(params2.download(ctx) == straight);
  CHECK(resumed.step_count() == 5);

  mlp::AdamState wrong = saved;
  wrong.m.pop_back();
  CHECK_THROWS_WITH_AS(resumed.restore(wrong), doctest::Contains("another MLP configuration"), Error);
}

TEST_CASE("schedule: learning rate of supplement eq. 24 at key steps") {
  const mlp::LrSchedule s;  // 5e-4 → 5e-6 over 1e6 steps, sine warm-up from 0.01 over 2,500 steps
  const double pi = 3.14159265358979323846;
  // Closed form: lr(step) = delay · lr_init · (lr_final / lr_init)^(step / max_steps).
  auto decay = [&](double step) { return 5e-4 * std::pow(1e-2, step / 1e6); };
  CHECK(mlp::learning_rate(s, 0) == doctest::Approx(0.01 * 5e-4).epsilon(1e-12));
  CHECK(mlp::learning_rate(s, 1250) ==
        doctest::Approx((0.01 + 0.99 * std::sin(pi / 4.0)) * decay(1250)).epsilon(1e-12));
  CHECK(mlp::learning_rate(s, 2500) == doctest::Approx(decay(2500)).epsilon(1e-12));
  CHECK(mlp::learning_rate(s, 500000) == doctest::Approx(5e-5).epsilon(1e-12));  // geometric mean
  CHECK(mlp::learning_rate(s, 1000000) == doctest::Approx(5e-6).epsilon(1e-12));
  CHECK(mlp::learning_rate(s, 2000000) == doctest::Approx(5e-6).epsilon(1e-12));  // clamped after the run
  // Monotone: rising through the warm-up, falling after it.
  for (int64_t step = 1; step <= 2500; step += 100) CHECK(mlp::learning_rate(s, step) > mlp::learning_rate(s, step - 1));
  for (int64_t step = 2600; step <= 1000000; step += 99999) {
    CHECK(mlp::learning_rate(s, step) < mlp::learning_rate(s, step - 100));
  }
  mlp::LrSchedule no_warmup = s;
  no_warmup.warmup_steps = 0;
  CHECK(mlp::learning_rate(no_warmup, 0) == doctest::Approx(5e-4).epsilon(1e-12));
  mlp::LrSchedule bad = s;
  bad.lr_final = 0.0;
  CHECK_THROWS_WITH_AS(mlp::learning_rate(bad, 1), doctest::Contains("lr_final"), Error);
}
