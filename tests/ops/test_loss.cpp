// The loss stage (kernels/loss.cl, ops::Loss): against the double reference, finite differences, chunking,
// lossmult weighting, the official normalisation, and non-finite inputs.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "cl/buffer.hpp"
#include "ops/loss.hpp"
#include "ref/loss.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

// One level's inputs for a batch of rays, as floats (what the device sees).
struct Batch {
  std::vector<float> comp_rgb;    // [R][3]
  std::vector<float> target_rgb;  // [R][3]
  std::vector<float> lossmult;    // [R]
  size_t n_rays() const { return lossmult.size(); }
  double lossmult_sum() const {
    double sum = 0.0;
    for (float m : lossmult) sum += m;
    return sum;
  }
};

// Colours in [0, 1] as a trained network produces them (widened sigmoid), targets in [0, 1], lossmult
// either 1 or the area weights of a 4-scale multiscale set (1, 4, 16, 64).
Batch random_batch(size_t n_rays, bool multiscale, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> colour(-0.001f, 1.001f);
  std::uniform_int_distribution<int> scale(0, 3);
  Batch b;
  b.comp_rgb.resize(3 * n_rays);
  b.target_rgb.resize(3 * n_rays);
  b.lossmult.resize(n_rays, 1.0f);
  for (auto& v : b.comp_rgb) v = colour(rng);
  for (auto& v : b.target_rgb) v = std::clamp(colour(rng), 0.0f, 1.0f);
  if (multiscale) {
    for (auto& m : b.lossmult) m = static_cast<float>(1 << (2 * scale(rng)));
  }
  return b;
}

std::vector<double> to_double(const std::vector<float>& v) { return std::vector<double>(v.begin(), v.end()); }

ocl::DeviceArray<float> upload(ocl::Context& ctx, const std::vector<float>& data, const char* name) {
  ocl::DeviceArray<float> array(ctx, data.size(), name);
  array.upload(ctx, data);
  return array;
}

// What one device run of a whole level returns.
struct DeviceResult {
  std::vector<float> d_comp_rgb;  // [R][3]
  std::vector<float> partials;    // [groups][2]
  size_t n_groups = 0;
};

// Runs the level over the batch in chunks of `chunk` rays (0 = one launch), each chunk's comp_rgb and
// d_comp_rgb in their own chunk-sized buffers, targets and lossmult batch-sized (batch_offset).
DeviceResult run_device(ops::Loss& loss, const Batch& b, float level_weight, size_t chunk = 0) {
  auto& ctx = test::test_context();
  const size_t n = b.n_rays();
  if (chunk == 0) chunk = n;
  auto target = upload(ctx, b.target_rgb, "target_rgb [batch][3]");
  auto lossmult = upload(ctx, b.lossmult, "lossmult [batch]");
  size_t total_groups = 0;
  for (size_t start = 0; start < n; start += chunk) total_groups += loss.groups_for(std::min(chunk, n - start));
  ocl::DeviceArray<float> partials(ctx, 2 * total_groups, "loss partials [groups][2]");
  partials.fill(ctx, std::numeric_limits<float>::quiet_NaN());  // every slot must be written
  DeviceResult result;
  result.d_comp_rgb.resize(3 * n);
  const ops::LossLevelArgs level{level_weight, b.lossmult_sum()};
  size_t group = 0;
  for (size_t start = 0; start < n; start += chunk) {
    const size_t count = std::min(chunk, n - start);
    std::vector<float> comp_chunk(b.comp_rgb.begin() + 3 * start, b.comp_rgb.begin() + 3 * (start + count));
    auto comp = upload(ctx, comp_chunk, "comp_rgb [chunk][3]");
    ocl::DeviceArray<float> d_comp(ctx, 3 * count, "d_comp_rgb [chunk][3]");
    loss.fwd_bwd(comp, target, loss.options().multiscale ? &lossmult : nullptr, level, d_comp, partials,
                 ops::LossChunk{count, start, group});
    d_comp.download(ctx, result.d_comp_rgb.data() + 3 * start, 3 * count);
    group += loss.groups_for(count);
  }
  result.partials = partials.download(ctx);
  result.n_groups = total_groups;
  return result;
}

// Reference of a whole level in one chunk with the device's group size.
struct RefResult {
  std::vector<double> d_comp_rgb, partials;
};
RefResult run_ref(const Batch& b, double level_weight, size_t group_size, bool multiscale,
                  const ref::DataLossOptions& data = {}) {
  const size_t n = b.n_rays();
  const auto comp = to_double(b.comp_rgb), target = to_double(b.target_rgb), mult = to_double(b.lossmult);
  RefResult r;
  r.d_comp_rgb.resize(3 * n);
  r.partials.resize(2 * ((n + group_size - 1) / group_size));
  ref::loss_fwd_bwd(comp.data(), target.data(), multiscale ? mult.data() : nullptr, level_weight,
                    1.0 / b.lossmult_sum(), r.d_comp_rgb.data(), r.partials.data(), 0, 0, n, group_size, data);
  return r;
}

// The reference level loss w_l · Σ lossmult·Σ_c term / Σ lossmult, for finite differences.
double ref_level_loss(const std::vector<double>& comp, const std::vector<double>& target,
                      const std::vector<double>& mult, double level_weight, const ref::DataLossOptions& data = {}) {
  const size_t n = mult.size();
  double mult_sum = 0.0;
  for (double m : mult) mult_sum += m;
  std::vector<double> d_comp(3 * n), sums(2);
  ref::loss_fwd_bwd(comp.data(), target.data(), mult.data(), level_weight, 1.0 / mult_sum, d_comp.data(),
                    sums.data(), 0, 0, n, n, data);
  return level_weight * sums[ref::loss_sum_weighted] / mult_sum;
}

bool close(double actual, double expected, double relative, double absolute = 0.0) {
  return std::abs(actual - expected) <= relative * std::abs(expected) + absolute;
}

}  // namespace

TEST_CASE("loss stage: the device matches the double reference on 12,345 random rays, with and without lossmult") {
  auto& ctx = test::test_context();
  for (bool multiscale : {false, true}) {
    CAPTURE(multiscale);
    ops::Loss loss(ctx, ops::LossOptions{multiscale});
    const Batch b = random_batch(12345, multiscale, multiscale ? 11 : 12);  // not a multiple of the group size
    for (float weight : {0.1f, 1.0f}) {
      CAPTURE(weight);
      const auto device = run_device(loss, b, weight);
      const auto expected = run_ref(b, weight, loss.group_size(), multiscale);
      REQUIRE(device.n_groups == expected.partials.size() / 2);
      // Gradient 2·w·(1/Σm)·m·(c − t): float rounds the difference, 1/Σm, the weight and three products,
      // each ≤ 1 unit (u = 2^-24) relative: ≤ 6u ≈ 3.6e-7, so 1e-6 relative.
      for (size_t i = 0; i < device.d_comp_rgb.size(); ++i) {
        REQUIRE(std::isfinite(device.d_comp_rgb[i]));
        REQUIRE(close(device.d_comp_rgb[i], expected.d_comp_rgb[i], 1e-6));
      }
      // Group sums of non-negative terms: each term carries ≤ 5u (difference, squares, channel adds,
      // multiplier) and the 6..7-level tree adds ≤ 7u more: ≤ 12u ≈ 7.2e-7, so 2e-6 relative.
      for (size_t k = 0; k < device.partials.size(); ++k) {
        REQUIRE(std::isfinite(device.partials[k]));
        REQUIRE(close(device.partials[k], expected.partials[k], 2e-6));
      }
      // The level's loss and MSE summed on the host in double: the same bound holds for the total.
      const auto level = ops::sum_loss_partials(device.partials, device.n_groups, b.lossmult_sum(), b.n_rays());
      double weighted = 0.0, plain = 0.0;
      for (size_t g = 0; g < device.n_groups; ++g) {
        weighted += expected.partials[2 * g];
        plain += expected.partials[2 * g + 1];
      }
      CHECK(close(level.loss(), weighted / b.lossmult_sum(), 2e-6));
      CHECK(close(level.mse(), plain / (3.0 * b.n_rays()), 2e-6));
      CHECK(level.finite());
    }
  }
}

TEST_CASE("loss stage: the gradient equals central finite differences of the reference two-level total") {
  // total = λ·loss_coarse + loss_fine, each level with its own colours, the same targets and lossmult.
  const size_t n = 300;
  const Batch coarse = random_batch(n, true, 21), fine = random_batch(n, true, 22);
  const auto target = to_double(coarse.target_rgb), mult = to_double(coarse.lossmult);
  std::vector<std::vector<double>> comp = {to_double(coarse.comp_rgb), to_double(fine.comp_rgb)};
  const double lambda = 0.1, mult_sum = coarse.lossmult_sum();
  auto total = [&] {
    return ref_level_loss(comp[0], target, mult, lambda) + ref_level_loss(comp[1], target, mult, 1.0);
  };
  std::mt19937 rng(23);
  std::uniform_int_distribution<size_t> pick(0, 3 * n - 1);
  for (size_t level = 0; level < 2; ++level) {
    const double weight = ops::loss_level_weight(level, 2, static_cast<float>(lambda));
    std::vector<double> d_comp(3 * n), partials(2);
    ref::loss_fwd_bwd(comp[level].data(), target.data(), mult.data(), weight, 1.0 / mult_sum, d_comp.data(),
                      partials.data(), 0, 0, n, n);
    for (int trial = 0; trial < 100; ++trial) {
      const size_t k = pick(rng);
      const double h = 1e-4, saved = comp[level][k];
      comp[level][k] = saved + h;
      const double up = total();
      comp[level][k] = saved - h;
      const double down = total();
      comp[level][k] = saved;
      const double fd = (up - down) / (2 * h);
      // The loss is quadratic in comp, so the central difference has no truncation error; what remains is
      // the rounding of two totals of order 1 (≈ 1e-16) divided by 2h: ≈ 1e-12. Gradients are ≈ 1e-3.
      CAPTURE(level);
      CAPTURE(k);
      CHECK(close(fd, d_comp[k], 1e-8, 1e-11));
    }
  }
  // λ enters as the level weight: the coarse gradient is 0.1× what the same colours give on the fine level.
  std::vector<double> as_coarse(3 * n), as_fine(3 * n), sums(2);
  ref::loss_fwd_bwd(comp[0].data(), target.data(), mult.data(), 0.1, 1.0 / mult_sum, as_coarse.data(), sums.data(),
                    0, 0, n, n);
  ref::loss_fwd_bwd(comp[0].data(), target.data(), mult.data(), 1.0, 1.0 / mult_sum, as_fine.data(), sums.data(),
                    0, 0, n, n);
  for (size_t i = 0; i < 3 * n; ++i) CHECK(close(as_coarse[i], 0.1 * as_fine[i], 1e-15));
}

TEST_CASE("loss stage: Charbonnier's term and the per-channel mean (mip-NeRF 360, Zip-NeRF) match the reference") {
  auto& ctx = test::test_context();
  for (bool multiscale : {false, true}) {
    for (float padding : {0.0f, 0.001f, 0.1f}) {
      CAPTURE(multiscale);
      CAPTURE(padding);
      ops::Loss loss(ctx, ops::LossOptions{multiscale, padding, true});
      Batch b = random_batch(5001, multiscale, multiscale ? 13 : 14);
      // Residuals of every scale against the padding: exact (0), far below it, about it.
      const float offsets[] = {0.0f, 1e-6f, 3e-4f, 1e-3f, 2e-3f};
      for (size_t r = 0; r < 300; ++r) {
        for (size_t c = 0; c < 3; ++c) b.comp_rgb[3 * r + c] = b.target_rgb[3 * r + c] + offsets[(r + c) % 5];
      }
      const auto device = run_device(loss, b, 0.1f);
      const auto expected = run_ref(b, 0.1, loss.group_size(), multiscale, {padding, true});
      // Gradient w·(1/Σm)·m·(1/3)·r/√(r² + p²): the difference, the square, the padding's add, the square root
      // (≤ 3 ulp in OpenCL C), the division (≤ 2.5 ulp) and four products: ≤ 10 units of 2^-24, so 2e-6; the squared
      // error's 2r as in the test above. An exact colour's gradient is 0 in both.
      for (size_t i = 0; i < device.d_comp_rgb.size(); ++i) {
        REQUIRE(std::isfinite(device.d_comp_rgb[i]));
        REQUIRE(close(device.d_comp_rgb[i], expected.d_comp_rgb[i], 2e-6));
      }
      // Group sums of positive terms, each within ~10 units, the channel and tree sums ≤ 9 more: 3e-6.
      for (size_t k = 0; k < device.partials.size(); ++k) {
        REQUIRE(close(device.partials[k], expected.partials[k], 3e-6));
      }
      // The squared error's sum (the MSE and PSNR a person reads) is the same whatever the data term.
      const auto level = ops::sum_loss_partials(device.partials, device.n_groups, b.lossmult_sum(), b.n_rays());
      const auto summed = run_ref(b, 0.1, loss.group_size(), multiscale);
      double plain_sse = 0.0, summed_loss = 0.0;
      for (size_t g = 0; g < device.n_groups; ++g) {
        plain_sse += summed.partials[2 * g + 1];
        summed_loss += summed.partials[2 * g];
      }
      CHECK(close(level.mse(), plain_sse / (3.0 * b.n_rays()), 2e-6));
      // With the squared error, the channel mean is a third of google/mipnerf's channel sum.
      if (padding == 0.0f) CHECK(close(level.loss(), summed_loss / b.lossmult_sum() / 3.0, 3e-6));
    }
  }
  CHECK_THROWS_WITH_AS(ops::Loss(ctx, ops::LossOptions{false, -1e-3f, true}), doctest::Contains("charbonnier_padding"),
                       Error);
}

TEST_CASE("loss stage: the Charbonnier gradient equals central finite differences of the reference") {
  // The square root is not quadratic: the central difference's truncation h²/6·|f'''| is at most h²/p² relative for
  // p = 1e-3, 1e-8 at h = 1e-7. The rounding of two totals of about 0.3 (a mean of Charbonnier terms) over 2h is about
  // 5e-10, against gradients m/(3·Σm)·r/√(r² + p²) of 5e-4 and more over 30 rays (a larger batch divides them and
  // leaves the rounding): 1e-6 relative and 1e-9 absolute. A third of the rays have residuals about the padding.
  const size_t n = 30;
  Batch b = random_batch(n, true, 24);
  for (size_t r = 0; r < 10; ++r) b.comp_rgb[3 * r] = b.target_rgb[3 * r] + 1e-3f * static_cast<float>(r % 7) - 3e-3f;
  const auto target = to_double(b.target_rgb), mult = to_double(b.lossmult);
  std::vector<double> comp = to_double(b.comp_rgb);
  for (const ref::DataLossOptions data : {ref::DataLossOptions{1e-3, true}, ref::DataLossOptions{1e-3, false}}) {
    CAPTURE(data.channel_mean);
    std::vector<double> d_comp(3 * n), partials(2);
    ref::loss_fwd_bwd(comp.data(), target.data(), mult.data(), 1.0, 1.0 / b.lossmult_sum(), d_comp.data(),
                      partials.data(), 0, 0, n, n, data);
    for (size_t k = 0; k < 3 * n; ++k) {
      const double h = 1e-7, saved = comp[k];
      comp[k] = saved + h;
      const double up = ref_level_loss(comp, target, mult, 1.0, data);
      comp[k] = saved - h;
      const double down = ref_level_loss(comp, target, mult, 1.0, data);
      comp[k] = saved;
      CAPTURE(k);
      CHECK(close((up - down) / (2 * h), d_comp[k], 1e-6, 1e-9));
    }
  }
}

TEST_CASE("loss stage: chunked equals unchunked") {
  auto& ctx = test::test_context();
  ops::Loss loss(ctx, ops::LossOptions{true});
  const Batch b = random_batch(10000, true, 31);
  const auto whole = run_device(loss, b, 0.1f);
  const auto whole_level = ops::sum_loss_partials(whole.partials, whole.n_groups, b.lossmult_sum(), b.n_rays());

  // Chunks that are multiples of the group size cover the same groups: partials identical bit for bit.
  const auto aligned = run_device(loss, b, 0.1f, 16 * loss.group_size());
  CHECK(aligned.n_groups == whole.n_groups);
  CHECK(aligned.partials == whole.partials);
  CHECK(aligned.d_comp_rgb == whole.d_comp_rgb);

  // Chunks of 1,000 rays split groups differently: the gradient is per ray, so still identical; the sums
  // differ only by float rounding (each ≤ 12u relative as in the reference test, so 2e-6).
  const auto unaligned = run_device(loss, b, 0.1f, 1000);
  CHECK(unaligned.d_comp_rgb == whole.d_comp_rgb);
  const auto level = ops::sum_loss_partials(unaligned.partials, unaligned.n_groups, b.lossmult_sum(), b.n_rays());
  CHECK(close(level.loss(), whole_level.loss(), 2e-6));
  CHECK(close(level.mse(), whole_level.mse(), 2e-6));
  CHECK(level.loss() != 0.0);
}

TEST_CASE("loss stage: lossmult weights each ray, normalised by the batch sum, and is not read without multiscale") {
  auto& ctx = test::test_context();
  ops::Loss multiscale(ctx, ops::LossOptions{true});
  ops::Loss plain(ctx, ops::LossOptions{false});
  Batch b = random_batch(2000, true, 41);
  for (size_t r = 0; r < 100; ++r) b.lossmult[r] = 0.0f;  // rays that must not count at all

  // A ray with weight k counts as k copies of it: duplicate each ray lossmult times, all weights 1.
  Batch expanded;
  for (size_t r = 0; r < b.n_rays(); ++r) {
    for (int copy = 0; copy < static_cast<int>(b.lossmult[r]); ++copy) {
      for (int c = 0; c < 3; ++c) {
        expanded.comp_rgb.push_back(b.comp_rgb[3 * r + c]);
        expanded.target_rgb.push_back(b.target_rgb[3 * r + c]);
      }
      expanded.lossmult.push_back(1.0f);
    }
  }
  REQUIRE(expanded.lossmult_sum() == b.lossmult_sum());
  const auto weighted = run_device(multiscale, b, 1.0f);
  const auto copies = run_device(plain, expanded, 1.0f);
  const auto weighted_level =
      ops::sum_loss_partials(weighted.partials, weighted.n_groups, b.lossmult_sum(), b.n_rays());
  const auto copies_level =
      ops::sum_loss_partials(copies.partials, copies.n_groups, expanded.lossmult_sum(), expanded.n_rays());
  // Same value, different float summation orders: 2e-6 relative as above.
  CHECK(close(weighted_level.loss(), copies_level.loss(), 2e-6));
  // The gradient of one weighted ray is the sum over its copies' gradients (k identical values).
  size_t copy_index = 0;
  for (size_t r = 0; r < b.n_rays(); ++r) {
    const int k = static_cast<int>(b.lossmult[r]);
    for (int c = 0; c < 3; ++c) {
      const float g = weighted.d_comp_rgb[3 * r + c];
      if (k == 0) {
        REQUIRE(g == 0.0f);
      } else {
        REQUIRE(close(g, k * static_cast<double>(copies.d_comp_rgb[3 * copy_index + c]), 1e-6));
      }
    }
    copy_index += k;
  }
  // The unweighted MSE counts every ray, zero-weight ones too.
  const auto ref = run_ref(b, 1.0, multiscale.group_size(), true);
  double plain_sse = 0.0;
  for (size_t g = 0; g < ref.partials.size() / 2; ++g) plain_sse += ref.partials[2 * g + 1];
  CHECK(close(weighted_level.mse(), plain_sse / (3.0 * b.n_rays()), 2e-6));

  // Without multiscale the lossmult buffer is never read: NaN weights change nothing against all ones.
  Batch nan_mult = b;
  for (auto& m : nan_mult.lossmult) m = std::numeric_limits<float>::quiet_NaN();
  Batch ones = b;
  for (auto& m : ones.lossmult) m = 1.0f;
  auto comp = upload(ctx, b.comp_rgb, "comp_rgb"), target = upload(ctx, b.target_rgb, "target_rgb");
  auto garbage = upload(ctx, nan_mult.lossmult, "lossmult (NaN)");
  ocl::DeviceArray<float> d_comp(ctx, 3 * b.n_rays(), "d_comp_rgb"), partials(ctx, 2 * plain.groups_for(2000), "p");
  plain.fwd_bwd(comp, target, &garbage, {1.0f, double(b.n_rays())}, d_comp, partials, {b.n_rays(), 0, 0});
  const auto with_ones = run_device(plain, ones, 1.0f);
  CHECK(d_comp.download(ctx) == with_ones.d_comp_rgb);
  CHECK(partials.download(ctx) == with_ones.partials);
}

TEST_CASE("loss stage: the official normalisation is 3x the per-channel MSE, reported separately as MSE and PSNR") {
  auto& ctx = test::test_context();
  ops::Loss loss(ctx, ops::LossOptions{false});
  // Every channel of every ray off by exactly 0.125 (exact in float, and so is its square): per-channel
  // MSE 1/64, official per-level loss 3/64, PSNR −10·log10(1/64).
  Batch b = random_batch(1000, false, 51);
  for (size_t i = 0; i < b.comp_rgb.size(); ++i) {
    b.target_rgb[i] = std::round(b.comp_rgb[i] * 8.0f) / 8.0f;
    b.comp_rgb[i] = b.target_rgb[i] + 0.125f;
  }
  const auto device = run_device(loss, b, 1.0f);
  const auto level = ops::sum_loss_partials(device.partials, device.n_groups, b.lossmult_sum(), b.n_rays());
  CHECK(level.loss() == 3.0 / 64.0);  // sums of exact dyadic values below 2^24 units: exact
  CHECK(level.mse() == 1.0 / 64.0);
  CHECK(level.psnr() == doctest::Approx(10.0 * std::log10(64.0)).epsilon(1e-14));
  // Gradient: 2·(0.125)/1000 per channel, in float (1/1000 is rounded once: 1e-6 relative).
  for (float g : device.d_comp_rgb) REQUIRE(close(g, 2.0 * 0.125 / 1000.0, 1e-6));
  // total = λ·coarse + fine; a third level would also get λ (every level but the last).
  ops::LevelLoss fine = level;
  fine.weighted_sse = level.weighted_sse / 4;
  CHECK(ops::total_loss({level, fine}, 0.1f) == doctest::Approx(0.1 * 3.0 / 64.0 + 3.0 / 256.0).epsilon(1e-7));
  CHECK(ops::loss_level_weight(0, 3) == 0.1f);
  CHECK(ops::loss_level_weight(1, 3) == 0.1f);
  CHECK(ops::loss_level_weight(2, 3) == 1.0f);
}

TEST_CASE("loss stage: the device reduction of the partials matches the double sum") {
  auto& ctx = test::test_context();
  ops::Loss loss(ctx, ops::LossOptions{true});
  const Batch b = random_batch(50000, true, 61);
  const auto device = run_device(loss, b, 1.0f);
  auto partials = upload(ctx, device.partials, "partials [groups][2]");
  ocl::DeviceArray<float> sums(ctx, 4, "loss sums [levels][2]");
  sums.fill(ctx, -1.0f);
  loss.reduce(partials, device.n_groups, sums, 1);
  const auto got = sums.download(ctx);
  std::vector<double> expected(4, -1.0);
  const auto partials_double = to_double(device.partials);
  ref::loss_reduce(partials_double.data(), device.n_groups, expected.data(), 1);
  CHECK(got[0] == -1.0f);  // slot 0 untouched
  CHECK(got[1] == -1.0f);
  // Compensated summation: error ≤ 2u + O(n·u²) relative for non-negative terms, so 2e-7.
  CHECK(close(got[2], expected[2], 2e-7));
  CHECK(close(got[3], expected[3], 2e-7));

  // A sum naive float addition gets wrong: one large group then 100,000 tiny ones, each below half an ulp
  // of the running sum (naive: stays 1e4, 0.1 % low). The compensated sum keeps them.
  std::vector<float> skewed(2 * 100001, 1e-4f);
  skewed[0] = skewed[1] = 1e4f;
  auto skewed_device = upload(ctx, skewed, "skewed partials [groups][2]");
  loss.reduce(skewed_device, 100001, sums, 0);
  const auto skewed_sums = sums.download(ctx);
  const double exact = 1e4 + 100000.0 * static_cast<double>(1e-4f);
  CHECK(close(skewed_sums[0], exact, 2e-7));
  CHECK(close(skewed_sums[1], exact, 2e-7));
}

TEST_CASE("loss stage: a NaN or Inf colour makes the loss non-finite for the host to detect, other rays unaffected") {
  auto& ctx = test::test_context();
  ops::Loss loss(ctx, ops::LossOptions{true});
  const Batch clean = random_batch(3000, true, 71);
  const auto clean_run = run_device(loss, clean, 1.0f);
  const float bad_values[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()};
  for (float bad : bad_values) {
    for (bool in_target : {false, true}) {
      CAPTURE(bad);
      CAPTURE(in_target);
      Batch b = clean;
      const size_t bad_ray = 1234;
      (in_target ? b.target_rgb : b.comp_rgb)[3 * bad_ray + 1] = bad;
      const auto run = run_device(loss, b, 1.0f);
      const auto level = ops::sum_loss_partials(run.partials, run.n_groups, b.lossmult_sum(), b.n_rays());
      CHECK_FALSE(level.finite());
      CHECK_FALSE(std::isfinite(level.loss()));
      CHECK_FALSE(std::isfinite(ops::total_loss({level, level})));
      CHECK_FALSE(std::isfinite(run.d_comp_rgb[3 * bad_ray + 1]));
      // Only the bad ray's group is affected; every other ray's gradient is as without the bad value.
      for (size_t i = 0; i < run.d_comp_rgb.size(); ++i) {
        if (i / 3 != bad_ray) REQUIRE(run.d_comp_rgb[i] == clean_run.d_comp_rgb[i]);
      }
      const size_t bad_group = bad_ray / loss.group_size();
      for (size_t g = 0; g < run.n_groups; ++g) {
        if (g != bad_group) REQUIRE(run.partials[2 * g] == clean_run.partials[2 * g]);
      }
      // The device reduction propagates it too.
      auto partials = upload(ctx, run.partials, "partials");
      ocl::DeviceArray<float> sums(ctx, 2, "sums");
      loss.reduce(partials, run.n_groups, sums, 0);
      const auto s = sums.download(ctx);
      CHECK_FALSE(std::isfinite(s[0]));
      CHECK_FALSE(std::isfinite(s[1]));
    }
  }
}

TEST_CASE("loss stage: bad arguments give errors that say what is wrong") {
  auto& ctx = test::test_context();
  ops::Loss multiscale(ctx, ops::LossOptions{true});
  ocl::DeviceArray<float> comp(ctx, 30, "comp_rgb"), target(ctx, 30, "target_rgb"), d_comp(ctx, 30, "d_comp_rgb");
  ocl::DeviceArray<float> partials(ctx, 2, "partials"), mult(ctx, 10, "lossmult");
  CHECK_THROWS_WITH_AS(multiscale.fwd_bwd(comp, target, nullptr, {1.0f, 10.0}, d_comp, partials, {10, 0, 0}),
                       doctest::Contains("no lossmult buffer"), Error);
  CHECK_THROWS_WITH_AS(multiscale.fwd_bwd(comp, target, &mult, {1.0f, 0.0}, d_comp, partials, {10, 0, 0}),
                       doctest::Contains("sum of loss multipliers"), Error);
  CHECK_THROWS_WITH_AS(multiscale.fwd_bwd(comp, target, &mult, {1.0f, 10.0}, d_comp, partials, {10, 5, 0}),
                       doctest::Contains("target_rgb"), Error);
  CHECK_THROWS_WITH_AS(multiscale.fwd_bwd(comp, target, &mult, {1.0f, 10.0}, d_comp, partials, {10, 0, 1}),
                       doctest::Contains("partials"), Error);
}
