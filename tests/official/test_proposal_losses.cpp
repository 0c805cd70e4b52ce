// Zip-NeRF's proposal losses, our references (host/ref/interlevel.hpp, distortion.hpp) and kernels
// (kernels/interlevel.cl, distortion.cl) against the official camp_zipnerf functions' own outputs
// (fixtures/zipnerf_proposal.json, written by make_proposal_vectors.py): stepfun.blur_and_resample_weights (wide and
// narrow blurs, a zero-width interval, queries past the histogram, an empty histogram),
// loss_utils.spline_interlevel_loss over two rounds with their blurs and its jax.grad w.r.t. each round's proposal
// weights, stepfun.lossfun_distortion, loss_utils.distortion_loss and its gradients w.r.t. the weights and the edges.
// The official math ran in float64.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "official_fixtures.hpp"
#include "ops/distortion.hpp"
#include "ops/interlevel.hpp"
#include "ref/distortion.hpp"
#include "ref/interlevel.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

io::Json proposal_fixture() {
  return official::zipnerf_fixture("zipnerf_proposal.json");
}

// The official runs blur_stepfun's cumulative sums of slopes and the integral's cumulative sums in float64: a drift
// of ~1e-16 of the slopes' sum (Σ|jumps| / 2r ≈ 2e4 for these histograms at r = 0.003) over a unit span, ~2e-12 at
// worst (3e-15 seen); ours in double is smaller still.
constexpr double kOfficialBlurBound = 1e-11;

struct ProposalRays {
  std::vector<double> c, w, cp, wp;
  size_t n_rays = 0, n = 0, m = 0;
};

std::vector<double> proposal_w_blur_bound(const ProposalRays& r, double halfwidth) {
  std::vector<double> bound;
  for (size_t ray = 0; ray < r.n_rays; ++ray) {
    const auto b = ref::blur_and_resample_float32_bound(&r.c[ray * (r.n + 1)], &r.w[ray * r.n], r.n,
                                                        &r.cp[ray * (r.m + 1)], r.m, halfwidth);
    for (double x : b) bound.push_back(x + kOfficialBlurBound);
  }
  return bound;
}

struct ProposalKernelRun {
  std::vector<float> w_blur, ray_loss, d_wp;
};

ProposalKernelRun run_proposal_kernel(const ProposalRays& r, float halfwidth, float mult) {
  auto& ctx = test::test_context();
  ops::SplineInterlevel stage(ctx);
  auto c = official::upload(ctx, official::as_float(r.c), "c"), w = official::upload(ctx, official::as_float(r.w), "w");
  auto cp = official::upload(ctx, official::as_float(r.cp), "cp");
  auto wp = official::upload(ctx, official::as_float(r.wp), "wp");
  ocl::DeviceArray<float> w_blur(ctx, r.n_rays * r.m, "w_blur"), ray_loss(ctx, r.n_rays, "ray_loss");
  ocl::DeviceArray<float> d_wp(ctx, r.n_rays * r.m, "d_wp");
  const ops::InterlevelInputs in{c, w, cp, wp, r.n_rays, r.n, r.m};
  stage.fwd(in, halfwidth, w_blur, ray_loss);
  stage.bwd(in, w_blur, mult, r.n_rays, d_wp);
  return {w_blur.download(ctx), ray_loss.download(ctx), d_wp.download(ctx)};
}

}  // namespace

TEST_CASE("zipnerf proposal: blur_and_resample_weights, our reference and kernel") {
  const io::Json fixture = proposal_fixture();  // held: a range-for over a temporary's member would dangle
  const io::Json& cases = fixture.at("blur_and_resample_weights");
  REQUIRE(cases.size() == 5);
  for (const auto& item : cases) {
    CAPTURE(item.at("name").get<std::string>());
    ProposalRays r;
    r.c = official::flat(item.at("t"));
    r.w = official::flat(item.at("w"));
    r.cp = official::flat(item.at("tq"));
    const auto expected = official::flat(item.at("wq"));
    r.n_rays = item.at("w").size();
    r.n = r.w.size() / r.n_rays;
    r.m = expected.size() / r.n_rays;
    r.wp.assign(r.n_rays * r.m, 0.0);
    const double halfwidth = item.at("halfwidth").get<double>();
    std::vector<double> ours(r.n_rays * r.m), ray_loss(r.n_rays);
    ref::spline_interlevel_fwd(r.c.data(), r.w.data(), r.cp.data(), r.wp.data(), halfwidth, ours.data(),
                               ray_loss.data(), r.n_rays, r.n, r.m);
    OFFICIAL_CHECK_AGREES("reference w_blur", ours, expected, official::constant_bound(kOfficialBlurBound));
    const auto bound = proposal_w_blur_bound(r, halfwidth);
    const auto kernel = run_proposal_kernel(r, static_cast<float>(halfwidth), 0.01f);
    OFFICIAL_CHECK_AGREES("kernel w_blur", kernel.w_blur, expected, [&](size_t i) { return bound[i]; });
  }
}

TEST_CASE("zipnerf proposal: spline_interlevel_loss and its gradient over two rounds, reference and kernel") {
  const io::Json fixture = proposal_fixture();
  const io::Json& s = fixture.at("spline_interlevel");
  const auto c = official::flat(s.at("c")), w = official::flat(s.at("w"));
  const auto blurs = s.at("blurs").get<std::vector<double>>();
  const double mult = s.at("mults").get<double>();
  const io::Json& rounds = s.at("rounds");
  REQUIRE(rounds.size() == 2);
  for (size_t k = 0; k < 2; ++k) {
    CAPTURE(k);
    ProposalRays r;
    r.c = c;
    r.w = w;
    r.cp = official::flat(rounds[k].at("cp"));
    r.wp = official::flat(rounds[k].at("wp"));
    r.n_rays = s.at("w").size();
    r.n = w.size() / r.n_rays;
    r.m = r.wp.size() / r.n_rays;
    const double loss = rounds[k].at("loss").get<double>();
    const auto d_wp = official::flat(rounds[k].at("d_wp"));
    // Reference: the loss to relative roundoff of the float64 official (its w_blur² / ε terms amplify 1e-10 of
    // w_blur error by 2 w_blur / ε ≈ 2e6 at most: relative 1e-9 covers it for losses of 0.3 and 300).
    std::vector<double> w_blur(r.n_rays * r.m), ray_loss(r.n_rays), grad(r.n_rays * r.m);
    ref::spline_interlevel_fwd(r.c.data(), r.w.data(), r.cp.data(), r.wp.data(), blurs[k], w_blur.data(),
                               ray_loss.data(), r.n_rays, r.n, r.m);
    const double grad_scale = mult / static_cast<double>(r.n_rays * r.m);
    ref::spline_interlevel_bwd(w_blur.data(), r.wp.data(), grad_scale, grad.data(), grad.size());
    const double ours = ref::spline_interlevel_loss(ray_loss, r.m, mult);
    CHECK(std::abs(ours - loss) <= 1e-9 * loss);
    // d_wp = −scale (2e/s + e²/s²): a w_blur error δ moves it by scale (2/s + 2e/s²) δ.
    std::vector<double> grad_bound(grad.size());
    for (size_t i = 0; i < grad.size(); ++i) {
      const double si = r.wp[i] + ref::kInterlevelEps, e = std::max(0.0, w_blur[i] - r.wp[i]);
      grad_bound[i] = grad_scale * (2 / si + 2 * e / (si * si)) * kOfficialBlurBound + 1e-12 * std::abs(grad[i]);
    }
    OFFICIAL_CHECK_AGREES("reference d_wp", grad, d_wp, [&](size_t i) { return grad_bound[i]; });
    // The kernel, with the float32 bound of each w_blur carried through the loss and the gradient.
    const auto kernel = run_proposal_kernel(r, static_cast<float>(blurs[k]), static_cast<float>(mult));
    const auto bound = proposal_w_blur_bound(r, blurs[k]);
    double loss_bound = 0;
    std::vector<double> kernel_grad_bound(grad.size());
    for (size_t i = 0; i < grad.size(); ++i) {
      const double si = r.wp[i] + ref::kInterlevelEps, e = std::max(0.0, w_blur[i] - r.wp[i]), d = bound[i];
      const double term = ref::interlevel_interval_loss(w_blur[i], r.wp[i]);
      loss_bound += (2 * e + d) * d / si + (r.m + 8) * official::kU * term;
      kernel_grad_bound[i] =
          grad_scale * ((2 / si + 2 * (e + d) / (si * si)) * d) + 16 * official::kU * std::abs(grad[i]);
    }
    loss_bound *= mult / static_cast<double>(r.n_rays * r.m);
    const double kernel_loss = ops::interlevel_loss_value(kernel.ray_loss, r.n_rays, r.m, static_cast<float>(mult));
    INFO("kernel loss " << kernel_loss << " official " << loss << " bound " << loss_bound);
    CHECK(std::abs(kernel_loss - loss) <= loss_bound);
    OFFICIAL_CHECK_AGREES("kernel d_wp", kernel.d_wp, d_wp, [&](size_t i) { return kernel_grad_bound[i]; });
  }
}

TEST_CASE("zipnerf proposal: lossfun_distortion, distortion_loss and their gradients, reference and kernel") {
  const io::Json fixture = proposal_fixture();
  const io::Json& d = fixture.at("distortion");
  const auto t = official::flat(d.at("t")), w = official::flat(d.at("w"));
  const auto per_ray = official::flat(d.at("per_ray"));
  const auto d_t = official::flat(d.at("d_t_of_mean")), d_w = official::flat(d.at("d_w_of_mean"));
  const size_t rays = per_ray.size(), n = w.size() / rays;
  const double mult = d.at("mult").get<double>(), loss = d.at("loss").get<double>();
  std::vector<double> ours(rays), ours_d_w(w.size()), ours_d_t(t.size());
  ref::distortion_fwd(t.data(), w.data(), ours.data(), rays, n);
  ref::distortion_bwd(t.data(), w.data(), 1.0 / rays, ours_d_w.data(), ours_d_t.data(), rays, n);
  OFFICIAL_CHECK_AGREES("reference per ray", ours, per_ray, [&](size_t i) { return 1e-14 * per_ray[i]; });
  CHECK(std::abs(ref::distortion_loss(ours, mult) - loss) <= 1e-14 * loss);
  OFFICIAL_CHECK_AGREES("reference d_w", ours_d_w, d_w, [&](size_t i) { return 1e-13 * std::abs(d_w[i]) + 1e-16; });
  OFFICIAL_CHECK_AGREES("reference d_t", ours_d_t, d_t, official::constant_bound(1e-14));

  auto& ctx = test::test_context();
  ops::Distortion stage(ctx);
  auto t_dev = official::upload(ctx, official::as_float(t), "t"),
       w_dev = official::upload(ctx, official::as_float(w), "w");
  ocl::DeviceArray<float> ray_loss(ctx, rays, "ray_loss"), k_d_w(ctx, w.size(), "d_w"), k_d_t(ctx, t.size(), "d_t");
  const ops::DistortionInputs in{t_dev, w_dev, rays, n};
  stage.fwd(in, ray_loss);
  stage.bwd(in, 1.0f, rays, k_d_w, k_d_t);  // mult 1: the gradient of the mean, as the fixture's
  const auto k_loss = ray_loss.download(ctx), k_w = k_d_w.download(ctx), k_t = k_d_t.download(ctx);
  // Non-negative sums: (4N + 16) u relative (tests/ops/test_distortion.cpp); d_t's cancelling 2w (W_< − W_>) is
  // bounded by (N + 8) u of 2 w (2W + w) over the edge's two intervals.
  const double sums = (4.0 * n + 16) * official::kU;
  OFFICIAL_CHECK_AGREES("kernel per ray", k_loss, per_ray, [&](size_t i) { return sums * per_ray[i]; });
  CHECK(std::abs(ops::distortion_loss_value(k_loss, rays, static_cast<float>(mult)) - loss) <= sums * loss);
  OFFICIAL_CHECK_AGREES("kernel d_w", k_w, d_w, [&](size_t i) { return sums * std::abs(d_w[i]) + 1e-12; });
  std::vector<double> t_bound(t.size());
  for (size_t ray = 0; ray < rays; ++ray) {
    double total = 0;
    for (size_t k = 0; k < n; ++k) total += w[ray * n + k];
    for (size_t e = 0; e <= n; ++e) {
      double near = 0;
      for (size_t k : {e - 1, e}) {
        if (k < n) near += w[ray * n + k] * (2 * total + w[ray * n + k]);
      }
      t_bound[ray * (n + 1) + e] = (n + 8) * official::kU * near / rays + 1e-12;
    }
  }
  OFFICIAL_CHECK_AGREES("kernel d_t", k_t, d_t, [&](size_t i) { return t_bound[i]; });
}
