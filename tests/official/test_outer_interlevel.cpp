// mip-NeRF 360's interlevel loss, our reference (host/ref/interlevel_outer.hpp) and kernel (kernels/interlevel_outer.cl)
// against the official multinerf functions' own outputs (fixtures/multinerf_proposal.json, written by
// make_outer_vectors.py): stepfun.inner_outer's outer measure and stepfun.lossfun_outer on single rays chosen for their
// edges (proposal edges on NeRF edges, NeRF edges past both ends, one proposal interval holding all, proposal zeros
// under NeRF mass, an empty NeRF histogram), and train_utils.interlevel_loss over two rounds with its jax.grad w.r.t.
// each round's weights. The official math ran in float64.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "official_fixtures.hpp"
#include "ops/interlevel_outer.hpp"
#include "ref/interlevel.hpp"
#include "ref/interlevel_outer.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

io::Json outer_fixture() { return official::multinerf_fixture("multinerf_proposal.json"); }

struct OuterRays {
  std::vector<double> c, w, cp, wp;
  size_t n_rays = 0, n = 0, m = 0;
};

// What float32 can move each NeRF interval's outer bound by (a sum of its window's K non-negative weights: K roundings
// of partial sums no larger than the bound) and the window sizes themselves.
struct OuterFloatBounds {
  std::vector<double> bound_error;  // [R][N]
  std::vector<size_t> lo, hi;       // [R][N] each interval's window [lo, hi) into the round's weights
};

OuterFloatBounds outer_float_bounds(const OuterRays& r) {
  OuterFloatBounds b;
  std::vector<double> bound(r.n);
  for (size_t ray = 0; ray < r.n_rays; ++ray) {
    const double* c = &r.c[ray * (r.n + 1)];
    const double* cp = &r.cp[ray * (r.m + 1)];
    ref::outer_bounds(c, r.n, cp, &r.wp[ray * r.m], r.m, bound.data());
    for (size_t j = 0; j < r.n; ++j) {
      size_t lo = 0, hi = 0, unused = 0;
      ref::outer_searchsorted(cp, r.m + 1, c[j], &lo, &unused);
      ref::outer_searchsorted(cp, r.m + 1, c[j + 1], &unused, &hi);
      b.lo.push_back(lo);
      b.hi.push_back(hi);
      b.bound_error.push_back(static_cast<double>(hi > lo ? hi - lo : 0) * official::kU * bound[j]);
    }
  }
  return b;
}

struct OuterKernelRun {
  std::vector<float> ray_loss, d_wp;
};

OuterKernelRun run_outer_kernel(const OuterRays& r, float mult) {
  auto& ctx = test::test_context();
  ops::OuterInterlevel stage(ctx);
  auto c = official::upload(ctx, official::as_float(r.c), "c"), w = official::upload(ctx, official::as_float(r.w), "w");
  auto cp = official::upload(ctx, official::as_float(r.cp), "cp");
  auto wp = official::upload(ctx, official::as_float(r.wp), "wp");
  ocl::DeviceArray<float> ray_loss(ctx, r.n_rays, "ray_loss"), d_wp(ctx, r.n_rays * r.m, "d_wp");
  const ops::InterlevelInputs in{c, w, cp, wp, r.n_rays, r.n, r.m};
  stage.fwd(in, ray_loss);
  stage.bwd(in, mult, r.n_rays, d_wp);
  return {ray_loss.download(ctx), d_wp.download(ctx)};
}

// The kernel's loss (per ray, summed over its intervals) and gradient bounds, from the reference's values and the
// float32 error of each outer bound: e = w − bound moves by the bound's error d plus one rounding, e² / (w + ε) by
// (2e + d) d / s plus ~4 roundings; each d_wp_k sums the −2e_j/s terms of the windows holding it.
void check_outer_kernel(const OuterRays& r, double mult, const std::vector<double>& ref_ray_loss,
                        const std::vector<double>& official_d_wp, const std::string& what) {
  const auto kernel = run_outer_kernel(r, static_cast<float>(mult));
  const auto fb = outer_float_bounds(r);
  const double scale = mult / static_cast<double>(r.n_rays * r.n);
  std::vector<double> loss_bound(r.n_rays, 0.0), grad_bound(r.n_rays * r.m, 0.0);
  std::vector<double> bound(r.n);
  for (size_t ray = 0; ray < r.n_rays; ++ray) {
    ref::outer_bounds(&r.c[ray * (r.n + 1)], r.n, &r.cp[ray * (r.m + 1)], &r.wp[ray * r.m], r.m, bound.data());
    for (size_t j = 0; j < r.n; ++j) {
      const size_t i = ray * r.n + j;
      const double w = r.w[i], s = w + ref::kInterlevelEps, e = std::max(0.0, w - bound[j]);
      const double d = fb.bound_error[i] + official::kU * (w + bound[j]);
      loss_bound[ray] += (2 * e + d) * d / s + (r.n + 6) * official::kU * ref::outer_interval_loss(w, bound[j]);
      for (size_t k = fb.lo[i]; k < fb.hi[i]; ++k) {
        grad_bound[ray * r.m + k] += scale * 2 * (d + 4 * official::kU * e) / s;
      }
    }
  }
  for (size_t k = 0; k < grad_bound.size(); ++k) {
    grad_bound[k] += static_cast<double>(r.n + 2) * official::kU * std::abs(official_d_wp[k]);
  }
  OFFICIAL_CHECK_AGREES(what + ": kernel ray loss", kernel.ray_loss, ref_ray_loss,
                        [&](size_t i) { return loss_bound[i] + 1e-300; });
  OFFICIAL_CHECK_AGREES(what + ": kernel d_wp", kernel.d_wp, official_d_wp,
                        [&](size_t i) { return grad_bound[i] + 1e-300; });
}

}  // namespace

TEST_CASE("mipnerf360 proposal: inner_outer and lossfun_outer on single rays, reference and kernel") {
  const io::Json fixture = outer_fixture();  // held: a range-for over a temporary's member would dangle
  const io::Json& cases = fixture.at("lossfun_outer");
  REQUIRE(cases.size() == 5);
  for (const auto& item : cases) {
    const std::string name = item.at("name").get<std::string>();
    CAPTURE(name);
    OuterRays r;
    r.c = official::flat(item.at("c"));
    r.w = official::flat(item.at("w"));
    r.cp = official::flat(item.at("cp"));
    r.wp = official::flat(item.at("wp"));
    r.n_rays = 1;
    r.n = r.w.size();
    r.m = r.wp.size();
    const auto outer = official::flat(item.at("outer")), loss = official::flat(item.at("loss"));
    std::vector<double> bound(r.n);
    ref::outer_bounds(r.c.data(), r.n, r.cp.data(), r.wp.data(), r.m, bound.data());
    OFFICIAL_CHECK_AGREES("reference outer measure", bound, outer, official::constant_bound(1e-15));
    std::vector<double> ours(r.n);
    for (size_t j = 0; j < r.n; ++j) ours[j] = ref::outer_interval_loss(r.w[j], bound[j]);
    OFFICIAL_CHECK_AGREES("reference lossfun_outer", ours, loss,
                          [&](size_t j) { return 1e-14 * std::max(1.0, loss[j]); });
    // The kernel's per-ray sum against the official's, and its gradient against the reference's (these single rays
    // have no official gradient; the batch below has).
    double official_sum = 0;
    for (double v : loss) official_sum += v;
    std::vector<double> ref_grad(r.m);
    ref::outer_interlevel_bwd(r.c.data(), r.w.data(), r.cp.data(), r.wp.data(), 1.0 / static_cast<double>(r.n),
                              ref_grad.data(), 1, r.n, r.m);
    check_outer_kernel(r, 1.0, {official_sum}, ref_grad, name);
  }
}

TEST_CASE("mipnerf360 proposal: interlevel_loss and its gradient over two rounds, reference and kernel") {
  const io::Json fixture = outer_fixture();
  const io::Json& s = fixture.at("interlevel_loss");
  const auto c = official::flat(s.at("c")), w = official::flat(s.at("w"));
  const double mult = s.at("mult").get<double>();
  const io::Json& rounds = s.at("rounds");
  const auto round_losses = s.at("round_losses").get<std::vector<double>>();
  REQUIRE(rounds.size() == 2);
  double total = 0;
  for (size_t k = 0; k < 2; ++k) {
    CAPTURE(k);
    OuterRays r;
    r.c = c;
    r.w = w;
    r.cp = official::flat(rounds[k].at("cp"));
    r.wp = official::flat(rounds[k].at("wp"));
    r.n_rays = s.at("w").size();
    r.n = w.size() / r.n_rays;
    r.m = r.wp.size() / r.n_rays;
    const auto d_wp = official::flat(rounds[k].at("d_wp"));
    std::vector<double> ray_loss(r.n_rays), grad(r.n_rays * r.m);
    ref::outer_interlevel_fwd(r.c.data(), r.w.data(), r.cp.data(), r.wp.data(), ray_loss.data(), r.n_rays, r.n, r.m);
    const double ours = ref::outer_interlevel_loss(ray_loss, r.n, mult);
    CHECK(std::abs(ours - round_losses[k]) <= 1e-13 * round_losses[k]);
    total += ours;
    ref::outer_interlevel_bwd(r.c.data(), r.w.data(), r.cp.data(), r.wp.data(), mult / static_cast<double>(r.n_rays * r.n),
                              grad.data(), r.n_rays, r.n, r.m);
    OFFICIAL_CHECK_AGREES("reference d_wp", grad, d_wp,
                          [&](size_t i) { return 1e-13 * std::abs(d_wp[i]) + 1e-16; });
    // Some proposal weight must take a gradient, and the gap under NeRF mass the constant one of bound 0.
    CHECK(std::count_if(d_wp.begin(), d_wp.end(), [](double v) { return v != 0.0; }) > 0);
    check_outer_kernel(r, mult, ray_loss, d_wp, "round " + std::to_string(k));
    const auto kernel = run_outer_kernel(r, static_cast<float>(mult));
    const double kernel_loss = ops::outer_interlevel_loss_value(kernel.ray_loss, r.n_rays, r.n, static_cast<float>(mult));
    CHECK(std::abs(kernel_loss - round_losses[k]) <= 1e-5 * round_losses[k]);
  }
  CHECK(std::abs(total - s.at("loss").get<double>()) <= 1e-13 * total);
}
