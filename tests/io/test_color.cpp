// sRGB ↔ linear (host/io/color): published values of the IEC 61966-2-1 curve, continuity, round trips.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "io/color.hpp"

using namespace mipnerf;

TEST_CASE("color: sRGB transfer curve known values") {
  // Endpoints are exact on both segments.
  CHECK(io::srgb_to_linear(0.0) == 0.0);
  CHECK(io::linear_to_srgb(0.0) == 0.0);
  CHECK(io::srgb_to_linear(1.0) == doctest::Approx(1.0).epsilon(1e-15));
  CHECK(io::linear_to_srgb(1.0) == doctest::Approx(1.0).epsilon(1e-15));
  // Commonly published values: encoded 0.5 is 21.404 % linear; linear 0.5 encodes to 0.735357;
  // 18 % grey encodes to 0.461356 (code 118); code 128 is 0.2158605 linear.
  CHECK(io::srgb_to_linear(0.5) == doctest::Approx(0.2140411405).epsilon(1e-9));
  CHECK(io::linear_to_srgb(0.5) == doctest::Approx(0.7353569831).epsilon(1e-9));
  CHECK(io::linear_to_srgb(0.18) == doctest::Approx(0.4613561295).epsilon(1e-9));
  CHECK(io::linear_to_srgb8(0.18) == 118);
  CHECK(io::srgb8_to_linear(128) == doctest::Approx(0.2158605001).epsilon(1e-9));
  // The linear segment: slope 12.92 below the thresholds.
  CHECK(io::linear_to_srgb(0.001) == doctest::Approx(0.01292).epsilon(1e-14));
  CHECK(io::srgb_to_linear(0.02) == doctest::Approx(0.02 / 12.92).epsilon(1e-14));
  CHECK(io::srgb8_to_linear(1) == doctest::Approx(1.0 / 255.0 / 12.92).epsilon(1e-14));
}

TEST_CASE("color: the two segments meet at the thresholds, and the curve is increasing") {
  // The standard's constants leave a gap below 1e-7 between the segments (12.92·0.0031308 = 0.04044994).
  const double t = 0.0031308, e = 0.04045;
  CHECK(std::abs(io::linear_to_srgb(std::nextafter(t, 1.0)) - io::linear_to_srgb(t)) < 1e-7);
  CHECK(std::abs(io::srgb_to_linear(std::nextafter(e, 1.0)) - io::srgb_to_linear(e)) < 1e-8);
  double previous = -1.0;
  for (int i = 0; i <= 100000; ++i) {
    const double v = io::linear_to_srgb(i / 100000.0);
    REQUIRE(v >= previous);
    previous = v;
  }
}

TEST_CASE("color: round trips, continuous and 8-bit") {
  for (int i = -100; i <= 20000; ++i) {
    const double x = i / 10000.0;  // −0.01 .. 2: outside [0, 1] too, no clamping
    REQUIRE(io::srgb_to_linear(io::linear_to_srgb(x)) == doctest::Approx(x).epsilon(1e-12));
    REQUIRE(io::linear_to_srgb(io::srgb_to_linear(x)) == doctest::Approx(x).epsilon(1e-12));
  }
  for (int code = 0; code < 256; ++code) {
    REQUIRE(io::linear_to_srgb8(io::srgb8_to_linear(static_cast<uint8_t>(code))) == code);
  }
  // float versions and arrays: one rounding to float of the double result.
  float values[4] = {0.0f, 0.25f, 0.5f, 1.0f}, encoded[4], back[4];
  io::linear_to_srgb(values, encoded, 4);
  io::srgb_to_linear(encoded, back, 4);
  for (int i = 0; i < 4; ++i) {
    CHECK(encoded[i] == static_cast<float>(io::linear_to_srgb(static_cast<double>(values[i]))));
    CHECK(back[i] == doctest::Approx(values[i]).epsilon(3e-7));  // two float roundings, slopes ≤ 12.92/… ~1
  }
  // 8-bit quantisation clamps and maps NaN to 0.
  CHECK(io::linear_to_srgb8(-0.5) == 0);
  CHECK(io::linear_to_srgb8(7.0) == 255);
  CHECK(io::linear_to_srgb8(std::numeric_limits<double>::quiet_NaN()) == 0);
  CHECK(std::isnan(io::srgb_to_linear(std::numeric_limits<double>::quiet_NaN())));
}
