// mip-NeRF 360's data loss, our reference (host/ref/loss.hpp) and the loss kernel (kernels/loss.cl with
// CHARBONNIER_LOSS and LOSS_CHANNEL_MEAN) against the official multinerf train_utils.compute_data_loss
// (fixtures/multinerf_data_loss.json, written by make_data_loss_vectors.py): the Charbonnier term √(r² + 0.001²) and
// the squared error, each over a batch weighed by lossmult = 1 and by multiscale footprints, the loss and its gradient
// with respect to the rendered colour. The official math ran in float64.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "cl/buffer.hpp"
#include "official_fixtures.hpp"
#include "ops/loss.hpp"
#include "ref/loss.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

struct DataLossCase {
  std::string type;
  double padding = 0.0;  // 0 for the squared error
  std::vector<double> lossmult, d_rgb;
  double loss = 0.0;
  bool weighted() const {
    for (double m : lossmult) {
      if (m != 1.0) return true;
    }
    return false;
  }
  double lossmult_sum() const {
    double sum = 0.0;
    for (double m : lossmult) sum += m;
    return sum;
  }
};

DataLossCase fixture_case(const io::Json& c) {
  DataLossCase out;
  out.type = c.at("data_loss_type").get<std::string>();
  out.padding = out.type == "charb" ? c.at("charb_padding").get<double>() : 0.0;
  out.lossmult = official::flat(c.at("lossmult"));
  out.loss = c.at("loss").get<double>();
  out.d_rgb = official::flat(c.at("d_rgb"), {out.lossmult.size(), 3});
  return out;
}

bool close(double actual, double expected, double relative, double absolute = 0.0) {
  return std::abs(actual - expected) <= relative * std::abs(expected) + absolute;
}

}  // namespace

TEST_CASE("official data loss: Charbonnier and squared error, per-channel mean, lossmult, as multinerf computes them") {
  const io::Json fixture = official::multinerf_fixture("multinerf_data_loss.json");
  const std::vector<double> target = official::flat(fixture.at("target_rgb"));
  const std::vector<double> rendered = official::flat(fixture.at("rendered_rgb"));
  const size_t n_rays = target.size() / 3;
  REQUIRE(fixture.at("cases").size() == 4);
  auto& ctx = test::test_context();
  for (const auto& c : fixture.at("cases")) {
    const DataLossCase expected = fixture_case(c);
    CAPTURE(expected.type);
    CAPTURE(expected.weighted());
    REQUIRE(expected.lossmult.size() == n_rays);
    const ref::DataLossOptions data{expected.padding, true};

    // The reference in double: the same sums in another order, so within 1e-13 of the official's.
    std::vector<double> d_comp(3 * n_rays), partials(2);
    ref::loss_fwd_bwd(rendered.data(), target.data(), expected.lossmult.data(), 1.0, 1.0 / expected.lossmult_sum(),
                      d_comp.data(), partials.data(), 0, 0, n_rays, n_rays, data);
    CHECK(close(partials[ref::loss_sum_weighted] / expected.lossmult_sum(), expected.loss, 1e-13));
    for (size_t i = 0; i < d_comp.size(); ++i) {
      CAPTURE(i);
      CHECK(close(d_comp[i], expected.d_rgb[i], 1e-13, 1e-300));
    }

    // Without the channel mean the loss and its gradient are 3× the official's: google/mipnerf's sum, not this.
    std::vector<double> summed(3 * n_rays), summed_partials(2);
    ref::loss_fwd_bwd(rendered.data(), target.data(), expected.lossmult.data(), 1.0, 1.0 / expected.lossmult_sum(),
                      summed.data(), summed_partials.data(), 0, 0, n_rays, n_rays, {expected.padding, false});
    CHECK(close(summed_partials[ref::loss_sum_weighted] / expected.lossmult_sum(), 3.0 * expected.loss, 1e-13));

    // The kernel in float32. Inputs are the fixture's float32 values. The gradient w·(1/Σm)·m·(1/3)·r/√(r² + p²)
    // (or 2r): the difference, the square, the padding's add, the square root (≤ 3 ulp in OpenCL C), the division
    // (≤ 2.5 ulp) and four products: ≤ 10 units of 2^-24 ≈ 6e-7 relative, so 2e-6. The loss: each term carries as
    // much, the channel and tree sums add ≤ 9 units more: 3e-6.
    ops::Loss loss(ctx, ops::LossOptions{expected.weighted(), static_cast<float>(expected.padding), true});
    ocl::DeviceArray<float> comp(ctx, 3 * n_rays, "comp_rgb"), target_device(ctx, 3 * n_rays, "target_rgb");
    ocl::DeviceArray<float> lossmult(ctx, n_rays, "lossmult"), d_device(ctx, 3 * n_rays, "d_comp_rgb");
    comp.upload(ctx, std::vector<float>(rendered.begin(), rendered.end()));
    target_device.upload(ctx, std::vector<float>(target.begin(), target.end()));
    lossmult.upload(ctx, std::vector<float>(expected.lossmult.begin(), expected.lossmult.end()));
    ocl::DeviceArray<float> device_partials(ctx, 2 * loss.groups_for(n_rays), "partials");
    loss.fwd_bwd(comp, target_device, expected.weighted() ? &lossmult : nullptr, {1.0f, expected.lossmult_sum()},
                 d_device, device_partials, {n_rays, 0, 0});
    const auto level = ops::sum_loss_partials(device_partials.download(ctx), loss.groups_for(n_rays),
                                              expected.lossmult_sum(), n_rays);
    CHECK(close(level.loss(), expected.loss, 3e-6));
    const std::vector<float> d_float = d_device.download(ctx);
    for (size_t i = 0; i < d_float.size(); ++i) {
      CAPTURE(i);
      CHECK(close(d_float[i], expected.d_rgb[i], 2e-6));
    }
  }
}
