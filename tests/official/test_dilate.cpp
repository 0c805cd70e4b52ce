// mip-NeRF 360's max-dilation of proposal histograms, our reference (host/ref/dilate.hpp) and kernel
// (kernels/dilate.cl) against the official multinerf stepfun.max_dilate_weights (renormalised, domain (0, 1)) on random
// histograms with the dilations Model.__call__ uses after 64 and 64 × 64 samples, and a wide one
// (fixtures/multinerf_proposal.json, written by make_outer_vectors.py). The official keeps [1:-1] of both outputs:
// compared so. The official math ran in float64.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "official_fixtures.hpp"
#include "ops/dilate.hpp"
#include "ref/dilate.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

TEST_CASE("mipnerf360 proposal: max_dilate_weights, our reference and kernel") {
  const io::Json fixture = official::multinerf_fixture("multinerf_proposal.json");
  const io::Json& cases = fixture.at("max_dilate_weights");
  REQUIRE(cases.size() == 3);
  auto& ctx = test::test_context();
  ops::MaxDilate stage(ctx);
  for (const auto& item : cases) {
    const double dilation = item.at("dilation").get<double>();
    CAPTURE(dilation);
    const auto t = official::flat(item.at("t")), w = official::flat(item.at("w"));
    const auto t_dilate = official::flat(item.at("t_dilate")), w_dilate = official::flat(item.at("w_dilate"));
    const size_t n_rays = item.at("t").size(), n = w.size() / n_rays;
    std::vector<double> expected_s, expected_w;  // the official's [1:-1] of each ray
    for (size_t ray = 0; ray < n_rays; ++ray) {
      expected_s.insert(expected_s.end(), t_dilate.begin() + ray * (3 * n + 1) + 1,
                        t_dilate.begin() + (ray + 1) * (3 * n + 1) - 1);
      expected_w.insert(expected_w.end(), w_dilate.begin() + ray * 3 * n + 1, w_dilate.begin() + (ray + 1) * 3 * n - 1);
    }
    std::vector<double> s_out, w_out;
    ref::max_dilate_weights_fwd(t, w, dilation, 0.0, 1.0, s_out, w_out, n_rays, n);
    OFFICIAL_CHECK_AGREES("reference edges", s_out, expected_s, official::constant_bound(1e-15));
    OFFICIAL_CHECK_AGREES("reference weights", w_out, expected_w,
                          [&](size_t i) { return 1e-12 * std::abs(expected_w[i]) + 1e-15; });
    // The kernel, with d rounded to float and each knot s ± d rounded once: a weight moves by its pooled pdf (at most
    // the ray's largest) times the moves of its two knots, plus its own roundings.
    auto s_in = official::upload(ctx, official::as_float(t), "s"), w_in = official::upload(ctx, official::as_float(w), "w");
    ocl::DeviceArray<float> ks(ctx, n_rays * ops::dilated_edges(n), "s_out"),
        kw(ctx, n_rays * ops::dilated_intervals(n), "w_out");
    ocl::DeviceArray<uint32_t> scratch(ctx, n_rays * n, "scratch");
    stage.fwd(s_in, w_in, n_rays, n, static_cast<float>(dilation), ks, kw, scratch);
    const double knot = 4 * official::kU * (1 + dilation);
    OFFICIAL_CHECK_AGREES("kernel edges", ks.download(ctx), expected_s, official::constant_bound(knot));
    std::vector<double> largest_pdf(n_rays, 0.0);
    for (size_t ray = 0; ray < n_rays; ++ray) {
      for (size_t k = 0; k < n; ++k) {
        const double width = t[ray * (n + 1) + k + 1] - t[ray * (n + 1) + k];
        largest_pdf[ray] = std::max(largest_pdf[ray], w[ray * n + k] / width);
      }
    }
    const size_t m = ops::dilated_intervals(n);
    OFFICIAL_CHECK_AGREES("kernel weights", kw.download(ctx), expected_w, [&](size_t i) {
      return 2 * knot * largest_pdf[i / m] + (3 * n + 8) * official::kU * std::abs(expected_w[i]);
    });
  }
}
