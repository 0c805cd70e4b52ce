// Our whole model (the host graph: rays, sampling, resampling, IPE, the MLP, activations and rendering, coarse and
// fine) against the official MipNerfModel's own outputs with the same weights (tests/official/fixtures/model.json and
// noise.json, written by make_vectors.py / model_vectors.py from google/mipnerf): every level's colour, accumulation
// and distance on 16 rays of the multiscale scene of multicam.json, deterministic and with llff.gin's density noise and
// randomized sampling given our draws. The bound of each output is derived from the official model's own per-stage
// sensitivities (official_model.hpp, model_output_bounds); changed conventions (concatenation orders, density_bias,
// background, no noise, no rgb_padding) must not match.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "official_fixtures.hpp"
#include "official_model.hpp"
#include "ops/render.hpp"
#include "support/gemm_backends.hpp"

using namespace mipnerf;
using official::flat;
using official::kU;

namespace {

// Our graph's rendering of the batch (inference: deterministic sampling, no noise), every level's colour.
std::vector<float> render_model(const io::Json& fx, gemm::GemmBackend backend, const train::Bundle& overrides = {},
                                const std::string& swap_rows = "") {
  auto& ctx = test::test_context();
  official::ModelBatch batch(fx);
  const auto config = official::model_config(fx, false, overrides);
  const auto spec = train::make_graph_spec(config, true);
  REQUIRE(spec.mlps.size() == 1);  // one MLP for both levels, as MipNerfModel
  auto network = mlp::make_network(ctx, spec.mlps[0], backend);
  network->upload_params(official::model_params(fx, spec.mlps[0], swap_rows));
  graph::Graph graph(ctx, spec, {network.get()}, graph::GraphMode::inference, batch.n_rays);
  graph.set_every_level_colour(true);
  graph.render_chunk(batch.source(), {0, batch.n_rays});
  return official::level_outputs(graph, spec.levels.size(), batch.n_rays);
}

}  // namespace

TEST_CASE("MipNerfModel: our graph renders the official model's coarse and fine colour, acc and distance") {
  const auto fx = official::fixture("model.json");
  const auto expected = flat(fx.at("outputs"));
  const auto config = official::model_config(fx, false);
  const auto bound = official::model_output_bounds(fx, train::make_graph_spec(config, true).mlps[0]);
  for (const auto backend : test::supported_gemm_backends(test::test_context())) {
    const std::string backend_name = enum_name(backend);
    CAPTURE(backend_name);
    OFFICIAL_CHECK_AGREES("outputs [level][ray][rgb, acc, distance]", render_model(fx, backend), expected,
                          [&](size_t i) { return bound[i]; });
  }
}

TEST_CASE("MipNerfModel: other concatenation orders, density_bias 0 or a black background do not match the official") {
  const auto fx = official::fixture("model.json");
  const auto expected = flat(fx.at("outputs"));
  const auto config = official::model_config(fx, false);
  const auto bound = official::model_output_bounds(fx, train::make_graph_spec(config, true).mlps[0]);
  const auto backend = test::supported_gemm_backends(test::test_context()).front();
  const auto bound_at = [&](size_t i) { return bound[i]; };
  // The skip layer reading [features | activation] and the view layer [view encoding | bottleneck]: the same weights
  // multiply other inputs, the outputs move by O(0.1) against bounds of ~1e-4.
  OFFICIAL_CHECK_DISAGREES("skip concatenated the other way", render_model(fx, backend, {}, "skip"), expected, 100.0,
                           bound_at);
  OFFICIAL_CHECK_DISAGREES("view branch concatenated the other way", render_model(fx, backend, {}, "view"), expected,
                           100.0, bound_at);
  // softplus(x) for softplus(x − 1): every density about doubles.
  OFFICIAL_CHECK_DISAGREES("density_bias 0", render_model(fx, backend, {{"density_bias", "0"}}), expected, 100.0,
                           bound_at);
  // 1 − acc ≈ 0.3 of white missing from every colour.
  OFFICIAL_CHECK_DISAGREES("black background", render_model(fx, backend, {{"background", "black"}}), expected, 100.0,
                           bound_at);
}

namespace {

// Our training graph's forward of the noisy randomized model (noise.json): one chunk, step and seed of the fixture's
// key, so the stratified, resampling and noise draws are the ones the official model was given.
std::vector<float> noisy_model(const io::Json& fx, double density_noise) {
  auto& ctx = test::test_context();
  official::ModelBatch batch(fx);
  const auto config = official::model_config(fx, true, {{"density_noise", official::setting_text(density_noise)}});
  const auto spec = train::make_graph_spec(config, true);
  auto network = mlp::make_network(ctx, spec.mlps[0], test::supported_gemm_backends(ctx).front());
  network->upload_params(official::model_params(official::fixture("model.json"), spec.mlps[0]));
  graph::Graph graph(ctx, spec, {network.get()}, graph::GraphMode::training, batch.n_rays, batch.n_rays);
  const auto& key = fx.at("key");
  REQUIRE(key.at("first_ray").get<uint32_t>() == 0);  // batch ray r is fixture ray r
  graph.begin_step(batch.n_rays, batch.lossmult_sum());
  graph.train_chunk(batch.source(), {0, batch.n_rays}, {*batch.target_dev, batch.lossmult_dev.get()},
                    {key.at("seed").get<uint64_t>(), key.at("step").get<uint32_t>()});
  graph.end_step();
  return official::level_outputs(graph, spec.levels.size(), batch.n_rays);
}

// The official model was given these draws; they must be ours for the fixture's key: the uniforms exactly
// (rng_uniform4: level 0 stratified, level 1 resampling), the normals to double rounding (rng_normal4 of the level).
void check_noise_draws_are_ours(const io::Json& fx) {
  const auto& key = fx.at("key");
  const uint64_t seed = key.at("seed").get<uint64_t>();
  const uint32_t step = key.at("step").get<uint32_t>(), first = key.at("first_ray").get<uint32_t>();
  size_t mismatches = 0;
  for (uint32_t level = 0; level < 2; ++level) {
    const auto& xi = fx.at("xi").at(level);
    const auto& z = fx.at("z").at(level);
    for (uint32_t r = 0; r < xi.size(); ++r) {
      for (uint32_t j = 0; j < xi.at(r).size(); ++j) {
        const uint32_t stream = level == 0 ? rng_stream_stratified : rng_stream_resample;
        const float u = rng_uniform4(seed, first + r, step, j / 4, stream)[j % 4];
        if (static_cast<double>(u) != xi.at(r).at(j).get<double>()) ++mismatches;
      }
      for (uint32_t i = 0; i < z.at(r).size(); ++i) {
        const double ours = rng_normal4(seed, first + r, step, (level << 24) + i / 4, rng_stream_density_noise)[i % 4];
        const double theirs = z.at(r).at(i).get<double>();
        if (std::abs(ours - theirs) > 1e-14 * (1 + std::abs(theirs))) ++mismatches;
      }
    }
  }
  INFO("the fixture's draws are not our Philox draws for its key: regenerate with make_vectors.py");
  REQUIRE(mismatches == 0);
}

}  // namespace

// The official model with llff.gin's density_noise = 1 while randomized (models.py: raw_density += noise·N(0, 1) before
// softplus(x + density_bias)), given our draws: our training graph's forward (stratified sampling, resampling and the
// fused render's noise keyed by seed, step and batch ray) must give every level's colour, acc and distance.
TEST_CASE("density noise: our training graph's noisy randomized forward is the official noisy model's output") {
  const auto fx = official::fixture("noise.json");
  check_noise_draws_are_ours(fx);
  REQUIRE(fx.at("model").at("density_noise").get<double>() == 1.0);
  const auto expected = flat(fx.at("outputs"));
  const auto config = official::model_config(fx, true);
  const auto bound = official::model_output_bounds(fx, train::make_graph_spec(config, true).mlps[0]);
  OFFICIAL_CHECK_AGREES("noisy outputs [level][ray][rgb, acc, distance]", noisy_model(fx, 1.0), expected,
                        [&](size_t i) { return bound[i]; });
  // The same randomized step without the noise: densities off by softplus(x + z) against softplus(x).
  OFFICIAL_CHECK_DISAGREES("outputs without the noise", noisy_model(fx, 0.0), expected, 100.0,
                           [&](size_t i) { return bound[i]; });
}

namespace {

// One level of noise.json at the stage: the official model's raw MLP outputs, edges and ray directions (float64,
// rounded to float32 for our kernel) through our fused activations + noise + render.
struct NoisyLevel {
  size_t R = 0, N = 0;
  std::vector<double> raw_rgb, raw_density, t, dirs, z, weights, acc, comp;
};

NoisyLevel noisy_level(const io::Json& fx, const io::Json& model_fx, size_t level) {
  NoisyLevel c;
  const auto& in = fx.at("levels").at(level);
  c.R = in.at("raw_density").size();
  c.N = in.at("raw_density").at(0).size();
  c.raw_rgb = flat(in.at("raw_rgb"), {c.R, c.N, 3});
  c.raw_density = flat(in.at("raw_density"), {c.R, c.N});
  c.t = flat(in.at("t_vals"), {c.R, c.N + 1});
  c.z = flat(fx.at("z").at(level), {c.R, c.N});
  c.weights = flat(in.at("weights"), {c.R, c.N});
  c.acc = flat(in.at("acc"), {c.R});
  c.comp = flat(in.at("comp_rgb"), {c.R, 3});
  // The rays' directions: multicam.json's official rays at the batch's pixels.
  const auto mc = official::fixture("multicam.json").at("outputs");
  std::vector<double> all;
  for (const auto& image : mc) {
    const auto d = flat(image.at("directions"));
    all.insert(all.end(), d.begin(), d.end());
  }
  for (const auto& index : model_fx.at("rays").at("multicam_pixels")) {
    for (int a = 0; a < 3; ++a) c.dirs.push_back(all[3 * index.get<size_t>() + a]);
  }
  return c;
}

struct NoisyRender {
  std::vector<float> weights, acc, comp;
};

NoisyRender render_noisy_level(const NoisyLevel& c, const DensityNoiseKey& key, const RenderOptions& options,
                               const ActivationOptions& activation) {
  auto& ctx = test::test_context();
  ops::RayBundle rays(ctx, c.R);
  rays.directions.upload(ctx, official::as_float(c.dirs));
  auto raw_rgb = official::upload(ctx, official::as_float(c.raw_rgb), "raw_rgb [R][N][3]");
  auto raw_density = official::upload(ctx, official::as_float(c.raw_density), "raw_density [R][N]");
  auto t = official::upload(ctx, official::as_float(c.t), "t_edges [R][N+1]");
  ocl::DeviceArray<float> comp(ctx, c.R * 3, "comp_rgb [R][3]"), acc(ctx, c.R, "acc [R]"),
      distance(ctx, c.R, "distance [R]"), weights(ctx, c.R * c.N, "weights [R][N]");
  ops::Render(ctx, options, activation)
      .raw_fwd({raw_rgb, raw_density, t, rays, c.R, c.N}, {comp, acc, distance, weights}, key);
  return {weights.download(ctx), acc.download(ctx), comp.download(ctx)};
}

}  // namespace

// The density noise at the stage, with the official model's own values (noise.json's levels): its raw MLP outputs,
// edges and the draws it was given, through our fused render with DENSITY_NOISE, against the official level's
// weights, acc and composite. Also: without the noise, without rgb_padding, or with density_bias 0 it must not match.
TEST_CASE("density noise: our fused render with noise 1 is the official noisy model's level, from its raw outputs") {
  const auto fx = official::fixture("noise.json");
  const auto model_fx = official::fixture("model.json");
  check_noise_draws_are_ours(fx);
  const auto& key_json = fx.at("key");
  const double density_bias = fx.at("model").at("density_bias").get<double>();
  const double rgb_padding = fx.at("model").at("rgb_padding").get<double>();
  const auto sigmoid = [](double x) { return 1.0 / (1.0 + std::exp(-x)); };
  for (uint32_t level = 0; level < 2; ++level) {
    CAPTURE(level);
    const auto c = noisy_level(fx, model_fx, level);
    const DensityNoiseKey key{{key_json.at("seed").get<uint64_t>(), key_json.at("step").get<uint32_t>(),
                               key_json.at("first_ray").get<uint32_t>()},
                              level};
    RenderOptions options;
    options.background = Background::white;
    options.density_noise = 1.0f;
    ActivationOptions activation;
    activation.density_bias = static_cast<float>(density_bias);
    activation.rgb_padding = static_cast<float>(rgb_padding);
    const auto ours = render_noisy_level(c, key, options, activation);

    // The bound of weight i (as render.json's, with the densities' and the intervals' errors carried through the
    // transmittance): (N + 16)·u·(1 + τ_{i+1}) for the rendering itself, plus ε_i + Σ_{j<i} ε_j·s_j where ε_j is the
    // relative error of s_j = σ_j·δ_j on our side: the density's (the draw within 36u·|z|, our float32 inputs'
    // rounding u·|raw|, the sums raw + z and + bias u each, times softplus'/softplus = sigmoid/softplus; softplus
    // itself 12u) and the interval's (the edges rounded to float32, u·(|t_j| + |t_{j+1}|)/Δt_j, and |d| from the
    // rounded direction, u). ∂ln w_i/∂ln s_i ≤ 1 and ∂ln w_i/∂ln s_j = −s_j for j < i.
    std::vector<double> weight_bound(c.R * c.N), ray_weight_bound(c.R, 0.0);
    for (size_t r = 0; r < c.R; ++r) {
      const double norm = std::sqrt(c.dirs[3 * r] * c.dirs[3 * r] + c.dirs[3 * r + 1] * c.dirs[3 * r + 1] +
                                    c.dirs[3 * r + 2] * c.dirs[3 * r + 2]);
      double tau = 0, earlier = 0;
      for (size_t i = 0; i < c.N; ++i) {
        const size_t at = r * c.N + i;
        const double noisy = c.raw_density[at] + c.z[at], x = noisy + density_bias;
        const double density = std::log1p(std::exp(x));
        const double t0 = c.t[r * (c.N + 1) + i], t1 = c.t[r * (c.N + 1) + i + 1];
        const double s = density * (t1 - t0) * norm;
        const double eps_density =
            (36 * kU * std::abs(c.z[at]) + kU * std::abs(c.raw_density[at]) + kU * std::abs(noisy) + kU * std::abs(x)) *
                sigmoid(x) / density +
            12 * kU;
        const double eps_interval = t1 > t0 ? kU * (std::abs(t0) + std::abs(t1)) / (t1 - t0) + kU : 0.0;
        const double eps = eps_density + eps_interval;
        tau += s;
        weight_bound[at] = ((static_cast<double>(c.N) + 16) * kU * (1 + tau) + eps + earlier) * c.weights[at];
        earlier += eps * s;
        ray_weight_bound[r] += weight_bound[at];
      }
    }
    OFFICIAL_CHECK_AGREES("noisy weights", ours.weights, c.weights, [&](size_t i) { return weight_bound[i] + 1e-30; });
    OFFICIAL_CHECK_AGREES("noisy acc", ours.acc, c.acc,
                          [&](size_t r) { return ray_weight_bound[r] + c.N * kU * c.acc[r] + 1e-30; });
    // comp_c = Σ w_i·c_i + (1 − Σ w_i) in our kernel (the white background from the same float weights): a weight's
    // error moves it by δw_i·(c_i − 1), |c_i − 1| ≤ 1 + ε, the official colour of the sample (models.py's widened
    // sigmoid of the official raw output, computed here for the bound only); plus the colours' own error w_i·(16u
    // for the widened sigmoid + u·|raw|/4 for our float32 input: sigmoid' ≤ ¼) and 2N·u of the two sums.
    std::vector<double> comp_error(c.R * 3, 2 * c.N * kU);
    for (size_t at = 0; at < c.R * c.N; ++at) {
      for (size_t ch = 0; ch < 3; ++ch) {
        const double raw = c.raw_rgb[3 * at + ch];
        const double colour = sigmoid(raw) * (1 + 2 * rgb_padding) - rgb_padding;
        comp_error[3 * (at / c.N) + ch] +=
            weight_bound[at] * std::abs(colour - 1) + c.weights[at] * (16 * kU + kU * std::abs(raw) / 4);
      }
    }
    const auto comp_bound = [&](size_t i) { return comp_error[i]; };
    OFFICIAL_CHECK_AGREES("noisy comp_rgb", ours.comp, c.comp, comp_bound);

    // Changed conventions must not match. Without the noise (DENSITY_NOISE off): every density moves.
    RenderOptions quiet = options;
    quiet.density_noise = 0.0f;
    OFFICIAL_CHECK_DISAGREES("weights without the noise", render_noisy_level(c, key, quiet, activation).weights,
                             c.weights, 100.0, [&](size_t i) { return weight_bound[i] + 1e-30; });
    // softplus(x) for softplus(x − 1).
    ActivationOptions no_bias = activation;
    no_bias.density_bias = 0.0f;
    OFFICIAL_CHECK_DISAGREES("weights with density_bias 0", render_noisy_level(c, key, options, no_bias).weights,
                             c.weights, 100.0, [&](size_t i) { return weight_bound[i] + 1e-30; });
    // sigmoid for (1 + 2ε)·sigmoid − ε: the colours move by ε·|2·sigmoid − 1| ≤ 0.001, saturated ones most.
    ActivationOptions no_padding = activation;
    no_padding.rgb_padding = 0.0f;
    OFFICIAL_CHECK_DISAGREES("comp_rgb without rgb_padding", render_noisy_level(c, key, options, no_padding).comp,
                             c.comp, 100.0, comp_bound);
  }
}
