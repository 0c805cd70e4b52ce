// PSNR and SSIM (host/eval/metrics) against hand-computed cases and a direct, non-separable SSIM.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/error.hpp"
#include "eval/metrics.hpp"

using namespace mipnerf;

namespace {

// An image that owns its pixels [height][width][channels].
struct TestImage {
  size_t height, width, channels;
  std::vector<float> pixels;
  TestImage(size_t h, size_t w, size_t c, float value = 0.0f) : height(h), width(w), channels(c), pixels(h * w * c, value) {}
  float& at(size_t y, size_t x, size_t c) { return pixels[(y * width + x) * channels + c]; }
  float at(size_t y, size_t x, size_t c) const { return pixels[(y * width + x) * channels + c]; }
  eval::ImageView view() const { return {pixels.data(), height, width, channels}; }
};

TestImage random_image(size_t h, size_t w, size_t c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  TestImage image(h, w, c);
  for (auto& v : image.pixels) v = value(rng);
  return image;
}

// `image` plus Gaussian noise of standard deviation sigma, clamped to [0, 1].
TestImage noisy(const TestImage& image, float sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, sigma);
  TestImage out = image;
  for (auto& v : out.pixels) v = std::clamp(v + noise(rng), 0.0f, 1.0f);
  return out;
}

const double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;

// The paper's SSIM written directly from its definition: a 2-D Gaussian window w(i, j) ∝ exp(−(i² + j²)/(2σ²))
// over the 11×11 neighbourhood (not separated), windowed moments, the same clamps, one value per window
// position wholly inside the image. An independent implementation of what metrics.cpp computes separably.
std::vector<double> direct_ssim_map(const TestImage& a, const TestImage& b, size_t size = 11, double sigma = 1.5) {
  const double centre = (static_cast<double>(size) - 1.0) / 2.0;
  std::vector<double> w(size * size);
  double total = 0.0;
  for (size_t i = 0; i < size; ++i) {
    for (size_t j = 0; j < size; ++j) {
      const double di = i - centre, dj = j - centre;
      w[i * size + j] = std::exp(-(di * di + dj * dj) / (2 * sigma * sigma));
      total += w[i * size + j];
    }
  }
  const size_t out_h = a.height - size + 1, out_w = a.width - size + 1;
  std::vector<double> map;
  for (size_t y = 0; y < out_h; ++y) {
    for (size_t x = 0; x < out_w; ++x) {
      for (size_t c = 0; c < a.channels; ++c) {
        double ma = 0, mb = 0, maa = 0, mbb = 0, mab = 0;
        for (size_t i = 0; i < size; ++i) {
          for (size_t j = 0; j < size; ++j) {
            const double weight = w[i * size + j] / total;
            const double va = a.at(y + i, x + j, c), vb = b.at(y + i, x + j, c);
            ma += weight * va;
            mb += weight * vb;
            maa += weight * va * va;
            mbb += weight * vb * vb;
            mab += weight * va * vb;
          }
        }
        const double var_a = std::max(0.0, maa - ma * ma), var_b = std::max(0.0, mbb - mb * mb);
        double cov = mab - ma * mb;
        cov = (cov > 0 ? 1.0 : cov < 0 ? -1.0 : 0.0) * std::min(std::sqrt(var_a * var_b), std::abs(cov));
        map.push_back((2 * ma * mb + kC1) * (2 * cov + kC2) / ((ma * ma + mb * mb + kC1) * (var_a + var_b + kC2)));
      }
    }
  }
  return map;
}

double mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

}  // namespace

TEST_CASE("metrics: PSNR is -10 log10 of the MSE over all pixels and channels") {
  // Values on a 1/256 grid, offset by exactly 1/16: every squared error is 1/256, exactly.
  TestImage a(20, 30, 3), b(20, 30, 3);
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> level(0, 200);
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    a.pixels[i] = level(rng) / 256.0f;
    b.pixels[i] = a.pixels[i] + 1.0f / 16.0f;
  }
  CHECK(eval::mse(a.view(), b.view()) == 1.0 / 256.0);
  CHECK(eval::psnr(a.view(), b.view()) == doctest::Approx(10.0 * std::log10(256.0)).epsilon(1e-14));
  // Only the green channel of half the pixels off by 1/2: MSE = (1/4)·(1/2)·(1/3) = 1/24.
  TestImage c = a;
  for (size_t p = 0; p < 20 * 30; p += 2) c.pixels[3 * p + 1] += 0.5f;
  CHECK(eval::mse(a.view(), c.view()) == doctest::Approx(1.0 / 24.0).epsilon(1e-15));
  CHECK(eval::psnr(a.view(), c.view()) == doctest::Approx(10.0 * std::log10(24.0)).epsilon(1e-14));
  CHECK(eval::psnr_from_mse(0.01) == doctest::Approx(20.0).epsilon(1e-15));
  CHECK(eval::psnr_from_mse(1.0) == 0.0);
  // Identical images: infinite PSNR, as −10·log10(0); a NaN pixel: NaN, never a number.
  CHECK(eval::psnr(a.view(), a.view()) == std::numeric_limits<double>::infinity());
  c.pixels[7] = std::numeric_limits<float>::quiet_NaN();
  CHECK(std::isnan(eval::psnr(a.view(), c.view())));
}

TEST_CASE("metrics: the SSIM window is the normalised 11-tap Gaussian of sigma 1.5") {
  const auto w = eval::ssim_window();
  REQUIRE(w.size() == 11);
  double norm = 0.0;
  for (int k = -5; k <= 5; ++k) norm += std::exp(-k * k / 4.5);
  for (int k = -5; k <= 5; ++k) CHECK(w[k + 5] == doctest::Approx(std::exp(-k * k / 4.5) / norm).epsilon(1e-15));
  // Even sizes shift by half a pixel: taps at ±0.5, ±1.5, ... symmetric, summing to 1.
  eval::SsimOptions even;
  even.filter_size = 8;
  even.filter_sigma = 1.0;
  const auto e = eval::ssim_window(even);
  double sum = 0.0;
  for (size_t i = 0; i < 8; ++i) {
    CHECK(e[i] == doctest::Approx(e[7 - i]).epsilon(1e-15));
    sum += e[i];
  }
  CHECK(sum == doctest::Approx(1.0).epsilon(1e-15));
  CHECK(e[3] / e[2] == doctest::Approx(std::exp(-0.5 * 0.25) / std::exp(-0.5 * 2.25)).epsilon(1e-14));
}

TEST_CASE("metrics: SSIM of identical images is 1, and SSIM is symmetric") {
  const TestImage a = random_image(32, 40, 3, 2);
  const TestImage b = noisy(a, 0.1f, 3);
  // Identical: numerator and denominator are the same products; only rounding separates them.
  CHECK(eval::ssim(a.view(), a.view()) == doctest::Approx(1.0).epsilon(1e-12));
  const auto ab = eval::ssim_map(a.view(), b.view());
  const auto ba = eval::ssim_map(b.view(), a.view());
  REQUIRE(ab.size() == 22 * 30 * 3);
  CHECK(ab == ba);  // every term of the formula is symmetric in (a, b), operation for operation
  // Noise lowers SSIM below 1, more noise lowers it further.
  const double s = eval::ssim(a.view(), b.view());
  CHECK(s < 0.99);
  CHECK(eval::ssim(a.view(), noisy(a, 0.3f, 3).view()) < s);
}

TEST_CASE("metrics: SSIM of two constant images matches the closed form, per channel") {
  // x = a, y = b everywhere: no variance, so SSIM = (2ab + c1)(c2) / ((a² + b² + c1)(c2)).
  const double values[][2] = {{0.5, 0.5}, {0.2, 0.7}, {0.0, 1.0}, {0.25, 0.0}, {0.9, 0.85}};
  for (const auto& pair : values) {
    const double va = pair[0], vb = pair[1];  // CAPTURE cannot capture a structured binding (C++17)
    TestImage a(16, 13, 1, static_cast<float>(va)), b(16, 13, 1, static_cast<float>(vb));
    const double fa = static_cast<float>(va), fb = static_cast<float>(vb);
    const double expected = (2 * fa * fb + kC1) / (fa * fa + fb * fb + kC1);
    CAPTURE(va);
    CAPTURE(vb);
    CHECK(eval::ssim(a.view(), b.view()) == doctest::Approx(expected).epsilon(1e-12));
  }
  // Three channels with different constants: the mean of the three closed forms.
  TestImage a(12, 12, 3), b(12, 12, 3);
  const float ca[3] = {0.1f, 0.5f, 0.75f}, cb[3] = {0.3f, 0.5f, 0.25f};
  double expected = 0.0;
  for (size_t c = 0; c < 3; ++c) {
    for (size_t y = 0; y < 12; ++y) {
      for (size_t x = 0; x < 12; ++x) a.at(y, x, c) = ca[c], b.at(y, x, c) = cb[c];
    }
    const double fa = ca[c], fb = cb[c];
    expected += (2 * fa * fb + kC1) / (fa * fa + fb * fb + kC1) / 3.0;
  }
  CHECK(eval::ssim_map(a.view(), b.view()).size() == 2 * 2 * 3);
  CHECK(eval::ssim(a.view(), b.view()) == doctest::Approx(expected).epsilon(1e-12));
}

TEST_CASE("metrics: SSIM of an image and a constant offset of it is 1 - d^2 / (mu^2 + (mu + d)^2 + c1)") {
  // y = x + d keeps every variance and covariance (σ_yy = σ_xy = σ_xx), so only the luminance term is
  // left: (2μ(μ + d) + c1) / (μ² + (μ + d)² + c1) = 1 − d² / (μ² + (μ + d)² + c1), μ the windowed mean of x.
  // Values on a 1/256 grid and d = 1/8, so y is exact in float.
  TestImage x(19, 23, 2), y(19, 23, 2);
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> level(20, 200);
  for (size_t i = 0; i < x.pixels.size(); ++i) {
    x.pixels[i] = level(rng) / 256.0f;
    y.pixels[i] = x.pixels[i] + 0.125f;
  }
  const auto map = eval::ssim_map(x.view(), y.view());
  REQUIRE(map.size() == 9 * 13 * 2);
  const double d = 0.125;
  const auto w = eval::ssim_window();
  for (size_t oy = 0; oy < 9; ++oy) {
    for (size_t ox = 0; ox < 13; ++ox) {
      for (size_t c = 0; c < 2; ++c) {
        double mu = 0.0;
        for (size_t i = 0; i < 11; ++i) {
          for (size_t j = 0; j < 11; ++j) mu += w[i] * w[j] * x.at(oy + i, ox + j, c);
        }
        const double expected = 1.0 - d * d / (mu * mu + (mu + d) * (mu + d) + kC1);
        // The variance terms cancel only up to rounding of windowed sums of order 0.1 (≈ 1e-16 each),
        // against c2 = 9e-4 in the denominator: well below 1e-11.
        REQUIRE(map[(oy * 13 + ox) * 2 + c] == doctest::Approx(expected).epsilon(1e-11));
      }
    }
  }
}

TEST_CASE("metrics: SSIM of an 11x11 image, one window, computed by hand") {
  // A single bright pixel in the centre: the window's centre tap is g0², g0 = 1 / Σ_k exp(−k²/4.5), so
  // for x = δ and y = s·δ the moments are μx = w, μy = s·w, σxx = w − w², σyy = s²(w − w²), σxy = s(w − w²).
  double norm = 0.0;
  for (int k = -5; k <= 5; ++k) norm += std::exp(-k * k / 4.5);
  const double w = 1.0 / (norm * norm);
  const double v = w - w * w;
  auto by_hand = [&](double s) {
    return (2 * s * w * w + kC1) * (2 * s * v + kC2) / ((w * w + s * s * w * w + kC1) * ((1 + s * s) * v + kC2));
  };
  const float scales[3] = {0.0f, 0.5f, -0.25f};  // channel 2 anti-correlated: both terms negative
  TestImage x(11, 11, 3), y(11, 11, 3);
  double expected = 0.0;
  for (size_t c = 0; c < 3; ++c) {
    x.at(5, 5, c) = 1.0f;
    y.at(5, 5, c) = scales[c];
    expected += by_hand(scales[c]) / 3.0;
  }
  const auto map = eval::ssim_map(x.view(), y.view());
  REQUIRE(map.size() == 3);
  for (size_t c = 0; c < 3; ++c) CHECK(map[c] == doctest::Approx(by_hand(scales[c])).epsilon(1e-12));
  CHECK(map[0] == doctest::Approx(kC1 * kC2 / ((w * w + kC1) * (v + kC2))).epsilon(1e-12));
  CHECK(eval::ssim(x.view(), y.view()) == doctest::Approx(expected).epsilon(1e-12));
}

TEST_CASE("metrics: SSIM of a noisy image equals a direct double loop over the 2-D window") {
  const TestImage a = random_image(27, 34, 3, 5);
  // A smooth image too (structure at the window's scale), so the clamps and large SSIMs are exercised.
  TestImage smooth(27, 34, 3);
  for (size_t y = 0; y < 27; ++y) {
    for (size_t x = 0; x < 34; ++x) {
      for (size_t c = 0; c < 3; ++c) smooth.at(y, x, c) = 0.5f + 0.4f * std::sin(0.3f * x + 0.2f * y + c);
    }
  }
  for (const TestImage* base : std::vector<const TestImage*>{&a, &smooth}) {
    const TestImage b = noisy(*base, 0.05f, 6);
    const auto map = eval::ssim_map(base->view(), b.view());
    const auto direct = direct_ssim_map(*base, b);
    REQUIRE(map.size() == direct.size());
    // Two summation orders of ~121 products of order 1 (≈ 1e-14 apart) against c2 = 9e-4: 1e-10.
    for (size_t i = 0; i < map.size(); ++i) REQUIRE(map[i] == doctest::Approx(direct[i]).epsilon(1e-10));
    CHECK(eval::ssim(base->view(), b.view()) == doctest::Approx(mean(direct)).epsilon(1e-12));
  }
}

TEST_CASE("metrics: SSIM clamps a negative variance to 0 and a covariance to the Cauchy-Schwarz bound") {
  auto formula = [](double mu_a, double mu_b, double var_a, double var_b, double cov) {
    return (2 * mu_a * mu_b + kC1) * (2 * cov + kC2) / ((mu_a * mu_a + mu_b * mu_b + kC1) * (var_a + var_b + kC2));
  };
  // Within bounds: the plain formula.
  double e_aa = 0.09 + 0.01, e_bb = 0.36 + 0.04, e_ab = 0.18 + 0.015;
  CHECK(eval::ssim_from_moments(0.3, 0.6, e_aa, e_bb, e_ab, kC1, kC2) ==
        doctest::Approx(formula(0.3, 0.6, e_aa - 0.09, e_bb - 0.36, e_ab - 0.18)).epsilon(1e-14));
  // |σ_ab| = 0.03 above √(0.01·0.04) = 0.02: clamped to −0.02, the sign kept.
  e_ab = 0.18 - 0.03;
  const double limit = std::sqrt((e_aa - 0.09) * (e_bb - 0.36));
  CHECK(limit == doctest::Approx(0.02).epsilon(1e-12));
  CHECK(eval::ssim_from_moments(0.3, 0.6, e_aa, e_bb, e_ab, kC1, kC2) ==
        doctest::Approx(formula(0.3, 0.6, e_aa - 0.09, e_bb - 0.36, -limit)).epsilon(1e-14));
  // σ_aa = −0.001 (impossible, from rounding): read as 0, which also forces σ_ab to 0.
  e_aa = 0.25 - 0.001;
  e_bb = 0.25 + 0.01;
  e_ab = 0.25 + 0.004;
  CHECK(eval::ssim_from_moments(0.5, 0.5, e_aa, e_bb, e_ab, kC1, kC2) ==
        doctest::Approx(formula(0.5, 0.5, 0.0, e_bb - 0.25, 0.0)).epsilon(1e-14));
  CHECK(std::isnan(eval::ssim_from_moments(0.5, std::nan(""), 0.3, 0.3, 0.3, kC1, kC2)));
}

TEST_CASE("metrics: bad inputs give errors, NaN stays NaN") {
  const TestImage a = random_image(12, 12, 3, 7), small = random_image(10, 12, 3, 8), grey = random_image(12, 12, 1, 9);
  CHECK_THROWS_WITH_AS(eval::ssim(small.view(), small.view()), doctest::Contains("smaller than the 11x11 window"),
                       Error);
  CHECK_THROWS_WITH_AS(eval::ssim(a.view(), grey.view()), doctest::Contains("differ in shape"), Error);
  CHECK_THROWS_WITH_AS(eval::psnr(a.view(), grey.view()), doctest::Contains("differ in shape"), Error);
  TestImage bad = a;
  bad.at(6, 6, 1) = std::numeric_limits<float>::quiet_NaN();
  CHECK(std::isnan(eval::ssim(a.view(), bad.view())));
}
