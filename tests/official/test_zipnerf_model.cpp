// One level of our Zip-NeRF model (--model zipnerf: the multisampled grid features, the MLP, the fused activations and
// rendering) against the official camp_zipnerf modules with the same weights on the same cone rays and interval edges
// (fixtures/zipnerf_model.json, written by make_zipnerf_model_vectors.py): the MLP's input features, every interval's
// raw density and colour, and each ray's colour, acc and distance. Our graph draws its own edges (coarse then fine),
// so the stages it runs for a zip_grid level are composed here on the fixture's edges, with the settings our
// configuration gives the zipnerf family. The bound of each value is derived from the official model's per-stage
// sensitivities (zipnerf_bounds below); the downweighting off or a dense level transposed must not match.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "mlp/grid_table.hpp"
#include "mlp/network.hpp"
#include "official_fixtures.hpp"
#include "official_model.hpp"
#include "ops/encode.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/render.hpp"
#include "ops/zip_features.hpp"
#include "support/gemm_backends.hpp"
#include "support/test_context.hpp"
#include "train/config.hpp"
#include "train/model.hpp"

using namespace mipnerf;
using official::flat;
using official::kU;

namespace {

io::Json zip_model_fixture() {
  return official::zipnerf_fixture("zipnerf_model.json");
}

// Our configuration of the fixture's HashEncoding and MLP keywords (camp_zipnerf names → our settings): the zipnerf
// family at the fixture's sizes, cone rays, white background, rendering (no randomized patterns).
train::TrainConfig zip_model_config(const io::Json& fx) {
  const auto& grid = fx.at("grid");
  const auto& m = fx.at("mlp");
  REQUIRE(m.at("net_depth_viewdirs").get<int>() == 1);             // ours: one view-branch layer
  REQUIRE(m.at("bottleneck_width") == m.at("net_width"));          // ours: the bottleneck is the trunk's width
  REQUIRE(m.at("unscented_mip_basis").get<std::string>() == "hexify");
  REQUIRE(fx.at("background").get<std::string>() == "white");
  const int hash_log2 = static_cast<int>(std::lround(std::log2(grid.at("hash_map_size").get<double>())));
  REQUIRE((1 << hash_log2) == grid.at("hash_map_size").get<int>());
  const train::Bundle settings = {{"grid_min", std::to_string(grid.at("min_grid_size").get<int>())},
                                  {"grid_max", std::to_string(grid.at("max_grid_size").get<int>())},
                                  {"grid_supersample", official::setting_text(grid.at("scale_supersample"))},
                                  {"grid_hash_log2", std::to_string(hash_log2)},
                                  {"grid_features", std::to_string(grid.at("num_features").get<int>())},
                                  {"grid_bound", official::setting_text(grid.at("bbox_scaling"))},
                                  {"grid_append_scale", official::setting_text(grid.at("append_scale"))},
                                  {"grid_multisample", "true"},
                                  {"grid_downweight", "true"},
                                  {"mlp_depth", std::to_string(m.at("net_depth").get<int>())},
                                  {"mlp_width", std::to_string(m.at("net_width").get<int>())},
                                  {"view_branch_width", std::to_string(m.at("net_width_viewdirs").get<int>())},
                                  {"view_max_deg", std::to_string(m.at("deg_view").get<int>())},
                                  {"density_bias", official::setting_text(m.at("density_bias"))},
                                  {"rgb_padding", official::setting_text(m.at("rgb_padding"))},
                                  {"ray_shape", "cone"},
                                  {"randomized", "false"},
                                  {"background", "white"}};
  return train::resolve_config("paper", "zipnerf", settings);
}

// The fixture's rays and edges as float32 (they were float32 values).
struct ZipModelRays {
  size_t R = 0, N = 0;
  std::vector<double> origins, directions, radii, viewdirs, t;
};

ZipModelRays zip_model_rays(const io::Json& fx) {
  const auto& r = fx.at("rays");
  ZipModelRays rays;
  rays.R = r.at("radii").size();
  rays.N = r.at("t_edges").at(0).size() - 1;
  rays.origins = flat(r.at("origins"), {rays.R, 3});
  rays.directions = flat(r.at("directions"), {rays.R, 3});
  rays.radii = flat(r.at("radii"), {rays.R});
  rays.viewdirs = flat(r.at("viewdirs"), {rays.R, 3});
  rays.t = flat(r.at("t_edges"), {rays.R, rays.N + 1});
  return rays;
}

// Our grid table from the official HashEncoding's parameters, level by level: a dense level's values[x][y][z][f] is
// our entry (x·N + y)·N + z, a hashed level's values[slot][f] our entry slot (test_grid_encoding.cpp pins both).
// `transpose_dense` (mutation) reads the dense levels as values[z][y][x].
std::vector<float> zip_table(const io::Json& fx, const std::vector<ops::GridLevelLayout>& layout, int features,
                             bool transpose_dense = false) {
  const auto& levels = fx.at("params").at("grid");
  const auto& names = fx.at("grid").at("level_names");
  REQUIRE(levels.size() == layout.size());
  std::vector<float> table;
  for (size_t l = 0; l < layout.size(); ++l) {
    const bool hashed = layout[l].hashed != 0;
    CAPTURE(l);
    REQUIRE(names.at(l).get<std::string>().rfind(hashed ? "hash_" : "grid_", 0) == 0);  // our rule is theirs
    const size_t n = layout[l].grid_size, entries = hashed ? layout[l].table_size : n * n * n;
    const auto values = flat(levels.at(l));
    REQUIRE(values.size() == entries * features);
    for (size_t e = 0; e < entries; ++e) {
      size_t from = e;
      if (transpose_dense && !hashed) from = ((e % n) * n + (e / n) % n) * n + e / (n * n);
      for (int f = 0; f < features; ++f) table.push_back(static_cast<float>(values[from * features + f]));
    }
  }
  return table;
}

// The official MLP's Dense_0 … Dense_4 (trunk, density, bottleneck, view, rgb: flax's creation order in models.MLP)
// in our flat buffer, which has the same order and [in][out] kernels (host/mlp/mlp_config.hpp).
std::vector<float> zip_mlp_params(const io::Json& fx, const mlp::MlpConfig& config) {
  const io::Json mlp_fixture = {{"params", fx.at("params").at("mlp")}};  // model_params reads fx["params"]
  return official::model_params(mlp_fixture, config);
}

// What we compute on the fixture: the features [R·N][L][F + 1], raw outputs [R][N][density, rgb 0..2] and per-ray
// outputs [R][rgb 0..2, acc, distance].
struct ZipLevelRun {
  std::vector<float> features, raw, outputs;
};

struct ZipMutation {
  bool downweight = true;
  bool transpose_dense = false;
};

// The stages Graph::forward_level runs for a zip_grid level (graph.cpp), in its order and with its options, on the
// fixture's edges: level scales and features, the view encoding, the MLP, the fused activations and rendering.
ZipLevelRun run_zip_level(const io::Json& fx, gemm::GemmBackend backend, const ZipMutation& mutation = {}) {
  auto& ctx = test::test_context();
  const auto spec = train::make_graph_spec(zip_model_config(fx), false);
  REQUIRE(spec.grids.size() == 1);
  REQUIRE(spec.mlps.size() == 1);
  const ZipModelRays r = zip_model_rays(fx);
  mlp::GridTable grid(ctx, spec.grids[0]);
  grid.upload_params(zip_table(fx, grid.layout(), spec.grids[0].features, mutation.transpose_dense));
  ops::ZipFeatureOptions zip_options = spec.zip_options(0);
  zip_options.downweight = mutation.downweight;
  ops::ZipFeatures zip(ctx, zip_options);
  ops::RayBundle rays(ctx, r.R);
  rays.origins.upload(ctx, official::as_float(r.origins));
  rays.directions.upload(ctx, official::as_float(r.directions));
  rays.radii.upload(ctx, official::as_float(r.radii));
  rays.viewdirs.upload(ctx, official::as_float(r.viewdirs));
  auto t_edges = official::upload(ctx, official::as_float(r.t), "t_edges [R][N+1]");
  const size_t rows = r.R * r.N, width = spec.mlps[0].input_width, view_width = spec.mlps[0].view_width;
  REQUIRE(width == grid.layout().size() * zip_options.level_width());
  ocl::DeviceArray<float> level_scale(ctx, grid.layout().size(), "level_scale [L]");
  ocl::DeviceArray<float> features(ctx, rows * width, "features [R·N][L][F+1]");
  zip.level_scale({grid.levels(), grid.layout()}, grid.params(), level_scale);
  zip.fwd({rays, t_edges, r.R, r.N}, {grid.levels(), grid.layout()}, grid.params(), level_scale, features);

  ops::Encode encode(ctx, spec.gaussian);
  ocl::DeviceArray<float> view_features(ctx, r.R * view_width, "view_encoding [R][view]");
  encode.pe(spec.view_encoding, {rays.viewdirs, r.R}, view_features);

  auto network = mlp::make_network(ctx, spec.mlps[0], backend);
  network->upload_params(zip_mlp_params(fx, spec.mlps[0]));
  auto ws = network->make_workspace(rows, r.R, mlp::WorkspaceMode::inference);
  ocl::DeviceArray<float> raw_density(ctx, rows, "raw_density [R·N]"), raw_rgb(ctx, rows * 3, "raw_rgb [R·N][3]");
  mlp::MlpInputs in;
  in.features = mlp::view(features, width);
  in.view_encoding = mlp::view(view_features, view_width);
  in.n_rays = r.R;
  in.samples_per_ray = r.N;
  network->forward(in, {mlp::view(raw_density, 1), mlp::view(raw_rgb, 3)}, ws);

  ocl::DeviceArray<float> comp(ctx, r.R * 3, "comp_rgb [R][3]"), acc(ctx, r.R, "acc [R]"),
      distance(ctx, r.R, "distance [R]"), weights(ctx, rows, "weights [R][N]");
  ops::Render(ctx, spec.render, spec.activation)
      .raw_fwd({raw_rgb, raw_density, t_edges, rays, r.R, r.N}, {comp, acc, distance, weights});

  ZipLevelRun run;
  run.features = features.download(ctx);
  const auto density = raw_density.download(ctx), rgb = raw_rgb.download(ctx);
  for (size_t i = 0; i < rows; ++i) run.raw.insert(run.raw.end(), {density[i], rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]});
  const auto c = comp.download(ctx), a = acc.download(ctx), d = distance.download(ctx);
  for (size_t i = 0; i < r.R; ++i) run.outputs.insert(run.outputs.end(), {c[3 * i], c[3 * i + 1], c[3 * i + 2], a[i], d[i]});
  return run;
}

// Each feature's float32 error, as tests/ops/test_zip_features.cpp bounds the kernel against the double reference
// (which test_grid_encoding.cpp pins to the official functions within 1e-12): every multisample's point carries ~64u
// of its largest term's magnitude mag_r = |o| + t_max·|d| + √½·r·t_max, which moves a corner weight by 64u·mag_r·N/box
// on each axis, 24 of those per feature (8 corners, 3 axes), times the level's largest |value|; plus 64u of the value
// for the weights' and the level weight's own roundings; all times precondition. A scale feature: 64u·level_scale·
// precondition. Written as the two stages the fixture's sensitivities use: grid_position (c = 24·64 = 1536,
// m = precondition·max|v_l|·mag_r·N_l/box) and grid_values (c = 64, m = precondition·max|v_l| or
// precondition·level_scale_l); make_zipnerf_model_vectors.py (grid_magnitudes) computes the same m.
struct FeatureMagnitudes {
  std::vector<double> position, values;  // [R][N][L·(F+1)]
};

FeatureMagnitudes feature_magnitudes(const io::Json& fx) {
  const auto& grid = fx.at("grid");
  const int features = grid.at("num_features").get<int>();
  const double precondition = grid.at("precondition_scaling").get<double>();
  const double maxval = grid.at("hash_init_range").get<double>() / precondition;
  const double box = 2 * grid.at("bbox_scaling").get<double>();
  const auto sizes = grid.at("level_sizes").get<std::vector<int>>();
  const ZipModelRays r = zip_model_rays(fx);
  const size_t L = sizes.size(), width = L * (features + 1);
  FeatureMagnitudes m{std::vector<double>(r.R * r.N * width), std::vector<double>(r.R * r.N * width)};
  for (size_t l = 0; l < L; ++l) {
    const auto values = flat(fx.at("params").at("grid").at(l));
    double largest = 0, mean_square = 0;
    for (double v : values) largest = std::max(largest, std::abs(v)), mean_square += v * v / values.size();
    const double level_scale = std::sqrt(maxval * maxval + mean_square);
    for (size_t ray = 0; ray < r.R; ++ray) {
      const double* o = &r.origins[3 * ray];
      const double* d = &r.directions[3 * ray];
      double t_max = 0;
      for (size_t i = 0; i <= r.N; ++i) t_max = std::max(t_max, std::abs(r.t[ray * (r.N + 1) + i]));
      const double mag = std::hypot(o[0], o[1], o[2]) + t_max * std::hypot(d[0], d[1], d[2]) +
                         std::sqrt(0.5) * r.radii[ray] * t_max;
      for (size_t i = 0; i < r.N; ++i) {
        double* position = &m.position[(ray * r.N + i) * width + l * (features + 1)];
        double* value = &m.values[(ray * r.N + i) * width + l * (features + 1)];
        for (int f = 0; f < features; ++f) {
          position[f] = precondition * largest * mag * sizes[l] / box;
          value[f] = precondition * largest;
        }
        value[features] = precondition * level_scale;
      }
    }
  }
  return m;
}

// Σ_s c_s·u·S_s over the fixture's stages (`sens`: stage → values of the shape of `n` outputs), our float32 error
// c_s of each stage: grid_position 1536 and grid_values 64 (above); each dense layer n_in + 2 (× |x|·|W| + |b|: a dot
// product of n_in terms in any order plus the bias); the view PE 8 (pe.json's bound); the density 16 (softplus' own
// rounding and those of raw + bias, × softplus(x) + |x|·sigmoid(x)); the colour 16 (the widened sigmoid, × 1). As in
// official_model.hpp (model_output_bounds), first order: second-order terms are O(u²) of the same sensitivities.
std::vector<double> stage_bounds(const io::Json& sens, const mlp::MlpConfig& config, size_t n) {
  std::vector<std::pair<std::string, double>> constants = {
      {"grid_position", 1536}, {"grid_values", 64}, {"pe", 8}, {"density", 16}, {"rgb", 16}};
  const auto layout = mlp::parameter_layout(config);  // held: all() points into it
  const auto layers = layout.all();
  for (size_t k = 0; k < layers.size(); ++k) {
    constants.push_back({"dense/Dense_" + std::to_string(k), static_cast<double>(layers[k]->in) + 2});
  }
  std::vector<double> bound(n, 0.0);
  for (const auto& entry : constants) {
    const auto& stage = entry.first;  // not a structured binding: clang cannot capture one in doctest's CAPTURE
    const auto c = entry.second;
    CAPTURE(stage);
    REQUIRE(sens.contains(stage));
    const auto s = flat(sens.at(stage));
    REQUIRE(s.size() == n);
    for (size_t i = 0; i < n; ++i) bound[i] += c * kU * s[i];
  }
  REQUIRE(sens.size() == constants.size());  // every stage the fixture measured has its constant here
  return bound;
}

struct ZipBounds {
  std::vector<double> features, raw, outputs;
};

// Plus each ray's own rendering (render.json's bound, as model_output_bounds: W = Σ_i (1 + τ_{i+1})·w_i from the
// fixture): acc (N + 16)u·W + N·u·acc, comp 2·(N + 16)u·W + 2N·u (white: the background term 1 − acc carries acc's
// error too), distance (2(N + 16)u·W/acc + 2N·u)·|distance|. The features' own bound is 1e-12 above the stage's (the
// reference's agreement with the official functions, test_grid_encoding.cpp).
ZipBounds zipnerf_bounds(const io::Json& fx, const mlp::MlpConfig& config) {
  const auto& sens = fx.at("sensitivities");
  const ZipModelRays r = zip_model_rays(fx);
  ZipBounds b;
  const FeatureMagnitudes m = feature_magnitudes(fx);
  for (size_t i = 0; i < m.position.size(); ++i) b.features.push_back(kU * (1536 * m.position[i] + 64 * m.values[i]) + 1e-12);
  b.raw = stage_bounds(sens.at("raw"), config, r.R * r.N * 4);
  b.outputs = stage_bounds(sens.at("outputs"), config, r.R * 5);
  const auto values = flat(fx.at("outputs"), {r.R, 5});
  const auto weight_sums = flat(sens.at("render_weight_sums"), {r.R});
  const double n = static_cast<double>(r.N);
  for (size_t ray = 0; ray < r.R; ++ray) {
    double* o = &b.outputs[5 * ray];
    const double* v = &values[5 * ray];
    const double w = (n + 16) * kU * weight_sums[ray];
    for (int k = 0; k < 3; ++k) o[k] += 2 * w + 2 * n * kU;
    o[3] += w + n * kU * v[3];
    o[4] += (2 * w / v[3] + 2 * n * kU) * std::abs(v[4]);
  }
  return b;
}

}  // namespace

TEST_CASE("zipnerf model: one level on given edges renders the official grid, MLP and volumetric_rendering's output") {
  const io::Json fx = zip_model_fixture();
  const auto spec = train::make_graph_spec(zip_model_config(fx), false);
  // Our configuration gives the fixture's grid and multisample settings (else the comparison would test another model).
  CHECK(mlp::grid_level_sizes(spec.grids[0]) == fx.at("grid").at("level_sizes").get<std::vector<int>>());
  CHECK(spec.zip.scale_mult == doctest::Approx(fx.at("mlp").at("unscented_scale_mult").get<double>()));
  CHECK(spec.grids[0].precondition == doctest::Approx(fx.at("grid").at("precondition_scaling").get<double>()));
  CHECK(spec.grids[0].init_range == doctest::Approx(fx.at("grid").at("hash_init_range").get<double>()));
  CHECK(spec.zip_options(0).box_min[0] == doctest::Approx(-fx.at("grid").at("bbox_scaling").get<double>()));
  const ZipBounds bound = zipnerf_bounds(fx, spec.mlps[0]);
  const auto features = flat(fx.at("features")), raw = flat(fx.at("raw")), outputs = flat(fx.at("outputs"));
  for (const auto backend : test::supported_gemm_backends(test::test_context())) {
    const std::string backend_name = enum_name(backend);
    CAPTURE(backend_name);
    const ZipLevelRun ours = run_zip_level(fx, backend);
    OFFICIAL_CHECK_AGREES("features [R][N][L][F+1]", ours.features, features,
                          [&](size_t i) { return bound.features[i]; });
    OFFICIAL_CHECK_AGREES("raw [R][N][density, rgb]", ours.raw, raw, [&](size_t i) { return bound.raw[i]; });
    OFFICIAL_CHECK_AGREES("outputs [R][rgb, acc, distance]", ours.outputs, outputs,
                          [&](size_t i) { return bound.outputs[i]; });
  }
}

TEST_CASE("zipnerf model: without the downweighting, or with a dense level read [z][y][x], it does not match") {
  const io::Json fx = zip_model_fixture();
  const auto spec = train::make_graph_spec(zip_model_config(fx), false);
  const ZipBounds bound = zipnerf_bounds(fx, spec.mlps[0]);
  const auto raw = flat(fx.at("raw")), outputs = flat(fx.at("outputs"));
  const auto backend = test::supported_gemm_backends(test::test_context()).front();
  const auto raw_bound = [&](size_t i) { return bound.raw[i]; };
  const auto output_bound = [&](size_t i) { return bound.outputs[i]; };
  // Wide rays' fine levels at full weight, and the scale features at 2·1 − 1 = 1: raw densities move by O(0.1).
  const ZipLevelRun plain = run_zip_level(fx, backend, {false, false});
  OFFICIAL_CHECK_DISAGREES("raw without the downweighting", plain.raw, raw, 100.0, raw_bound);
  OFFICIAL_CHECK_DISAGREES("outputs without the downweighting", plain.outputs, outputs, 100.0, output_bound);
  // The dense levels' cells at their mirror images about the diagonal: other features everywhere off it.
  const ZipLevelRun transposed = run_zip_level(fx, backend, {true, true});
  OFFICIAL_CHECK_DISAGREES("raw with dense levels transposed", transposed.raw, raw, 100.0, raw_bound);
  OFFICIAL_CHECK_DISAGREES("outputs with dense levels transposed", transposed.outputs, outputs, 100.0, output_bound);
}

// Our distance is mip-NeRF's E[t_mid] (kernels/render.cl); the official Zip-NeRF's distance_mean is exp(E[log t_mid]),
// a geometric mean, so by Jensen's inequality never above it. The fixture's "distance" is mip-NeRF's formula on the
// official weights (what the test above compares); here: that it is not the official distance_mean, so the
// difference stays a known one (tests/official/README.md) rather than a silent one.
TEST_CASE("zipnerf model: our distance is mip-NeRF's mean depth, not the official log-space distance_mean") {
  const io::Json fx = zip_model_fixture();
  const auto spec = train::make_graph_spec(zip_model_config(fx), false);
  const ZipBounds bound = zipnerf_bounds(fx, spec.mlps[0]);
  const auto outputs = flat(fx.at("outputs")), distance_mean = flat(fx.at("distance_mean"));
  const size_t R = distance_mean.size();
  const ZipLevelRun ours = run_zip_level(fx, test::supported_gemm_backends(test::test_context()).front());
  std::vector<float> our_distance;
  for (size_t r = 0; r < R; ++r) {
    CAPTURE(r);
    our_distance.push_back(ours.outputs[5 * r + 4]);
    CHECK(distance_mean[r] <= outputs[5 * r + 4] * (1 + 1e-12));  // Jensen: geometric ≤ arithmetic
  }
  OFFICIAL_CHECK_DISAGREES("our distance against distance_mean", our_distance, distance_mean, 10.0,
                           [&](size_t r) { return bound.outputs[5 * r + 4]; });
}
