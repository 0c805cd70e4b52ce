// sRGB ↔ linear conversion: the IEC 61966-2-1 piecewise transfer curve, and 8-bit quantisation.
//
// Like the official NeRF and mip-NeRF code, training fits the stored (sRGB-encoded) PNG values directly,
// so the network's colours are sRGB-encoded: PNG output writes them as they are, and OpenEXR output,
// which holds linear RGB by convention, converts them with srgb_to_linear first.
#pragma once

#include <cstddef>
#include <cstdint>

namespace mipnerf::io {

// Encoded → linear: v / 12.92 for v ≤ 0.04045, else ((v + 0.055) / 1.055)^2.4.
double srgb_to_linear(double encoded);
// Linear → encoded: 12.92·l for l ≤ 0.0031308, else 1.055·l^(1/2.4) − 0.055.
double linear_to_srgb(double linear);
// No clamping: values below 0 follow the linear segment, values above 1 the power segment (so HDR
// values survive a round trip); NaN stays NaN.

// float versions (computed in double, rounded once) and in-place-safe array versions (out may be in).
float srgb_to_linear(float encoded);
float linear_to_srgb(float linear);
void srgb_to_linear(const float* encoded, float* linear, size_t count);
void linear_to_srgb(const float* linear, float* encoded, size_t count);

// 8-bit codes: linear → encoded, clamped to [0, 1], rounded to the nearest of 0..255 (NaN gives 0);
// and code → linear. linear_to_srgb8(srgb8_to_linear(c)) == c for every code.
uint8_t linear_to_srgb8(double linear);
double srgb8_to_linear(uint8_t code);

}  // namespace mipnerf::io
