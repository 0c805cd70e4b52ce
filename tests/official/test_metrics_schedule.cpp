// Our metrics (host/eval/metrics: PSNR, SSIM) and learning-rate schedule (host/mlp/adam: supplement eq. 24) against
// the official math.py's own outputs (tests/official/fixtures, written by make_vectors.py from google/mipnerf, in
// float64 on float32 images). Both sides compute in double, so the bounds are double-precision rounding.
#include <doctest/doctest.h>

#include <cstdint>
#include <vector>

#include "eval/metrics.hpp"
#include "mlp/adam.hpp"
#include "official_fixtures.hpp"

using namespace mipnerf;
using official::flat;

TEST_CASE("learning_rate_decay: our schedule is the official one, with and without the warm-up") {
  const auto fx = official::fixture("schedule.json");
  std::vector<int64_t> steps;
  for (const auto& s : fx.at("steps")) steps.push_back(s.get<int64_t>());
  for (const auto& c : fx.at("cases")) {
    mlp::LrSchedule schedule;
    schedule.lr_init = c.at("lr_init").get<double>();
    schedule.lr_final = c.at("lr_final").get<double>();
    schedule.max_steps = c.at("max_steps").get<int64_t>();
    schedule.warmup_steps = c.at("lr_delay_steps").get<int64_t>();
    schedule.warmup_mult = c.at("lr_delay_mult").get<double>();
    CAPTURE(schedule.warmup_steps);
    const auto expected = flat(c.at("lr"), {steps.size()});
    std::vector<double> ours;
    for (const int64_t step : steps) ours.push_back(mlp::learning_rate(schedule, step));
    // exp, log and sin in double (≤ 1 ulp each) and a few products: 1e-13 relative is ~500 ulp, far below any
    // convention change (a step off by one moves the warm-up by ~1e-3 relative).
    OFFICIAL_CHECK_AGREES("learning rate", ours, expected, [&](size_t i) { return 1e-13 * expected[i]; });
  }
}

TEST_CASE("mse_to_psnr and compute_ssim: our PSNR and SSIM are the official ones on two image pairs") {
  const auto fx = official::fixture("metrics.json");
  for (const auto& pair : fx.at("pairs")) {
    const size_t h = pair.at("pred").size(), w = pair.at("pred").at(0).size();
    const auto pred = official::as_float(flat(pair.at("pred"), {h, w, 3}));
    const auto gt = official::as_float(flat(pair.at("gt"), {h, w, 3}));
    const eval::ImageView a{pred.data(), h, w, 3}, b{gt.data(), h, w, 3};
    // The images are float32 values on both sides; the MSE is a double sum of h·w·3 ≈ 1700 squares: ≤ 1700·2^-53
    // relative ≈ 2e-13, and PSNR = −10·log10(mse) inherits it as ~1e-12 absolute (10/ln 10 · relative error).
    const double mse = pair.at("mse").get<double>();
    CHECK(eval::mse(a, b) == doctest::Approx(mse).epsilon(1e-12));
    const std::vector<double> psnr{eval::psnr(a, b)};
    OFFICIAL_CHECK_AGREES("PSNR", psnr, std::vector<double>{pair.at("psnr").get<double>()},
                          official::constant_bound(1e-10));
    // SSIM: separable 11-tap double filters, σ = E[x²] − μ² cancelling up to ~300× for these images (σ ≈ 1e-3 of
    // E[x²] ≈ 0.3), so ~1e-13 per window; the mean of the map keeps it: 1e-10 absolute, far below SSIM's resolution.
    const std::vector<double> ssim{eval::ssim(a, b)};
    OFFICIAL_CHECK_AGREES("SSIM", ssim, std::vector<double>{pair.at("ssim").get<double>()},
                          official::constant_bound(1e-10));
  }
}
