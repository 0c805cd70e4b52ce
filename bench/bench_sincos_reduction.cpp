// The two measured inputs of encode.cl's bound on sincos_reduced_in_double (gaussian_ipe_axis_fwd's sin/cos), from
// the host mirror ref::sincos_reduced_in_double (bit for bit the kernel's, tests/ops/test_encode.cpp):
//  1. the smallest |r| of y = n·π/2 + r over every float y in [π/4, 2^40) with n ≠ 0 (how close a float comes to a
//     multiple of π/2, which sets how much r's absolute error could matter relative to r);
//  2. the polynomials' error in ulp over every float r in [2^−12, 0.7856] against long double sin and cos.
// Usage: bench_sincos_reduction (about 10 s on one core; no device).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "ref/encode.hpp"

namespace {

float float_of_bits(uint32_t bits) {
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

uint32_t bits_of(float value) {
  uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

// |x − want| in units of the float ulp at want.
double ulps(float x, long double want) {
  const float want_float = static_cast<float>(std::fabs(want));
  const double ulp = std::nextafter(want_float, INFINITY) - want_float;
  return static_cast<double>(std::fabs(static_cast<long double>(x) - want)) / ulp;
}

void smallest_reduced() {
  double smallest = 1.0;
  float argument = 0.0f;
  for (uint32_t bits = bits_of(0.78539816f); bits < bits_of(1099511627776.0f); ++bits) {
    const float y = float_of_bits(bits);
    double n = 0;
    const double r = std::fabs(mipnerf::ref::reduce_by_half_pi(y, &n));
    if (n != 0 && r < smallest) {
      smallest = r;
      argument = y;
    }
  }
  std::printf("smallest |r| over every float y in [pi/4, 2^40): %.6g at y = %.9g\n", smallest, argument);
}

void polynomial_error() {
  double worst_sin = 0, worst_cos = 0;
  float at_sin = 0, at_cos = 0;
  for (uint32_t bits = bits_of(0.000244140625f); bits <= bits_of(0.7856f); ++bits) {
    const float r = float_of_bits(bits);
    float sin_r = 0, cos_r = 0;
    mipnerf::ref::sincos_of_reduced(r, &sin_r, &cos_r);
    const double e_sin = ulps(sin_r, std::sin(static_cast<long double>(r)));
    const double e_cos = ulps(cos_r, std::cos(static_cast<long double>(r)));
    if (e_sin > worst_sin) worst_sin = e_sin, at_sin = r;
    if (e_cos > worst_cos) worst_cos = e_cos, at_cos = r;
  }
  std::printf("polynomials over every float r in [2^-12, 0.7856]: sin within %.3f ulp (worst at r = %.9g), "
              "cos within %.3f ulp (worst at r = %.9g)\n",
              worst_sin, at_sin, worst_cos, at_cos);
}

}  // namespace

int main() {
  smallest_reduced();
  polynomial_error();
  return 0;
}
