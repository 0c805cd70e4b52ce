// TrainConfig → GraphSpec (the levels and options of mip-NeRF, the NeRF baseline and the ablations), the
// networks, and the data-loading options.
#include "train/model.hpp"

#include "data/formats/formats.hpp"

namespace mipnerf::train {
namespace {

EncodingOptions position_encoding(const TrainConfig& c) {
  EncodingOptions e;
  e.min_deg = c.pos_min_deg;
  e.max_deg = c.pos_max_deg;
  e.append_identity = c.pos_identity;
  e.covariance_degrees = c.cov_max_deg;
  return e;
}

// The networks' shared shape; input width follows the level's encoding.
mlp::MlpConfig network(const TrainConfig& c, size_t input_width, size_t index) {
  mlp::MlpConfig m;
  m.input_width = input_width;
  m.depth = static_cast<size_t>(c.mlp_depth);
  m.width = static_cast<size_t>(c.mlp_width);
  // The official rule concatenates after trunk layer i when i % skip == 0 and i > 0; a skip at or past the
  // last layer means none (MlpConfig: 0).
  m.skip_layer = c.mlp_skip > 0 && c.mlp_skip < c.mlp_depth - 1 ? static_cast<size_t>(c.mlp_skip) : 0;
  m.view_dependence = c.view_dependence;
  m.view_width = static_cast<size_t>(3 + 6 * c.view_max_deg);
  m.view_branch_width = static_cast<size_t>(c.view_branch_width);
  m.bottleneck_width = static_cast<size_t>(c.bottleneck_width > 0 ? c.bottleneck_width : c.mlp_width);
  m.seed = c.seed + 0x9E3779B97F4A7C15ull * (index + 1);  // distinct weights per network
  m.weight_init = c.weight_init;
  return m;
}

// Zip-NeRF's grid of a configuration (the seed apart from the networks').
mlp::GridConfig grid_config(const TrainConfig& c) {
  mlp::GridConfig g;
  g.min_grid_size = c.grid_min;
  g.max_grid_size = c.grid_max;
  g.scale_supersample = c.grid_supersample;
  g.hash_table_size = uint32_t{1} << c.grid_hash_log2;
  g.features = c.grid_features;
  g.seed = c.seed ^ 0x5A49504E45524647ull;  // "ZIPNERFG"
  return g;
}

// The grid's cube: [−b, b]³, b from the setting or the scene (NDC space spans [−1, 1]³; a Blender object fits in
// [−1.5, 1.5]³; an unbounded scene is contracted into the ball of radius 2).
void set_grid_box(const TrainConfig& c, ops::ZipFeatureOptions& zip) {
  const double bound = c.grid_bound > 0             ? c.grid_bound
                       : c.unbounded                   ? 2.0  // the contraction's ball of radius 2
                       : c.ray_shape == RayShape::cylinder ? 1.0
                                                           : 1.5;
  for (float& m : zip.box_min) m = static_cast<float>(-bound);
  zip.box_size = static_cast<float>(2 * bound);
}

// The blur half-width (normalised s) of proposal round `round` of `rounds`: the official's (0.03, 0.003) for its two
// rounds (camp_zipnerf configs/zipnerf/360.gin spline_interlevel_params blurs), the finer one for the round before the
// NeRF level and the coarser one for every earlier round.
float proposal_blur_halfwidth(int round, int rounds) { return round + 1 == rounds ? 0.003f : 0.03f; }

// The interlevel loss weight of each proposal round: the setting, or (negative: automatic) the official of the model
// family's loss: Zip-NeRF's spline loss 0.01 (camp_zipnerf 360.gin), mip-NeRF 360's outer loss 1 (multinerf
// Config.interlevel_loss_mult).
float proposal_interlevel_mult(const TrainConfig& c) {
  if (c.interlevel_mult >= 0) return static_cast<float>(c.interlevel_mult);
  return c.variant == ModelFamily::zipnerf ? 0.01f : 1.0f;
}

// The dilation of proposal level `l` ≥ 1 after levels drawing `samples_before` intervals in all (their product): the
// settings, or (negative: automatic) the official of the model family (multinerf Model: 0.0025 + 0.5 / that product;
// camp_zipnerf: none).
float proposal_dilation(const TrainConfig& c, double samples_before) {
  const bool zipnerf = c.variant == ModelFamily::zipnerf;
  const double bias = c.dilation_bias >= 0 ? c.dilation_bias : zipnerf ? 0.0 : 0.0025;
  const double mult = c.dilation_mult >= 0 ? c.dilation_mult : zipnerf ? 0.0 : 0.5;
  return static_cast<float>(bias + mult / samples_before);
}

// A mip-NeRF 360 proposal round's network (official PropMLP: net_depth 4, net_width 256, disable_rgb): the IPE in, the
// skip rule of the NeRF's (none within 4 layers), density only.
mlp::MlpConfig proposal_mlp(const TrainConfig& c, size_t input_width, size_t index) {
  mlp::MlpConfig m = network(c, input_width, index);
  m.depth = static_cast<size_t>(c.proposal_mlp_depth);
  m.width = static_cast<size_t>(c.proposal_mlp_width);
  m.skip_layer = c.mlp_skip > 0 && c.mlp_skip < c.proposal_mlp_depth - 1 ? static_cast<size_t>(c.mlp_skip) : 0;
  m.bottleneck_width = m.width;
  m.view_dependence = false;
  return m;
}

// The proposal pipeline (sampler = proposal; official Model.__call__ of camp_zipnerf 360.gin's sampling_strategy, or
// of multinerf's mip-NeRF 360): levels 0 .. K−1 are the proposal rounds, level K the NeRF level; every level samples
// by proposal, the first from the whole ray.
//   Zip-NeRF: round i has grid i (1 feature a level, finest proposal_grid_max / 4^(K−1−i)) and a density-only network
//   i of the tiny MLP's shape; the NeRF level grid K (the grid_* settings) and network K; the spline interlevel loss.
//   mip-NeRF: every level encodes its frustums by IPE (unbounded: mip-NeRF 360's IPE of contracted frustums); round i
//   has a density-only network of proposal_mlp_depth × proposal_mlp_width, the NeRF level the mip-NeRF MLP; the outer
//   interlevel loss (mip-NeRF 360 eq. 13).
void add_proposal_levels(const TrainConfig& c, graph::GraphSpec& spec) {
  const int rounds = c.proposal_rounds;
  const bool grids = c.variant == ModelFamily::zipnerf;
  spec.basis_tessellation = c.basis_subdivisions;  // before the networks: it sets a contracted IPE's width
  spec.grids.clear();
  for (int round = 0; grids && round < rounds; ++round) {
    mlp::GridConfig grid = grid_config(c);
    grid.features = 1;  // official: "no need for >1 features in the proposal NGPs, the output is 1d"
    grid.max_grid_size = proposal_round_grid_max(c, round);
    grid.seed = grid.seed + 0x9E3779B97F4A7C15ull * static_cast<uint64_t>(round + 1);
    spec.grids.push_back(grid);
  }
  if (grids) spec.grids.push_back(grid_config(c));
  double samples_before = 1.0;  // the product of the earlier levels' samples (official prod_num_samples)
  for (int l = 0; l <= rounds; ++l) {
    graph::LevelSpec level;
    level.sampling = graph::Sampling::proposal;
    if (l > 0) level.dilation = proposal_dilation(c, samples_before);
    level.encoding = grids         ? graph::Encoding::zip_grid
                     : c.unbounded ? graph::Encoding::contracted_ipe
                                   : graph::Encoding::integrated;
    level.grid_index = grids ? static_cast<size_t>(l) : 0;
    // multinerf's mip-NeRF 360 calls one PropMLP in every round (proposal_mlp_shared): network 0 for the rounds, 1 for
    // the NeRF level; otherwise one network a level.
    const bool shared = !grids && c.proposal_mlp_shared;
    level.mlp_index = shared ? (l < rounds ? 0 : 1) : static_cast<size_t>(l);
    if (l < rounds) {
      level.role = graph::LevelRole::proposal;
      level.new_samples = static_cast<size_t>(c.proposal_samples);
      level.interlevel.kind = grids ? ops::InterlevelKind::spline : ops::InterlevelKind::outer;
      level.interlevel.blur_halfwidth = proposal_blur_halfwidth(l, rounds);
      level.interlevel.mult = proposal_interlevel_mult(c);
    } else {
      level.new_samples = static_cast<size_t>(c.num_samples);
      level.distortion_mult = static_cast<float>(c.distortion_mult);
    }
    samples_before *= static_cast<double>(level.new_samples);
    spec.levels.push_back(level);
    if (level.mlp_index < spec.mlps.size()) continue;  // a shared proposal network, made by the first round
    const size_t input_width = spec.feature_width(level), index = level.mlp_index;
    mlp::MlpConfig m = grids || l == rounds ? network(c, input_width, index) : proposal_mlp(c, input_width, index);
    // A proposal round's network: its trunk and density, no colour to condition (official disable_rgb).
    if (l < rounds) m.view_dependence = false;
    spec.mlps.push_back(m);
  }
  // Official Model defaults: resample_padding 0, single_jitter, the domain [init_s_near, init_s_far] = [0, 1].
  spec.sample_intervals.resample_padding = 0.0f;
  spec.sample_intervals.single_jitter = true;
  spec.sample_intervals.randomized = c.randomized;
  spec.anneal_slope = static_cast<float>(c.anneal_slope);
  spec.ray_distance = !c.unbounded ? RayDistance::linear : grids ? RayDistance::power_ladder : RayDistance::reciprocal;
}

}  // namespace

graph::GraphSpec make_graph_spec(const TrainConfig& c, bool multiscale_data) {
  graph::GraphSpec spec;
  const bool nerf = c.variant == ModelFamily::nerf;
  spec.position_encoding = position_encoding(c);
  spec.view_encoding.min_deg = 0;
  spec.view_encoding.max_deg = c.view_max_deg;
  spec.view_encoding.append_identity = true;

  const bool zipnerf = c.variant == ModelFamily::zipnerf;
  if (zipnerf) {
    spec.grids.push_back(grid_config(c));
    spec.zip.multisample = c.grid_multisample;
    spec.zip.downweight = c.grid_downweight;
    spec.zip.append_scale = c.grid_append_scale;
    spec.zip.scale_mult = static_cast<float>(c.grid_scale_mult);
    spec.zip.cylinder = c.ray_shape == RayShape::cylinder;
    spec.zip.randomized = c.randomized;
    spec.zip.contract = c.unbounded;
    set_grid_box(c, spec.zip);
    spec.grid_weight_decay = static_cast<float>(c.grid_weight_decay);
  }
  const graph::Encoding encoding = zipnerf                 ? graph::Encoding::zip_grid
                                   : nerf                  ? graph::Encoding::midpoint_pe
                                   : c.integrated_encoding ? graph::Encoding::integrated
                                   : c.cov_max_deg > 0     ? graph::Encoding::concat_pe
                                                           : graph::Encoding::frustum_mean_pe;
  graph::LevelSpec encoded;
  encoded.encoding = encoding;
  const size_t input_width = spec.feature_width(encoded);
  const bool proposal = c.sampler == Sampler::proposal;
  if (proposal) add_proposal_levels(c, spec);
  for (int l = 0; l < (proposal ? 0 : c.num_levels); ++l) {
    graph::LevelSpec level;
    const bool first = l == 0, last = l == c.num_levels - 1;
    if (nerf) {
      // NeRF: num_samples/2 coarse points, then num_samples more drawn and merged with them (64 + 128).
      level.sampling = first ? graph::Sampling::stratified : graph::Sampling::resample_union;
      level.new_samples = static_cast<size_t>(first ? c.num_samples / 2 : c.num_samples);
    } else {
      level.sampling = first ? graph::Sampling::stratified : graph::Sampling::resample;
      level.new_samples = static_cast<size_t>(c.num_samples);
    }
    level.encoding = encoding;
    level.mlp_index = c.single_mlp ? 0 : static_cast<size_t>(l);
    level.loss_weight = last ? 1.0f : static_cast<float>(c.coarse_loss_mult);
    spec.levels.push_back(level);
  }
  const size_t n_networks = proposal ? 0 : c.single_mlp ? 1 : static_cast<size_t>(c.num_levels);
  for (size_t i = 0; i < n_networks; ++i) spec.mlps.push_back(network(c, input_width, i));

  spec.rays.ray_shape = c.ray_shape;
  spec.rays.pixel_center_offset = static_cast<float>(c.pixel_center);
  spec.rays.jitter_subpixel = c.jitter_pixels;  // training only: rendering decides its own supersampling
  spec.rays.view_dependence = c.view_dependence;
  spec.rays.unit_viewdirs = c.unit_viewdirs;
  if (c.ray_shape == RayShape::cylinder && c.ndc_projection[0] > 0.0) {
    spec.rays.ndc_scale_x = static_cast<float>(c.ndc_projection[0]);
    spec.rays.ndc_scale_y = static_cast<float>(c.ndc_projection[1]);
  }
  spec.gaussian.ray_shape = spec.rays.ray_shape;
  spec.sample.lindisp = c.lindisp;
  spec.sample.randomized = c.randomized;
  spec.resample.padding = static_cast<float>(c.resample_padding);
  spec.resample.blur = c.resample_blur;
  spec.resample.randomized = c.randomized;
  spec.activation.density = c.density_activation;
  spec.activation.density_bias = static_cast<float>(c.density_bias);
  spec.activation.rgb_padding = static_cast<float>(c.rgb_padding);
  spec.render.background = c.background;
  spec.render.opaque_background = c.opaque_background;
  spec.render.density_noise = static_cast<float>(c.density_noise);  // the graph adds it while training only
  spec.loss.multiscale = multiscale_data && c.area_loss;
  spec.loss.charbonnier_padding = c.data_loss == DataLoss::charbonnier ? static_cast<float>(c.charb_padding) : 0.0f;
  spec.loss.channel_mean = c.loss_channel_mean;
  spec.validate();
  return spec;
}

std::vector<std::unique_ptr<mlp::GridTable>> make_grids(ocl::Context& ctx, const graph::GraphSpec& spec) {
  std::vector<std::unique_ptr<mlp::GridTable>> grids;
  for (const auto& config : spec.grids) grids.push_back(std::make_unique<mlp::GridTable>(ctx, config));
  return grids;
}

std::vector<std::unique_ptr<mlp::Network>> make_networks(ocl::Context& ctx, const graph::GraphSpec& spec,
                                                        gemm::GemmBackend backend) {
  std::vector<std::unique_ptr<mlp::Network>> networks;
  for (const auto& config : spec.mlps) networks.push_back(mlp::make_network(ctx, config, backend));
  return networks;
}

data::LoadOptions load_options(const TrainConfig& config, const std::string& data_path, std::vector<std::string> splits,
                               int scales) {
  data::LoadOptions options;
  options.background = config.background;
  options.factor = static_cast<uint32_t>(config.factor);
  // A folder that is multiscale on disk (metadata.json) already holds its scales; build them otherwise.
  const bool on_disk_multiscale = data::detect_reader(data_path).scales_on_disk;
  options.scales = scales > 0 ? scales : config.multiscale && !on_disk_multiscale ? config.multiscale_scales : 1;
  if (config.near > 0) options.near = config.near;
  if (config.far > 0) options.far = config.far;
  const bool zipnerf = config.variant == ModelFamily::zipnerf;
  if (config.unbounded && !(config.near > 0)) options.near = zipnerf ? kUnboundedNear : kContractedIpeNear;
  if (config.unbounded && !(config.far > 0)) options.far = kUnboundedFar;
  // The contraction leaves the ball of radius 1 as it is: a transforms.json's world (an import puts its median camera
  // 4 from the centre) moves to the one around its cameras, as spherify moves an LLFF capture's.
  options.world_around_cameras = config.unbounded;
  options.llff.spherify = config.spherify;
  options.llff.ndc = config.ray_shape == RayShape::cylinder;  // the ray kernel's cylinders are NDC rays
  options.forward_facing_ndc = options.llff.ndc;             // a transforms.json's world moves into NDC's
  options.splits = std::move(splits);
  return options;
}

}  // namespace mipnerf::train
