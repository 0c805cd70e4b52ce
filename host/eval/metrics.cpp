// PSNR and SSIM as the paper's code computes them (google/mipnerf internal/math.py), in double.
#include "eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.hpp"

namespace mipnerf::eval {
namespace {

std::string shape(const ImageView& image) {
  return std::to_string(image.height) + "x" + std::to_string(image.width) + "x" + std::to_string(image.channels);
}

void require_same_shape(const ImageView& a, const ImageView& b, const char* metric) {
  if (a.height != b.height || a.width != b.width || a.channels != b.channels) {
    throw Error(std::string(metric) + ": the images differ in shape (" + shape(a) + " vs " + shape(b) +
                ", height x width x channels)");
  }
  if (a.count() == 0) throw Error(std::string(metric) + ": the images are empty (" + shape(a) + ")");
  if (!a.pixels || !b.pixels) throw Error(std::string(metric) + ": an image has no pixel data");
}

// One channel's plane, filtered with the window along x, then along y, keeping only windows wholly
// inside the plane ('valid'): [height − k + 1][width − k + 1].
std::vector<double> blur_valid(const std::vector<double>& plane, size_t height, size_t width,
                               const std::vector<double>& window) {
  const size_t k = window.size(), out_w = width - k + 1, out_h = height - k + 1;
  std::vector<double> along_x(height * out_w);
  for (size_t y = 0; y < height; ++y) {
    for (size_t x = 0; x < out_w; ++x) {
      double sum = 0.0;
      for (size_t i = 0; i < k; ++i) sum += window[i] * plane[y * width + x + i];
      along_x[y * out_w + x] = sum;
    }
  }
  std::vector<double> out(out_h * out_w);
  for (size_t y = 0; y < out_h; ++y) {
    for (size_t x = 0; x < out_w; ++x) {
      double sum = 0.0;
      for (size_t i = 0; i < k; ++i) sum += window[i] * along_x[(y + i) * out_w + x];
      out[y * out_w + x] = sum;
    }
  }
  return out;
}

// f(a, b) of channel `c` of the pair, pixel by pixel, as a double plane [height][width].
template <typename F>
std::vector<double> plane_of(const ImageView& a, const ImageView& b, size_t c, F f) {
  std::vector<double> plane(a.height * a.width);
  for (size_t p = 0; p < plane.size(); ++p) {
    plane[p] = f(static_cast<double>(a.pixels[p * a.channels + c]), static_cast<double>(b.pixels[p * b.channels + c]));
  }
  return plane;
}

double clamp_nonnegative(double x) { return x < 0.0 ? 0.0 : x; }

}  // namespace

double mse(const ImageView& a, const ImageView& b) {
  require_same_shape(a, b, "MSE");
  double sum = 0.0;
  for (size_t i = 0; i < a.count(); ++i) {
    const double d = static_cast<double>(a.pixels[i]) - static_cast<double>(b.pixels[i]);
    sum += d * d;
  }
  return sum / static_cast<double>(a.count());
}

double psnr_from_mse(double mse) {
  if (mse == 0.0) return std::numeric_limits<double>::infinity();
  return -10.0 * std::log10(mse);
}

double psnr(const ImageView& a, const ImageView& b) { return psnr_from_mse(mse(a, b)); }

std::vector<double> ssim_window(const SsimOptions& options) {
  if (options.filter_size == 0 || !(options.filter_sigma > 0.0)) {
    throw Error("SSIM: the window needs a size >= 1 and sigma > 0 (got " + std::to_string(options.filter_size) +
                ", " + std::to_string(options.filter_sigma) + ")");
  }
  const size_t size = options.filter_size;
  const double half = static_cast<double>(size / 2);
  // Even sizes shift by half a pixel so the taps stay symmetric about the window's centre.
  const double shift = (size % 2 == 0) ? 0.5 : 0.0;
  std::vector<double> window(size);
  double total = 0.0;
  for (size_t i = 0; i < size; ++i) {
    const double u = (static_cast<double>(i) - half + shift) / options.filter_sigma;
    window[i] = std::exp(-0.5 * u * u);
    total += window[i];
  }
  for (double& w : window) w /= total;
  return window;
}

double ssim_from_moments(double mu_a, double mu_b, double e_aa, double e_bb, double e_ab, double c1, double c2) {
  const double mu_aa = mu_a * mu_a, mu_bb = mu_b * mu_b, mu_ab = mu_a * mu_b;
  // E[x²] − μ² can come out slightly negative (or |σ_ab| slightly above √(σ_aa·σ_bb)) by rounding; the
  // official code clamps both back to what a variance and a covariance can be. The clamps are written so
  // a NaN passes through them, as jnp.maximum and jnp.sign let it.
  const double var_a = clamp_nonnegative(e_aa - mu_aa);
  const double var_b = clamp_nonnegative(e_bb - mu_bb);
  const double raw_cov = e_ab - mu_ab;
  const double cov_limit = std::sqrt(var_a * var_b);
  const double cov = std::abs(raw_cov) > cov_limit ? std::copysign(cov_limit, raw_cov) : raw_cov;
  return (2.0 * mu_ab + c1) * (2.0 * cov + c2) / ((mu_aa + mu_bb + c1) * (var_a + var_b + c2));
}

std::vector<double> ssim_map(const ImageView& a, const ImageView& b, const SsimOptions& options) {
  require_same_shape(a, b, "SSIM");
  const auto window = ssim_window(options);
  const size_t k = window.size();
  if (a.height < k || a.width < k) {
    throw Error("SSIM: the images (" + shape(a) + ") are smaller than the " + std::to_string(k) + "x" +
                std::to_string(k) + " window; SSIM is undefined below that size");
  }
  const double c1 = (options.k1 * options.max_value) * (options.k1 * options.max_value);
  const double c2 = (options.k2 * options.max_value) * (options.k2 * options.max_value);
  const size_t out_h = a.height - k + 1, out_w = a.width - k + 1, channels = a.channels;
  std::vector<double> map(out_h * out_w * channels);

  for (size_t c = 0; c < channels; ++c) {
    auto blur = [&](auto f) { return blur_valid(plane_of(a, b, c, f), a.height, a.width, window); };
    const auto mu_a = blur([](double x, double) { return x; });
    const auto mu_b = blur([](double, double y) { return y; });
    const auto e_aa = blur([](double x, double) { return x * x; });
    const auto e_bb = blur([](double, double y) { return y * y; });
    const auto e_ab = blur([](double x, double y) { return x * y; });
    for (size_t p = 0; p < out_h * out_w; ++p) {
      map[p * channels + c] = ssim_from_moments(mu_a[p], mu_b[p], e_aa[p], e_bb[p], e_ab[p], c1, c2);
    }
  }
  return map;
}

double ssim(const ImageView& a, const ImageView& b, const SsimOptions& options) {
  const auto map = ssim_map(a, b, options);
  double sum = 0.0;
  for (double v : map) sum += v;
  return sum / static_cast<double>(map.size());
}

}  // namespace mipnerf::eval
