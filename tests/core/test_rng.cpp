// The counter-based RNG: known answers, device = CPU mirror bit for bit, and basic uniformity.
#include <doctest/doctest.h>

#include "cl/buffer.hpp"
#include "cl/launch.hpp"
#include "core/rng.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {
struct Kat {
  std::array<uint32_t, 4> counter;
  std::array<uint32_t, 2> key;
  std::array<uint32_t, 4> expected;
};
// Known-answer vectors of Philox4x32-10 published with Random123 (kat_vectors).
const Kat kKnownAnswers[] = {
    {{0, 0, 0, 0}, {0, 0}, {0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}},
    {{0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff},
     {0xffffffff, 0xffffffff},
     {0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}},
    {{0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344},
     {0xa4093822, 0x299f31d0},
     {0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}},
};
}  // namespace

TEST_CASE("rng: Philox4x32-10 known answers on the CPU mirror and the device") {
  auto& ctx = test::test_context();
  for (const auto& kat : kKnownAnswers) {
    CHECK(philox4x32_10(kat.counter, kat.key) == kat.expected);
    ocl::DeviceArray<uint32_t> counters(ctx, 4, "counters"), out(ctx, 4, "words");
    counters.upload(ctx, kat.counter.data(), 4);
    auto& kernel = ctx.program({"common.cl", "util.cl"}).kernel("philox_words");
    ocl::set_args(kernel, "philox_words", counters, kat.key[0], kat.key[1], out, cl_uint{1});
    ocl::launch_1d(ctx, kernel, 1, "philox_words");
    const auto words = out.download(ctx);
    CHECK(std::array<uint32_t, 4>{words[0], words[1], words[2], words[3]} == kat.expected);
  }
}

TEST_CASE("rng: device uniforms equal the CPU mirror bit for bit, lie in 0..1 and look uniform") {
  auto& ctx = test::test_context();
  const cl_uint n = 10000;
  const uint64_t seed = 0x123456789abcdefULL;
  ocl::DeviceArray<float> out(ctx, 4 * n, "uniforms [n][4]");
  auto& kernel = ctx.program({"common.cl", "util.cl"}).kernel("rng_uniform4_fill");
  ocl::set_args(kernel, "rng_uniform4_fill", cl_ulong{seed}, cl_uint{7}, cl_uint{3}, cl_uint{rng_stream_batch},
                out, n);
  ocl::launch_1d(ctx, kernel, n, "rng_uniform4_fill");
  const auto device = out.download(ctx);
  double sum = 0.0;
  int bins[10] = {};
  for (cl_uint i = 0; i < n; ++i) {
    const auto expected = rng_uniform4(seed, i, 7, 3, rng_stream_batch);
    for (int k = 0; k < 4; ++k) {
      REQUIRE(device[4 * i + k] == expected[k]);
      REQUIRE(expected[k] >= 0.0f);
      REQUIRE(expected[k] < 1.0f);
      sum += expected[k];
      ++bins[static_cast<int>(expected[k] * 10)];
    }
  }
  // 40,000 draws: the mean's standard deviation is sqrt(1/12/40000) ≈ 0.0014, so 0.01 is > 7 sigma;
  // each decile expects 4,000 with sd ≈ 60, so ±400 is > 6 sigma.
  CHECK(std::abs(sum / (4.0 * n) - 0.5) < 0.01);
  for (int b = 0; b < 10; ++b) CHECK(std::abs(bins[b] - 4000) < 400);
  // A different stream or step gives different numbers.
  CHECK(rng_uniform4(seed, 0, 7, 3, 0) != rng_uniform4(seed, 0, 7, 3, 1));
  CHECK(rng_uniform4(seed, 0, 7, 3, 0) != rng_uniform4(seed, 0, 8, 3, 0));
}
