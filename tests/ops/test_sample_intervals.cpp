// Proposal sampling's sampler (kernels/sample_intervals.cl): the kernel inside the reference's float32 envelope
// (ref::sample_intervals_envelope, derived there) deterministic and randomised, one jitter per ray or per sample;
// hard cases with closed-form answers (one interval holding every weight, all-zero weights, empty intervals with
// large weights, anneal 0, M = 2, domain clipping, no non-empty interval); sorted, finite, inside the domain on
// extreme inputs; chunking; refusals; the anneal schedule.
#include <doctest/doctest.h>

#include <algorithm>
#include <limits>

#include "core/proposal_anneal.hpp"
#include "kernel_checks.hpp"
#include "ops/sample_intervals.hpp"
#include "ref/sample_intervals.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

constexpr double kFloatEpsilon = std::numeric_limits<float>::epsilon();  // the envelope's eps for the kernel

struct ProposalHistograms {
  size_t n_rays = 0, n_intervals = 0;
  std::vector<float> s_edges, weights;
};

// Sorted edges in [0, 1] with random gaps, every 5th ray with some zero-width intervals; weights of five kinds:
// uniform random, sparse spikes, a smooth bump, all zero, and huge (1e30) spikes on tiny ones.
ProposalHistograms random_proposal_histograms(size_t n_rays, size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  ProposalHistograms h;
  h.n_rays = n_rays;
  h.n_intervals = n;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    std::vector<double> gaps(n);
    double total = 0;
    for (size_t i = 0; i < n; ++i) {
      gaps[i] = (ray % 5 == 0 && i % 3 == 1) ? 0.0 : test::log_uniform(rng, 1e-3, 1.0);
      total += gaps[i];
    }
    double s = 0;
    for (size_t k = 0; k <= n; ++k) {
      h.s_edges.push_back(static_cast<float>(k == n ? 1.0 : s / total));
      if (k < n) s += gaps[k];
    }
    const size_t kind = ray % 5, peak = rng() % n;
    for (size_t i = 0; i < n; ++i) {
      double w = 0;
      if (kind == 0) w = unit(rng);
      if (kind == 1) w = unit(rng) < 0.15 ? unit(rng) : 0.0;
      if (kind == 2) w = std::exp(-0.5 * std::pow((double(i) - peak) / 2.0, 2));
      if (kind == 4) w = unit(rng) < 0.1 ? 1e30 * unit(rng) : 1e-6 * unit(rng);
      h.weights.push_back(static_cast<float>(w));
    }
  }
  return h;
}

// Rays first .. first + count − 1 of `h` into m intervals on the device.
std::vector<float> run_sample_intervals(const SampleIntervalsOptions& options, const ProposalHistograms& h, size_t m,
                                        const RngKey& key, size_t first = 0, size_t count = SIZE_MAX) {
  auto& ctx = test::test_context();
  count = std::min(count, h.n_rays - first);
  const size_t n = h.n_intervals;
  const std::vector<float> s(h.s_edges.begin() + first * (n + 1), h.s_edges.begin() + (first + count) * (n + 1));
  const std::vector<float> w(h.weights.begin() + first * n, h.weights.begin() + (first + count) * n);
  auto s_dev = test::upload(ctx, s, "s_edges"), w_dev = test::upload(ctx, w, "weights");
  auto out = test::filled(ctx, count * (m + 1), 7.0f, "s_new");
  ops::SampleIntervals stage(ctx);
  stage.fwd(options, {s_dev, w_dev, count, n, m}, out, key);
  return out.download(ctx);
}

// Counts the device edges outside the envelope of their ray (and checks sorted, finite, inside the domain).
struct EnvelopeCount {
  size_t outside = 0, unsorted = 0, outside_domain = 0, non_finite = 0;
  double widest = 0;  // the widest envelope seen (to show it is not vacuous)
};
EnvelopeCount count_outside_envelope(const SampleIntervalsOptions& options, const ProposalHistograms& h, size_t m,
                                     const RngKey& key, const std::vector<float>& device) {
  EnvelopeCount c;
  const size_t n = h.n_intervals;
  const std::vector<double> s = test::to_double(h.s_edges), w = test::to_double(h.weights);
  for (size_t ray = 0; ray < h.n_rays; ++ray) {
    const auto u = ref::sample_intervals_u(options, m, key, ray);
    const auto env =
        ref::sample_intervals_envelope(options, s.data() + ray * (n + 1), w.data() + ray * n, n, u, kFloatEpsilon);
    for (size_t j = 0; j <= m; ++j) {
      const float e = device[ray * (m + 1) + j];
      if (!std::isfinite(e)) ++c.non_finite;
      if (!(e >= env.lo[j] && e <= env.hi[j])) ++c.outside;
      if (j > 0 && e < device[ray * (m + 1) + j - 1]) ++c.unsorted;
      if (e < options.domain_near || e > options.domain_far) ++c.outside_domain;
      c.widest = std::max(c.widest, env.hi[j] - env.lo[j]);
    }
  }
  return c;
}

SampleIntervalsOptions proposal_options(bool randomized, bool single_jitter, float anneal = 1.0f,
                                        float padding = 0.0f) {
  SampleIntervalsOptions o;
  o.randomized = randomized;
  o.single_jitter = single_jitter;
  o.anneal = anneal;
  o.resample_padding = padding;
  return o;
}

}  // namespace

TEST_CASE("sample_intervals: the kernel's edges lie in the reference's float32 envelope, every mode") {
  const RngKey key{20261128, 7, 3};
  for (size_t n : {1, 16, 64}) {
    const auto h = random_proposal_histograms(500, n, 11 + static_cast<unsigned>(n));
    for (size_t m : {2, 7, 48}) {
      for (int mode = 0; mode < 3; ++mode) {
        for (float anneal : {1.0f, 0.37f}) {
          const auto options = proposal_options(mode > 0, mode == 2, anneal, n == 16 ? 0.01f : 0.0f);
          CAPTURE(n);
          CAPTURE(m);
          CAPTURE(mode);
          CAPTURE(anneal);
          const auto device = run_sample_intervals(options, h, m, key);
          const auto c = count_outside_envelope(options, h, m, key, device);
          CHECK(c.non_finite == 0);
          CHECK(c.outside == 0);
          CHECK(c.unsorted == 0);
          CHECK(c.outside_domain == 0);
          if (std::getenv("MIPNERF_TEST_VERBOSE")) MESSAGE("widest envelope " << c.widest);
        }
      }
    }
  }
}

TEST_CASE("sample_intervals: the envelope rejects a wrong jitter mode, anneal or u (it is not vacuous)") {
  const RngKey key{5, 1, 0};
  const size_t n = 32, m = 32;
  const auto h = random_proposal_histograms(200, n, 99);
  const auto per_sample = proposal_options(true, false);
  // The kernel run with one jitter per ray, judged as per-sample jitter: most edges must fall outside.
  const auto single = run_sample_intervals(proposal_options(true, true), h, m, key);
  CHECK(count_outside_envelope(per_sample, h, m, key, single).outside > h.n_rays * (m + 1) / 2);
  // Anneal 0.9 judged as anneal 1 (rays with weights that are not all equal move).
  const auto annealed = run_sample_intervals(proposal_options(false, false, 0.9f), h, m, key);
  CHECK(count_outside_envelope(proposal_options(false, false, 1.0f), h, m, key, annealed).outside > h.n_rays);
  // The deterministic linspace judged as the randomised draws.
  const auto deterministic = run_sample_intervals(proposal_options(false, false), h, m, key);
  CHECK(count_outside_envelope(per_sample, h, m, key, deterministic).outside > h.n_rays * (m + 1) / 2);
}

namespace {

// One ray (edges s, weights w) into m intervals: the reference's edges and the kernel's, the kernel CHECKed inside
// the reference's envelope (so a closed form checked on the reference holds for the kernel to within it). The
// closed forms' bound: u_j = (j + 1/2)/M − j·ε/(M − 1) moves a centre by ≤ ε of its interval's width, a midpoint by
// ≤ ε, the reflected last edge by 2ε − (M − 3/2)ε/(M − 1) ≤ 1.5ε (M = 2 reaches it); 1e-15 for the double's own
// roundings.
struct OneRay {
  std::vector<double> reference;
  std::vector<float> device;
};
OneRay one_ray(const SampleIntervalsOptions& options, std::vector<float> s, std::vector<float> w, size_t m) {
  ProposalHistograms h;
  h.n_rays = 1;
  h.n_intervals = w.size();
  h.s_edges = std::move(s);
  h.weights = std::move(w);
  OneRay r;
  r.device = run_sample_intervals(options, h, m, {});
  const auto sd = test::to_double(h.s_edges), wd = test::to_double(h.weights);
  r.reference = ref::sample_intervals_ray(options, sd.data(), wd.data(), h.n_intervals,
                                          ref::sample_intervals_u(options, m, {}, 0));
  const auto c = count_outside_envelope(options, h, m, {}, r.device);
  CHECK(c.outside == 0);
  CHECK(c.non_finite == 0);
  CHECK(c.unsorted == 0);
  return r;
}

std::vector<float> uniform_edges(size_t n, double lo, double hi) {
  std::vector<float> s(n + 1);
  for (size_t k = 0; k <= n; ++k) s[k] = static_cast<float>(lo + (hi - lo) * double(k) / double(n));
  return s;
}

// CHECKs edges [M+1] against linspace(lo, hi, M + 1) within `tolerance`.
void check_linspace(const std::vector<double>& edges, double lo, double hi, double tolerance, const char* what) {
  const size_t m = edges.size() - 1;
  double worst = 0;
  for (size_t j = 0; j <= m; ++j)
    worst = std::max(worst, std::abs(edges[j] - (lo + (hi - lo) * double(j) / double(m))));
  INFO(what << ": worst |edge − linspace| " << worst << " against " << tolerance);
  CHECK(worst <= tolerance);
}

}  // namespace

TEST_CASE("sample_intervals: closed-form cases (one full interval, zero weights, empty intervals, anneal 0, M = 2)") {
  const auto det = proposal_options(false, false);
  for (size_t m : {2, 5, 16}) {
    CAPTURE(m);
    // All the weight in interval 2 of [0.2, 0.3]: the other logits are log(FLT_MIN) ≈ −87, their mass ~1e-38; the
    // deterministic centres are 0.2 + u_j·0.1, so the edges are linspace(0.2, 0.3, M + 1) to within 1.5·ε·0.1.
    {
      const auto r = one_ray(det, {0.0f, 0.1f, 0.2f, 0.3f, 1.0f}, {0.0f, 0.0f, 3.0f, 0.0f}, m);
      const double width = double(0.3f) - double(0.2f);
      check_linspace(r.reference, 0.2f, 0.3f, 1.5 * kFloatEpsilon * width + 1e-15, "one full interval, reference");
    }
    // All-zero weights, no padding: equal logits, a uniform histogram over 8 equal intervals: linspace(0, 1).
    {
      const auto r = one_ray(det, uniform_edges(8, 0, 1), std::vector<float>(8, 0.0f), m);
      check_linspace(r.reference, 0, 1, 1.5 * kFloatEpsilon + 1e-15, "all-zero weights, reference");
    }
    // Empty intervals (repeated edges) with weights 1e6 beside equal weights on four equal non-empty intervals:
    // −∞ logits give them no mass, so the edges are linspace(0, 1); were their weights used, every centre would
    // sit at 0.25, 0.5 or 0.75.
    {
      const auto r = one_ray(det, {0.0f, 0.25f, 0.25f, 0.5f, 0.5f, 0.75f, 0.75f, 1.0f},
                             {1.0f, 1e6f, 1.0f, 1e6f, 1.0f, 1e6f, 1.0f}, m);
      check_linspace(r.reference, 0, 1, 1.5 * kFloatEpsilon + 1e-15, "empty intervals, reference");
    }
    // Anneal 0: every non-empty interval's logit is 0 whatever its weight: uniform over them (linspace over the
    // equal non-empty intervals of [0, 1], one empty one in between).
    {
      const auto r = one_ray(proposal_options(false, false, 0.0f), {0.0f, 0.25f, 0.5f, 0.5f, 0.75f, 1.0f},
                             {9.0f, 0.001f, 5.0f, 0.0f, 123.0f}, m);
      check_linspace(r.reference, 0, 1, 1.5 * kFloatEpsilon + 1e-15, "anneal 0, reference");
    }
  }
}

TEST_CASE("sample_intervals: edges are clipped to the domain, and a ray with no non-empty interval is one point") {
  // Most weight in [0, 0.1] and some in [0.9, 1] (padding 0.01 keeps the rest): the reflected first edge falls
  // below 0 and the last beyond 1 before the clip; the domain (0.05, 0.95) clips more.
  auto options = proposal_options(false, false, 1.0f, 0.01f);
  options.domain_near = 0.05f;
  options.domain_far = 0.95f;
  const std::vector<float> s = {0.0f, 0.1f, 0.5f, 0.9f, 1.0f}, w = {5.0f, 0.0f, 0.0f, 1.0f};
  const auto r = one_ray(options, s, w, 6);
  CHECK(r.device.front() == 0.05f);
  CHECK(r.device.back() == 0.95f);
  CHECK(r.reference.front() == double(0.05f));
  // Unclipped, the reflections leave [0, 1]: the reference without a domain shows it.
  auto open = options;
  open.domain_near = -std::numeric_limits<float>::infinity();
  open.domain_far = std::numeric_limits<float>::infinity();
  const auto r_open = one_ray(open, s, w, 6);
  CHECK(r_open.reference.front() < 0.05);
  CHECK(r_open.device.front() < 0.05f);
  // Every edge equal: all logits −∞; the official's softmax is NaN there, ours is the ray's one point, clipped.
  const auto empty = one_ray(options, {0.3f, 0.3f, 0.3f}, {1.0f, 2.0f}, 3);
  for (float e : empty.device) CHECK(e == 0.3f);
  const auto outside = one_ray(options, {0.01f, 0.01f}, {1.0f}, 2);
  for (float e : outside.device) CHECK(e == 0.05f);
}

// The linear s → t of bounded scenes (official construct_ray_warps with fn = None): against the reference, exact at s = 0
// and 1 (near and far themselves), within a float32 rounding of the lerp elsewhere, and clipped into [near, far].
TEST_CASE("sample_intervals: s to t is the official linear warp per ray, exact at the ends, inside [near, far]") {
  auto& ctx = test::test_context();
  const size_t n_rays = 5, per_ray = 7;
  const std::vector<float> near = {2.0f, 0.0f, 0.5f, 1e-3f, 3.0f}, far = {6.0f, 1.0f, 100.0f, 1e3f, 3.0f};
  std::vector<float> s;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    for (size_t k = 0; k < per_ray; ++k) s.push_back(static_cast<float>(k) / static_cast<float>(per_ray - 1));
  }
  s[3] = 0.3333333f;
  ops::RayBundle rays(ctx, n_rays);
  rays.near.upload(ctx, near);
  rays.far.upload(ctx, far);
  auto s_device = test::upload(ctx, s, "s");
  auto t_device = test::filled(ctx, n_rays * per_ray, -1.0f, "t");
  ops::SampleIntervals(ctx).s_to_t(s_device, rays, n_rays, per_ray, t_device);
  const auto t = t_device.download(ctx);
  std::vector<double> expected;
  ref::sample_intervals_s_to_t(test::to_double(s), test::to_double(near), test::to_double(far), expected, n_rays,
                               per_ray);
  for (size_t i = 0; i < t.size(); ++i) {
    const size_t ray = i / per_ray, k = i % per_ray;
    INFO("ray " << ray << " value " << k);
    CHECK(t[i] >= near[ray]);
    CHECK(t[i] <= far[ray]);
    if (k == 0) CHECK(t[i] == near[ray]);
    if (k + 1 == per_ray) CHECK(t[i] == far[ray]);
    // Two products and a sum of values ≤ max(|near|, |far|): within 3 ulp of it.
    CHECK(std::abs(t[i] - expected[i]) <= 3 * kFloatEpsilon * std::max(std::abs(near[ray]), std::abs(far[ray])));
  }
  CHECK_THROWS_WITH_AS(ops::SampleIntervals(ctx).s_to_t(s_device, rays, n_rays, 0, t_device),
                       doctest::Contains("n_per_ray must be at least 1"), Error);
}

// The unbounded scenes' power ladder (camp_zipnerf 360.gin): against the reference within its float32 bound, from
// s = 0 to the last float32 below 1 and 1 itself, near 0 and far 1e6 as the official trains and other bounds; the
// ends near and min(far, ≈ 8.58e4) (the official's clip of y); increasing in s; finite with far = +∞. The bound is the
// derivation's (ref::ray_distance_power_ladder_float32_bound): the linear warp's value at s = 0.5 misses it by 10^5×.
TEST_CASE("sample_intervals: s to t by the power ladder is the reference within its float32 bound, out to 1 and far = inf") {
  auto& ctx = test::test_context();
  const std::vector<float> near = {0.0f, 0.0f, 0.2f, 1e-3f, 0.0f}, far = {1e6f, 10.0f, 1e6f, 3.0f,
                                                                       std::numeric_limits<float>::infinity()};
  const size_t n_rays = near.size();
  std::vector<float> per_ray_s = {0.0f, 1e-7f, 1e-3f, 0.01f, 0.1f, 0.25f, 0.5f, 0.75f, 0.9f, 0.99f, 0.999f,
                                  0.9999f, 0.99999f, 0.999999f, 0.9999999f, std::nextafter(1.0f, 0.0f), 1.0f};
  for (int k = 1; k < 40; ++k) per_ray_s.push_back(static_cast<float>(k) / 40.0f);
  std::sort(per_ray_s.begin(), per_ray_s.end());
  const size_t per_ray = per_ray_s.size();
  std::vector<float> s;
  for (size_t ray = 0; ray < n_rays; ++ray) s.insert(s.end(), per_ray_s.begin(), per_ray_s.end());
  ops::RayBundle rays(ctx, n_rays);
  rays.near.upload(ctx, near);
  rays.far.upload(ctx, far);
  auto s_device = test::upload(ctx, s, "s");
  auto t_device = test::filled(ctx, n_rays * per_ray, -1.0f, "t");
  ops::SampleIntervals warp(ctx, RayDistance::power_ladder);
  CHECK(warp.ray_distance() == RayDistance::power_ladder);
  warp.s_to_t(s_device, rays, n_rays, per_ray, t_device);
  const auto t = t_device.download(ctx);
  std::vector<double> expected;
  ref::sample_intervals_s_to_t(test::to_double(s), test::to_double(near), test::to_double(far), expected, n_rays,
                               per_ray, RayDistance::power_ladder);
  double worst_ratio = 0.0;
  for (size_t i = 0; i < t.size(); ++i) {
    const size_t ray = i / per_ray, k = i % per_ray;
    INFO("ray " << ray << " (near " << near[ray] << ", far " << far[ray] << ") s = " << s[i]);
    REQUIRE(std::isfinite(t[i]));
    CHECK(t[i] >= near[ray]);
    CHECK(t[i] <= far[ray]);
    if (k > 0) CHECK(t[i] >= t[i - 1]);
    const double bound = ref::ray_distance_power_ladder_float32_bound(expected[i]);
    CHECK(std::abs(t[i] - expected[i]) <= bound);
    worst_ratio = std::max(worst_ratio, std::abs(t[i] - expected[i]) / bound);
    // A warp that is not the power ladder (the linear one) misses the bound by far.
    const double linear = ref::ray_distance_s_to_t(RayDistance::linear, s[i], near[ray], std::min(far[ray], 1e6f));
    if (s[i] == 0.5f) CHECK(std::abs(linear - expected[i]) > 1e5 * bound);
  }
  MESSAGE("power ladder s to t: worst error / bound " << worst_ratio);
  // The ends: s = 0 gives near; s = 1 gives far where far is below the official's clip, ≈ 8.58e4 past it.
  CHECK(t[0] == 0.0f);
  CHECK(t[2 * per_ray] == 0.2f);
  CHECK(t[2 * per_ray - 1] == 10.0f);
  CHECK(std::abs(t[per_ray - 1] - 85774.7) < 85774.7 * 1e-5);
  CHECK(std::abs(t[n_rays * per_ray - 1] - 85774.7) < 85774.7 * 1e-5);
  // Half the uniform s within t ≈ 0.73 of the origin (near 0, far 1e6): where a spherified capture's object is.
  CHECK(std::abs(expected[std::find(per_ray_s.begin(), per_ray_s.end(), 0.5f) - per_ray_s.begin()] - 0.7345) < 1e-3);
}

TEST_CASE("sample_intervals: sorted, finite and inside the domain on extreme weights, whatever the chunking") {
  const RngKey key{77, 3, 100};
  auto h = random_proposal_histograms(300, 24, 4242);
  for (size_t i = 0; i < h.weights.size(); i += 7) h.weights[i] = (i % 2) ? 3e38f : 1e-38f;
  auto options = proposal_options(true, false);
  options.domain_near = 0.1f;
  options.domain_far = 0.8f;
  const auto whole = run_sample_intervals(options, h, 20, key);
  const auto c = count_outside_envelope(options, h, 20, key, whole);
  CHECK(c.non_finite == 0);
  CHECK(c.unsorted == 0);
  CHECK(c.outside_domain == 0);
  CHECK(c.outside == 0);
  // The same rays in two launches (the second starting at first_ray + 128) draw the same jitter.
  const auto part1 = run_sample_intervals(options, h, 20, key, 0, 128);
  const auto part2 = run_sample_intervals(options, h, 20, {key.seed, key.step, key.first_ray + 128}, 128);
  std::vector<float> joined = part1;
  joined.insert(joined.end(), part2.begin(), part2.end());
  CHECK(joined == whole);
}

TEST_CASE("sample_intervals: refusals name the value and what is allowed") {
  auto& ctx = test::test_context();
  auto s = test::upload(ctx, std::vector<float>{0.0f, 0.5f, 1.0f}, "s");
  auto w = test::upload(ctx, std::vector<float>{1.0f, 1.0f}, "w");
  auto out = test::filled(ctx, 4, 0.0f, "out");
  ops::SampleIntervals stage(ctx);
  SampleIntervalsOptions options;
  CHECK_THROWS_WITH_AS(stage.fwd(options, {s, w, 1, 2, 1}, out), doctest::Contains("at least 2"), Error);
  auto bad = options;
  bad.anneal = std::nanf("");
  CHECK_THROWS_WITH_AS(stage.fwd(bad, {s, w, 1, 2, 3}, out), doctest::Contains("anneal"), Error);
  bad = options;
  bad.domain_near = 1.0f;
  bad.domain_far = 0.0f;
  CHECK_THROWS_WITH_AS(stage.fwd(bad, {s, w, 1, 2, 3}, out), doctest::Contains("domain_near ≤ domain_far"), Error);
  CHECK_THROWS_AS(stage.fwd(options, {s, w, 1, 2, 4}, out), Error);  // out holds 4, needs 5
}

TEST_CASE("proposal_anneal: Schlick's bias from 0 to 1, 1/2 at x = 1/(s + 1), off for slope ≤ 0") {
  CHECK(proposal_anneal(0.0, 10.0) == 0.0);
  CHECK(proposal_anneal(1.0, 10.0) == 1.0);
  CHECK(proposal_anneal(1.0 / 11.0, 10.0) == doctest::Approx(0.5).epsilon(1e-15));
  CHECK(proposal_anneal(0.3, 1.0) == doctest::Approx(0.3).epsilon(1e-15));  // s = 1: the identity
  CHECK(proposal_anneal(0.3, 0.0) == 1.0);
  CHECK(proposal_anneal(0.3, -2.0) == 1.0);
  double previous = -1;
  for (int i = 0; i <= 100; ++i) {
    const double a = proposal_anneal(i / 100.0, 10.0);
    CHECK(a > previous);
    previous = a;
  }
}
