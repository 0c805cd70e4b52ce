// The IEC 61966-2-1 (sRGB) transfer curve.
#include "io/color.hpp"

#include <cmath>

namespace mipnerf::io {

// The standard's constants. Its two thresholds do not meet exactly (12.92 · 0.0031308 = 0.04044994 vs
// 0.04045); the gap is below 1e-7, far under 8-bit or float16 resolution, and we keep the standard's values.
namespace {
constexpr double kLinearThreshold = 0.0031308;
constexpr double kEncodedThreshold = 0.04045;
constexpr double kSlope = 12.92;
constexpr double kOffset = 0.055;
constexpr double kGamma = 2.4;
}  // namespace

double srgb_to_linear(double encoded) {
  if (encoded <= kEncodedThreshold) return encoded / kSlope;
  return std::pow((encoded + kOffset) / (1.0 + kOffset), kGamma);
}

double linear_to_srgb(double linear) {
  if (linear <= kLinearThreshold) return kSlope * linear;
  return (1.0 + kOffset) * std::pow(linear, 1.0 / kGamma) - kOffset;
}

float srgb_to_linear(float encoded) { return static_cast<float>(srgb_to_linear(static_cast<double>(encoded))); }
float linear_to_srgb(float linear) { return static_cast<float>(linear_to_srgb(static_cast<double>(linear))); }

void srgb_to_linear(const float* encoded, float* linear, size_t count) {
  for (size_t i = 0; i < count; ++i) linear[i] = srgb_to_linear(encoded[i]);
}

void linear_to_srgb(const float* linear, float* encoded, size_t count) {
  for (size_t i = 0; i < count; ++i) encoded[i] = linear_to_srgb(linear[i]);
}

uint8_t linear_to_srgb8(double linear) {
  if (!(linear > 0.0)) return 0;  // also NaN
  if (linear >= 1.0) return 255;
  return static_cast<uint8_t>(std::lround(255.0 * linear_to_srgb(linear)));
}

double srgb8_to_linear(uint8_t code) { return srgb_to_linear(code / 255.0); }

}  // namespace mipnerf::io
