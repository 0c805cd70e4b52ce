// Zip-NeRF's proposal sampler, our reference (host/ref/sample_intervals.hpp) and kernel (kernels/sample_intervals.cl)
// against the official camp_zipnerf stepfun.sample_intervals with models.py's annealed, padded logits
// (fixtures/zipnerf_sample_intervals.json, written by make_sample_intervals_vectors.py): deterministic and randomised
// (the official given our own draws in place of jax.random.uniform), one jitter per ray or per sample, M = 2..32,
// clipped domains; and Schlick's bias, the anneal schedule. The official math ran in float64.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/proposal_anneal.hpp"
#include "core/rng.hpp"
#include "official_fixtures.hpp"
#include "ops/sample_intervals.hpp"
#include "ref/sample_intervals.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

io::Json sample_intervals_fixture() {
  return official::zipnerf_fixture("zipnerf_sample_intervals.json");
}

SampleIntervalsOptions case_options(const io::Json& c) {
  SampleIntervalsOptions o;
  const std::string mode = c.at("mode").get<std::string>();
  o.randomized = mode != "deterministic";
  o.single_jitter = mode == "single_jitter";
  o.anneal = c.at("anneal").get<float>();
  o.resample_padding = c.at("resample_padding").get<float>();
  o.domain_near = c.at("domain").at(0).get<float>();
  o.domain_far = c.at("domain").at(1).get<float>();
  return o;
}

// The official's u differs from the exact one by its float32 constants (eps, and the numpy-scalar arithmetic on it:
// linspace's stop 1 − pad − eps, u_max, 1 − u_max and max_jitter each round to float32, ≤ ε/2 each for values ≤ 1,
// four of them): ≤ 2ε; doubled so the bound does not sit on the derivation's edge.
constexpr double kOfficialUSlack = 4.0 * std::numeric_limits<float>::epsilon();

}  // namespace

TEST_CASE("official sample_intervals: the fixture's draws are ours (key, stream 6, slot per sample)") {
  const auto json = sample_intervals_fixture();
  const auto& k = json.at("rng_key");
  const RngKey key{k.at("seed").get<uint64_t>(), k.at("step").get<uint32_t>(), k.at("first_ray").get<uint32_t>()};
  REQUIRE(json.at("rng_stream").get<uint32_t>() == rng_stream_proposal);
  size_t checked = 0;
  for (const auto& c : json.at("cases")) {
    if (c.at("xi").is_null()) continue;
    const auto xi = official::flat(c.at("xi"));
    const size_t d = c.at("xi").at(0).size();
    for (size_t ray = 0; ray < c.at("xi").size(); ++ray) {
      for (size_t j = 0; j < d; ++j) {
        const float ours = rng_uniform4(key.seed, key.first_ray + static_cast<uint32_t>(ray), key.step,
                                        static_cast<uint32_t>(j / 4), rng_stream_proposal)[j % 4];
        CHECK(xi[ray * d + j] == ours);
        ++checked;
      }
    }
  }
  CHECK(checked > 0);
}

TEST_CASE("official sample_intervals: reference and kernel against the official edges") {
  const auto json = sample_intervals_fixture();
  const size_t n_rays = json.at("n_rays").get<size_t>(), n = json.at("n_intervals").get<size_t>();
  const auto s = official::flat(json.at("s_edges"), {n_rays, n + 1});
  const auto w = official::flat(json.at("weights"), {n_rays, n});
  const auto& k = json.at("rng_key");
  const RngKey key{k.at("seed").get<uint64_t>(), k.at("step").get<uint32_t>(), k.at("first_ray").get<uint32_t>()};
  auto& ctx = test::test_context();
  const std::vector<float> s_f(s.begin(), s.end()), w_f(w.begin(), w.end());
  ocl::DeviceArray<float> s_dev(ctx, s_f.size(), "s_edges"), w_dev(ctx, w_f.size(), "weights");
  s_dev.upload(ctx, s_f);
  w_dev.upload(ctx, w_f);
  ops::SampleIntervals stage(ctx);
  size_t case_index = 0;
  for (const auto& c : json.at("cases")) {
    const auto options = case_options(c);
    const size_t m = c.at("new_intervals").get<size_t>();
    const auto official_edges = official::flat(c.at("s_new"), {n_rays, m + 1});
    ocl::DeviceArray<float> out(ctx, n_rays * (m + 1), "s_new");
    stage.fwd(options, {s_dev, w_dev, n_rays, n, m}, out, key);
    const auto device = out.download(ctx);
    std::vector<double> reference;
    ref::sample_intervals_fwd(options, s, w, reference, n_rays, n, m, key);
    CAPTURE(case_index);
    CAPTURE(c.at("mode").get<std::string>());
    CAPTURE(m);
    size_t ref_outside = 0, device_outside = 0, official_outside_float = 0;
    double worst_ref_error = 0;
    for (size_t ray = 0; ray < n_rays; ++ray) {
      const auto u = ref::sample_intervals_u(options, m, key, ray);
      // Our reference vs the official, both float64: the envelope at float64's eps, widened in u by the official's
      // float32 constants (kOfficialUSlack); where the CDF is flat it spans the bin, elsewhere δ/p_k of it.
      const auto tight = ref::sample_intervals_envelope(options, s.data() + ray * (n + 1), w.data() + ray * n, n, u,
                                                        std::numeric_limits<double>::epsilon(), kOfficialUSlack);
      // The float32 kernel: the envelope at float32's eps (ref/sample_intervals.hpp derives it), with the same slack
      // so that the official's edges lie in it too: |kernel − official| ≤ its width.
      const auto loose = ref::sample_intervals_envelope(options, s.data() + ray * (n + 1), w.data() + ray * n, n, u,
                                                        std::numeric_limits<float>::epsilon(), kOfficialUSlack);
      for (size_t j = 0; j <= m; ++j) {
        const size_t at = ray * (m + 1) + j;
        const double off = official_edges[at];
        if (!(off >= tight.lo[j] && off <= tight.hi[j])) ++ref_outside;
        if (!(off >= loose.lo[j] && off <= loose.hi[j])) ++official_outside_float;
        if (!std::isfinite(device[at]) || !(device[at] >= loose.lo[j] && device[at] <= loose.hi[j])) {
          ++device_outside;
        }
        worst_ref_error = std::max(worst_ref_error, std::abs(reference[at] - off));
        INFO("ray " << ray << " edge " << j << ": official " << off << " reference " << reference[at] << " kernel "
                    << device[at] << " float64 envelope [" << tight.lo[j] << ", " << tight.hi[j]
                    << "] float32 envelope [" << loose.lo[j] << ", " << loose.hi[j] << "]");
        CHECK((off >= tight.lo[j] && off <= tight.hi[j]));
        CHECK((device[at] >= loose.lo[j] && device[at] <= loose.hi[j]));
      }
    }
    if (std::getenv("MIPNERF_TEST_VERBOSE")) {
      MESSAGE("case " << case_index << ": worst |reference − official| " << worst_ref_error);
    }
    CHECK(ref_outside == 0);
    CHECK(official_outside_float == 0);
    CHECK(device_outside == 0);
    ++case_index;
  }
  CHECK(case_index == 10);
}

TEST_CASE("official sample_intervals: the float64 envelope tells the jitter modes apart (the comparison can fail)") {
  const auto json = sample_intervals_fixture();
  const size_t n_rays = json.at("n_rays").get<size_t>(), n = json.at("n_intervals").get<size_t>();
  const auto s = official::flat(json.at("s_edges"), {n_rays, n + 1});
  const auto w = official::flat(json.at("weights"), {n_rays, n});
  const auto& k = json.at("rng_key");
  const RngKey key{k.at("seed").get<uint64_t>(), k.at("step").get<uint32_t>(), k.at("first_ray").get<uint32_t>()};
  size_t judged = 0, outside = 0;
  for (const auto& c : json.at("cases")) {
    if (c.at("mode").get<std::string>() == "deterministic") continue;
    auto wrong = case_options(c);
    wrong.single_jitter = !wrong.single_jitter;  // the other mode's u
    const size_t m = c.at("new_intervals").get<size_t>();
    const auto official_edges = official::flat(c.at("s_new"), {n_rays, m + 1});
    for (size_t ray = 0; ray < n_rays; ++ray) {
      const auto u = ref::sample_intervals_u(wrong, m, key, ray);
      const auto env = ref::sample_intervals_envelope(wrong, s.data() + ray * (n + 1), w.data() + ray * n, n, u,
                                                      std::numeric_limits<double>::epsilon(), kOfficialUSlack);
      for (size_t j = 0; j <= m; ++j, ++judged) {
        const double off = official_edges[ray * (m + 1) + j];
        if (!(off >= env.lo[j] && off <= env.hi[j])) ++outside;
      }
    }
  }
  // M = 2 with one jitter per sample differs from one per ray in u_1 only, and clipped or flat-CDF edges can agree:
  // most, not all, must fall outside.
  INFO(outside << " of " << judged << " official edges outside the other mode's envelope");
  CHECK(outside * 2 > judged);
}

TEST_CASE("official sample_intervals: proposal_anneal is models.py's Schlick bias") {
  const auto json = sample_intervals_fixture();
  size_t checked = 0;
  for (const auto& row : json.at("bias")) {
    const double x = row.at("train_frac").get<double>(), slope = row.at("anneal_slope").get<double>();
    const double official = row.at("anneal").get<double>();
    // Both evaluate s·x / ((s − 1)·x + 1) in float64: four roundings each, ≤ 4·2^-53 relative apiece.
    CHECK(std::abs(proposal_anneal(x, slope) - official) <= 8.0 * std::numeric_limits<double>::epsilon() * official);
    ++checked;
  }
  CHECK(checked == 28);
}

// Zip-NeRF's ray distance of unbounded scenes (configs/zipnerf/360.gin: raydist_fn = power_ladder / inv_power_ladder
// with p = −3/2, premult 2) against the official construct_ray_warps' s_to_t (fixtures/zipnerf_ray_distance.json):
// near 0 / far 1e6 as the official trains, other bounds, s up to the last float32 values below 1 and 1 (where the
// official's clip holds the edge at ≈ 8.58e4). The official ran in float64 but with its float32 constants, mirrored
// by ours but for its float32 exponent 1/p (−0.6666667 for −2/3): t^(official) differs from the exact one by
// ≤ |ln G|·2e−8 ≤ 3.4e−7 relative (G ≥ 5.6e−8), the slack below; the kernel's own float32 bound on top.
TEST_CASE("official ray distance: the power ladder's s to t equals camp_zipnerf's, reference and kernel") {
  const io::Json json = official::zipnerf_fixture("zipnerf_ray_distance.json");
  const auto s = json.at("s").get<std::vector<double>>();
  const auto& cases = json.at("cases");
  REQUIRE(cases.size() >= 5);
  const size_t n_rays = cases.size(), per_ray = s.size();
  std::vector<float> s_all, near, far;
  std::vector<double> official_t;
  for (const auto& c : cases) {
    near.push_back(c.at("near").get<float>());
    far.push_back(c.at("far").get<float>());
    for (double v : s) s_all.push_back(static_cast<float>(v));
    const auto t = c.at("t").get<std::vector<double>>();
    REQUIRE(t.size() == per_ray);
    official_t.insert(official_t.end(), t.begin(), t.end());
  }
  for (size_t i = 0; i < s_all.size(); ++i) REQUIRE(static_cast<double>(s_all[i]) == s[i % per_ray]);  // float32 s
  auto& ctx = test::test_context();
  ops::RayBundle rays(ctx, n_rays);
  rays.near.upload(ctx, near);
  rays.far.upload(ctx, far);
  ocl::DeviceArray<float> s_device(ctx, s_all.size(), "s"), t_device(ctx, s_all.size(), "t");
  s_device.upload(ctx, s_all);
  ops::SampleIntervals(ctx, RayDistance::power_ladder).s_to_t(s_device, rays, n_rays, per_ray, t_device);
  const auto t = t_device.download(ctx);
  const auto exponent_slack = [](double t_value) { return 3.4e-7 * (t_value + 1.25); };
  double worst_ref = 0.0, worst_kernel = 0.0;
  for (size_t i = 0; i < t.size(); ++i) {
    const size_t ray = i / per_ray;
    const double expected = official_t[i];
    INFO("near " << near[ray] << ", far " << far[ray] << ", s = " << s[i % per_ray] << ": official t " << expected);
    const double ours = ref::ray_distance_s_to_t(RayDistance::power_ladder, s[i % per_ray], near[ray], far[ray]);
    CHECK(std::abs(ours - expected) <= exponent_slack(expected));
    const double kernel_bound = ref::ray_distance_power_ladder_float32_bound(expected) + exponent_slack(expected);
    CHECK(std::abs(t[i] - expected) <= kernel_bound);
    worst_ref = std::max(worst_ref, std::abs(ours - expected) / exponent_slack(expected));
    worst_kernel = std::max(worst_kernel, std::abs(t[i] - expected) / kernel_bound);
  }
  MESSAGE("ray distance vs official: reference " << worst_ref << " of its slack, kernel " << worst_kernel
                                                 << " of its bound");
  // The official's own range: s = 1 at its clip, not at far = 1e6.
  CHECK(official_t[per_ray - 1] < 1e5);
  CHECK(std::abs(t[per_ray - 1] - official_t[per_ray - 1]) <= 1e-5 * official_t[per_ray - 1]);
}
