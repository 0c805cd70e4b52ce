// Image quality metrics as the paper's evaluation computes them (google/mipnerf internal/math.py):
// PSNR from the MSE over all pixels and channels, and SSIM with an 11×11 Gaussian window. In double.
#pragma once

#include <cstddef>
#include <vector>

namespace mipnerf::eval {

// A read-only image: pixels [height][width][channels], row-major, float32 (rendered or loaded values,
// nominally in [0, 1]; the metrics assume a maximum value of 1 unless SsimOptions says otherwise).
struct ImageView {
  const float* pixels = nullptr;
  size_t height = 0;
  size_t width = 0;
  size_t channels = 0;
  size_t count() const { return height * width * channels; }
};

// Mean of (a − b)² over every pixel and channel. Throws mipnerf::Error when the shapes differ or are empty.
double mse(const ImageView& a, const ImageView& b);

// PSNR for values in [0, 1]: −10·log10(mse) (official mse_to_psnr). mse = 0 gives +inf; NaN stays NaN.
double psnr_from_mse(double mse);
// PSNR of one image against another: psnr_from_mse(mse(a, b)). Per image; a split's PSNR is the mean of
// its images' PSNRs, not the PSNR of the pooled MSE (as the official eval averages them).
double psnr(const ImageView& a, const ImageView& b);

// The official SSIM's parameters (compute_ssim defaults as train.py and eval.py call it).
struct SsimOptions {
  size_t filter_size = 11;  // window width and height in pixels
  double filter_sigma = 1.5;
  double k1 = 0.01;
  double k2 = 0.03;
  double max_value = 1.0;  // data range: c1 = (k1·max)², c2 = (k2·max)²
};

// The normalised 1-D Gaussian window: w_i ∝ exp(−½((i − hw + shift)/σ)²), hw = size/2, shift = ½ for
// even sizes, 0 for odd ones (so the window is symmetric), Σ w_i = 1.
std::vector<double> ssim_window(const SsimOptions& options = {});

// SSIM of one window from its windowed moments μ_a, μ_b, E[a²], E[b²], E[ab], with the official clamps:
// σ_aa, σ_bb = max(0, E[x²] − μ²); σ_ab = sign(σ_ab)·min(√(σ_aa·σ_bb), |σ_ab|) (rounding can push a
// variance below zero or a covariance past Cauchy–Schwarz); c1 = (k1·max)², c2 = (k2·max)².
double ssim_from_moments(double mu_a, double mu_b, double e_aa, double e_bb, double e_ab, double c1, double c2);

// Per-pixel SSIM map of one image pair: [height − size + 1][width − size + 1][channels]. Each channel
// is filtered separably with 'valid' boundaries (no padding: only windows wholly inside the image), then
//   μ_a, μ_b, σ_aa = E[a²] − μ_a², σ_bb = E[b²] − μ_b², σ_ab = E[ab] − μ_a·μ_b  (windowed expectations)
//   ssim = (2μ_aμ_b + c1)(2σ_ab + c2) / ((μ_a² + μ_b² + c1)(σ_aa + σ_bb + c2))  (ssim_from_moments)
// Throws mipnerf::Error when the shapes differ or the image is smaller than the window.
std::vector<double> ssim_map(const ImageView& a, const ImageView& b, const SsimOptions& options = {});

// SSIM of one image pair: the mean of ssim_map over pixels and channels (official compute_ssim).
double ssim(const ImageView& a, const ImageView& b, const SsimOptions& options = {});

}  // namespace mipnerf::eval
