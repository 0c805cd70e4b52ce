// The host graph: one loop over levels, one chunk of rays at a time.
#include "graph/graph.hpp"

#include <cstdint>

#include "core/error.hpp"
#include "core/proposal_anneal.hpp"
#include "graph/stage_traffic.hpp"
#include "parallel/world.hpp"

namespace mipnerf::graph {
namespace {

// Element counts of every buffer the graph allocates, computed in one place for allocation and estimates.
struct BufferPlan {
  size_t rays = 0;     // R: rays per chunk
  size_t samples = 0;  // S: R · max intervals
  size_t view_width = 0;
  size_t feature_width = 0;
  bool needs_points = false;  // a PE encoding needs means/covs buffers
  bool grid_gradients = false;  // training a grid level: d_features [S][F]
  size_t drawn_edges = 0;     // union levels: R · (new + 1)
  std::vector<size_t> level_intervals;
  std::vector<bool> level_s_edges;     // per level: proposal-sampled (its [R][N+1] s-edges)
  std::vector<size_t> level_own;       // per level: a training proposal round's own features width (0: none)
  bool unit_histogram = false;         // the first level samples by proposal: [R][2] + [R]
  size_t proposal_intervals = 0;       // training: the proposal rounds' most intervals (their shared backward)
  size_t distortion_intervals = 0;     // training with a distortion loss: the last level's intervals
  size_t dilated_from = 0;             // the most intervals a dilated level's previous level has (N: 3N − 1 edges)
  size_t batch_rays = 0;
  size_t partial_slots = 0;  // per colour level (training)
  bool training = false;

  // Floats of every buffer but the ray bundle (RayBundle::bytes_for).
  size_t float_count() const {
    size_t n = rays * view_width + samples * feature_width + samples * 4 + drawn_edges;
    if (needs_points) n += 2 * 3 * samples;
    if (training) n += rays * 3 + samples * 4;
    if (grid_gradients) n += samples * feature_width;
    for (size_t l = 0; l < level_intervals.size(); ++l) {
      const size_t intervals = level_intervals[l];
      n += rays * (2 * intervals + 1) + rays * 5 + (training && !level_own[l] ? 2 * partial_slots : 0);
      if (level_s_edges[l]) n += rays * (intervals + 1);
      if (level_own[l]) n += rays * intervals * (level_own[l] + 1) + batch_rays;
    }
    if (unit_histogram) n += 3 * rays;
    n += rays * proposal_intervals * (2 + 3) + (proposal_intervals ? rays : 0);
    if (distortion_intervals) n += rays * (2 * distortion_intervals + 1) + rays + batch_rays;
    if (dilated_from) n += rays * (7 * dilated_from - 3);  // + the deque's [R][N] (4-byte indices)
    return n;
  }
};

BufferPlan plan_for(const GraphSpec& spec, GraphMode mode, size_t max_chunk_rays, size_t max_batch_rays,
                    size_t loss_group_size) {
  BufferPlan plan;
  plan.rays = max_chunk_rays;
  plan.samples = max_chunk_rays * spec.max_intervals();
  plan.view_width = spec.rays.view_dependence ? static_cast<size_t>(spec.view_encoding.pe_width()) : 0;
  plan.level_intervals = spec.intervals_per_level();
  plan.training = mode == GraphMode::training;
  plan.batch_rays = max_batch_rays;
  plan.unit_histogram = spec.levels.front().sampling == Sampling::proposal;
  for (const auto& level : spec.levels) {
    plan.level_s_edges.push_back(level.sampling == Sampling::proposal);
    const bool own = plan.training && level.role == LevelRole::proposal;
    plan.level_own.push_back(own ? spec.feature_width(level) : 0);
    if (own) plan.proposal_intervals = std::max(plan.proposal_intervals, level.new_samples);
    plan.feature_width = std::max(plan.feature_width, spec.feature_width(level));
    // The fused kernels (IPE, concatenated PE, grid features) compute their Gaussians or multisamples inline; the PE
    // paths stage means first.
    plan.needs_points = plan.needs_points || level.encoding == Encoding::frustum_mean_pe ||
                        level.encoding == Encoding::midpoint_pe;
    plan.grid_gradients = plan.grid_gradients || (plan.training && level.encoding == Encoding::zip_grid);
    if (level.sampling == Sampling::resample_union) {
      plan.drawn_edges = std::max(plan.drawn_edges, max_chunk_rays * (level.new_samples + 1));
    }
  }
  if (plan.training && spec.levels.back().distortion_mult > 0.0f) plan.distortion_intervals = plan.level_intervals.back();
  for (size_t l = 1; l < spec.levels.size(); ++l) {
    if (spec.levels[l].dilation > 0.0f) plan.dilated_from = std::max(plan.dilated_from, plan.level_intervals[l - 1]);
  }
  // Each chunk of n rays writes ceil(n / group) slots: at most batch/group + one partial group per chunk.
  const size_t chunks = max_chunk_rays ? (max_batch_rays + max_chunk_rays - 1) / max_chunk_rays : 0;
  plan.partial_slots = max_batch_rays / loss_group_size + chunks + 1;
  return plan;
}

// The MLP workspaces a graph holds: one per network for the levels that are not proposal rounds (sized for the most
// rows among them), one per proposal round (its forward's activations wait for its backward after the last level's,
// also when rounds share one network).
struct WorkspaceSlot {
  size_t mlp_index = 0;
  size_t max_rows = 0;
};
struct WorkspacePlan {
  std::vector<WorkspaceSlot> slots;
  std::vector<size_t> level_slot;  // [levels]
};
WorkspacePlan workspace_slots(const GraphSpec& spec, size_t max_chunk_rays) {
  const auto intervals = spec.intervals_per_level();
  WorkspacePlan plan;
  plan.level_slot.assign(spec.levels.size(), 0);
  std::vector<size_t> network_slot(spec.mlps.size(), SIZE_MAX);  // the slot of a network's non-proposal levels
  for (size_t l = 0; l < spec.levels.size(); ++l) {
    const bool round = spec.levels[l].role == LevelRole::proposal;
    const size_t rows = std::max<size_t>(1, max_chunk_rays * intervals[l]), i = spec.levels[l].mlp_index;
    if (!round && network_slot[i] != SIZE_MAX) {
      plan.slots[network_slot[i]].max_rows = std::max(plan.slots[network_slot[i]].max_rows, rows);
    } else {
      plan.slots.push_back({i, rows});
      if (!round) network_slot[i] = plan.slots.size() - 1;
    }
    plan.level_slot[l] = round ? plan.slots.size() - 1 : network_slot[i];
  }
  return plan;
}

mlp::WorkspaceMode workspace_mode(GraphMode mode) {
  return mode == GraphMode::training ? mlp::WorkspaceMode::training : mlp::WorkspaceMode::inference;
}

// Estimates assume the smallest loss work-group any device gets (more partial slots: an upper bound).
constexpr size_t kSmallestLossGroup = 64;

}  // namespace

size_t Graph::bytes_for(const GraphSpec& spec, GraphMode mode, size_t max_chunk_rays, size_t max_batch_rays) {
  size_t bytes = plan_for(spec, mode, max_chunk_rays, max_batch_rays, kSmallestLossGroup).float_count() * sizeof(float);
  bytes += ops::RayBundle::bytes_for(max_chunk_rays) + 2 * max_chunk_rays * sizeof(uint32_t);
  for (const WorkspaceSlot& slot : workspace_slots(spec, max_chunk_rays).slots) {
    bytes += mlp::Workspace::bytes_for(spec.mlps[slot.mlp_index], slot.max_rows, max_chunk_rays, workspace_mode(mode));
  }
  return bytes;
}

Graph::Graph(ocl::Context& ctx, const GraphSpec& spec, std::vector<mlp::Network*> networks, GraphMode mode,
             size_t max_chunk_rays, size_t max_batch_rays)
    : Graph(ctx, spec, std::move(networks), {}, mode, max_chunk_rays, max_batch_rays) {}

Graph::Graph(ocl::Context& ctx, const GraphSpec& spec, std::vector<mlp::Network*> networks,
             std::vector<mlp::GridTable*> grids, GraphMode mode, size_t max_chunk_rays, size_t max_batch_rays)
    : ctx_(&ctx),
      spec_(spec),
      networks_(std::move(networks)),
      grids_(std::move(grids)),
      mode_(mode),
      max_chunk_rays_(max_chunk_rays),
      max_batch_rays_(max_batch_rays) {
  spec_.validate();
  if (networks_.size() != spec_.mlps.size()) {
    throw Error("graph: " + std::to_string(spec_.mlps.size()) + " networks in the spec, " +
                std::to_string(networks_.size()) + " given");
  }
  if (grids_.size() != spec_.grids.size()) {
    throw Error("graph: " + std::to_string(spec_.grids.size()) + " grids in the spec, " +
                std::to_string(grids_.size()) + " given");
  }
  for (size_t g = 0; g < grids_.size(); ++g) {
    if (grids_[g] == nullptr || mlp::grid_level_sizes(grids_[g]->config()) != mlp::grid_level_sizes(spec_.grids[g]) ||
        grids_[g]->config().features != spec_.grids[g].features ||
        grids_[g]->config().hash_table_size != spec_.grids[g].hash_table_size) {
      throw Error("graph: grid " + std::to_string(g) + " is not the spec's (" + mlp::describe(spec_.grids[g]) + ")");
    }
  }
  if (max_chunk_rays_ == 0) throw Error("graph: the chunk size must be at least one ray");
  const bool training = mode_ == GraphMode::training;
  if (training && max_batch_rays_ == 0) throw Error("graph: a training graph needs the batch size");

  // Sampling is jittered only while training (and only if the spec asks); rendering is deterministic.
  SampleOptions sample_options = spec_.sample;
  sample_options.randomized = training && spec_.sample.randomized;
  resample_options_ = spec_.resample;
  resample_options_.randomized = training && spec_.resample.randomized;
  // Proposal sampling: rendering is the official eval (rng None: deterministic; train_frac 1: anneal 1); training
  // starts at anneal 1 until set_train_fraction.
  sample_intervals_options_ = spec_.sample_intervals;
  sample_intervals_options_.randomized = training && spec_.sample_intervals.randomized;
  sample_intervals_options_.anneal = 1.0f;
  RaysOptions rays_options = spec_.rays;
  // Supersampling jitter while rendering is the renderer's choice (inference_jittered), whatever training did.
  if (!training) rays_options.jitter_subpixel = mode_ == GraphMode::inference_jittered;

  rays_ = std::make_unique<ops::Rays>(ctx, rays_options);
  sample_ = std::make_unique<ops::Sample>(ctx, sample_options);
  resample_ = std::make_unique<ops::Resample>(ctx);
  gaussian_ = std::make_unique<ops::Gaussian>(ctx, spec_.gaussian);
  ops::EncodeTuning encode_tuning;
  for (const auto& level : spec_.levels) encode_tuning.concat_pe |= level.encoding == Encoding::concat_pe;
  encode_ = std::make_unique<ops::Encode>(ctx, spec_.gaussian, encode_tuning);
  for (const auto& level : spec_.levels) {
    if (level.encoding == Encoding::contracted_ipe && !contracted_ipe_) {
      contracted_ipe_ = std::make_unique<ops::ContractedIpe>(ctx, spec_.gaussian, spec_.basis_tessellation);
    }
  }
  // Density noise regularises training only (official: when randomized); rendering never compiles it in.
  RenderOptions render_options = spec_.render;
  if (!training) render_options.density_noise = 0.0f;
  render_ = std::make_unique<ops::Render>(ctx, render_options, spec_.activation);
  if (training) loss_ = std::make_unique<ops::Loss>(ctx, spec_.loss);
  // A proposal-sampled level reads a proposal-sampled previous level (GraphSpec::validate), so some level samples by
  // proposal exactly when the first does.
  if (spec_.levels.front().sampling == Sampling::proposal) {
    sample_intervals_ = std::make_unique<ops::SampleIntervals>(ctx, spec_.ray_distance);
  }
  if (training) {
    for (const auto& level : spec_.levels) {
      if (level.role != LevelRole::proposal) continue;
      if (level.interlevel.kind == ops::InterlevelKind::spline && !interlevel_) {
        interlevel_ = std::make_unique<ops::SplineInterlevel>(ctx);
      }
      if (level.interlevel.kind == ops::InterlevelKind::outer && !outer_interlevel_) {
        outer_interlevel_ = std::make_unique<ops::OuterInterlevel>(ctx);
      }
    }
  }
  if (training && spec_.levels.back().distortion_mult > 0.0f) distortion_ = std::make_unique<ops::Distortion>(ctx);
  for (size_t g = 0; g < spec_.grids.size(); ++g) {
    ops::ZipFeatureOptions zip_options = spec_.zip_options(g);
    zip_options.randomized = training && spec_.zip.randomized;  // rendering: the fixed pattern
    // A CPU device adds the table's gradient level by level, in a fixed order (deterministic: a resumed run equals an
    // uninterrupted one); a GPU needs the per-sample atomic scatter's parallelism.
    zip_options.scatter = (ctx.device_info().type & CL_DEVICE_TYPE_CPU) ? ops::ZipFeatureOptions::Scatter::by_level
                                                                        : ops::ZipFeatureOptions::Scatter::atomic;
    zip_.push_back(std::make_unique<ops::ZipFeatures>(ctx, zip_options));
    level_scales_.emplace_back(ctx, mlp::grid_level_sizes(spec_.grids[g]).size(), "grid level_scale [L]");
  }

  const BufferPlan plan =
      plan_for(spec_, mode_, max_chunk_rays_, max_batch_rays_, training ? loss_->group_size() : kSmallestLossGroup);
  const size_t R = plan.rays, S = plan.samples;
  camera_ids_ = ocl::DeviceArray<uint32_t>(ctx, R, "chunk camera_ids [R]");
  pixel_ids_ = ocl::DeviceArray<uint32_t>(ctx, R, "chunk pixel_ids [R]");
  chunk_rays_ = ops::RayBundle(ctx, R);
  view_features_ = ocl::DeviceArray<float>(ctx, R * plan.view_width, "view_encoding [R][view]");
  features_ = ocl::DeviceArray<float>(ctx, S * plan.feature_width, "features [samples][F]");
  if (plan.needs_points) {
    means_ = ocl::DeviceArray<float>(ctx, 3 * S, "means [samples][3]");
    covs_ = ocl::DeviceArray<float>(ctx, 3 * S, "covs [samples][3]");
  }
  if (plan.drawn_edges) drawn_edges_ = ocl::DeviceArray<float>(ctx, plan.drawn_edges, "drawn t_edges [R][new+1]");
  raw_density_ = ocl::DeviceArray<float>(ctx, S, "raw_density [samples]");
  raw_rgb_ = ocl::DeviceArray<float>(ctx, 3 * S, "raw_rgb [samples][3]");
  if (training) {
    d_comp_rgb_ = ocl::DeviceArray<float>(ctx, 3 * R, "d_comp_rgb [R][3]");
    d_raw_density_ = ocl::DeviceArray<float>(ctx, S, "d_raw_density [samples]");
    d_raw_rgb_ = ocl::DeviceArray<float>(ctx, 3 * S, "d_raw_rgb [samples][3]");
  }
  if (plan.grid_gradients) d_features_ = ocl::DeviceArray<float>(ctx, S * plan.feature_width, "d_features [samples][F]");
  if (plan.unit_histogram) {
    std::vector<float> unit_edges(2 * R);
    for (size_t r = 0; r < R; ++r) unit_edges[2 * r + 1] = 1.0f;
    unit_s_edges_ = ocl::DeviceArray<float>(ctx, 2 * R, "unit s_edges [R][2]");
    unit_s_edges_.upload(ctx, unit_edges);
    unit_weights_ = ocl::DeviceArray<float>(ctx, R, "unit weights [R]");
    unit_weights_.fill(ctx, 1.0f);
  }
  if (const size_t M = plan.proposal_intervals) {
    w_blur_ = ocl::DeviceArray<float>(ctx, R * M, "interlevel w_blur [R][M]");
    d_wp_ = ocl::DeviceArray<float>(ctx, R * M, "interlevel d_wp [R][M]");
    chunk_ray_loss_ = ocl::DeviceArray<float>(ctx, R, "interlevel ray_loss [R]");
    zero_d_raw_rgb_ = ocl::DeviceArray<float>(ctx, 3 * R * M, "proposal d_raw_rgb [R·M][3] (zeros)");
    zero_d_raw_rgb_.fill(ctx, 0.0f);
  }
  if (const size_t N = plan.dilated_from) {
    dilate_ = std::make_unique<ops::MaxDilate>(ctx);
    dilated_s_edges_ = ocl::DeviceArray<float>(ctx, R * ops::dilated_edges(N), "dilated s_edges [R][3N-1]");
    dilated_weights_ = ocl::DeviceArray<float>(ctx, R * ops::dilated_intervals(N), "dilated weights [R][3N-2]");
    dilate_scratch_ = ocl::DeviceArray<uint32_t>(ctx, R * N, "dilation deque [R][N]");
  }
  if (const size_t N = plan.distortion_intervals) {
    d_w_distortion_ = ocl::DeviceArray<float>(ctx, R * N, "distortion d_w [R][N]");
    d_t_distortion_ = ocl::DeviceArray<float>(ctx, R * (N + 1), "distortion d_t [R][N+1] (unused)");
    distortion_chunk_loss_ = ocl::DeviceArray<float>(ctx, R, "distortion ray_loss [R]");
    distortion_ray_loss_ = ocl::DeviceArray<float>(ctx, max_batch_rays_, "distortion ray_loss [B]");
  }
  for (size_t l = 0; l < spec_.levels.size(); ++l) {
    LevelBuffers level;
    level.intervals = plan.level_intervals[l];
    const std::string tag = "level " + std::to_string(l) + " ";
    level.t_edges = ocl::DeviceArray<float>(ctx, R * (level.intervals + 1), tag + "t_edges [R][N+1]");
    if (plan.level_s_edges[l]) {
      level.s_edges = ocl::DeviceArray<float>(ctx, R * (level.intervals + 1), tag + "s_edges [R][N+1]");
    }
    if (const size_t width = plan.level_own[l]) {
      level.features = ocl::DeviceArray<float>(ctx, R * level.intervals * width, tag + "features [R·N][F]");
      level.raw_density = ocl::DeviceArray<float>(ctx, R * level.intervals, tag + "raw_density [R·N]");
      level.ray_loss = ocl::DeviceArray<float>(ctx, max_batch_rays_, tag + "interlevel ray_loss [B]");
    }
    level.weights = ocl::DeviceArray<float>(ctx, R * level.intervals, tag + "weights [R][N]");
    level.outputs.comp_rgb = ocl::DeviceArray<float>(ctx, 3 * R, tag + "comp_rgb [R][3]");
    level.outputs.acc = ocl::DeviceArray<float>(ctx, R, tag + "acc [R]");
    level.outputs.distance = ocl::DeviceArray<float>(ctx, R, tag + "distance [R]");
    if (training && !plan.level_own[l]) {
      level.partials = ocl::DeviceArray<float>(ctx, 2 * plan.partial_slots, tag + "loss partials");
    }
    levels_.push_back(std::move(level));
  }
  const WorkspacePlan workspaces = workspace_slots(spec_, R);
  for (const WorkspaceSlot& slot : workspaces.slots) {
    workspaces_.push_back(networks_[slot.mlp_index]->make_workspace(slot.max_rows, R, workspace_mode(mode_)));
  }
  level_workspace_ = workspaces.level_slot;
}

Graph::~Graph() = default;

void Graph::generate_rays(const RaySource& source, ChunkRange chunk, StepKey key, uint32_t first_ray) {
  if (chunk.count == 0 || chunk.count > max_chunk_rays_) {
    throw Error("graph: a chunk of " + std::to_string(chunk.count) + " rays (the graph holds up to " +
                std::to_string(max_chunk_rays_) + ")");
  }
  ocl::StageScope stage(*ctx_, "rays");
  ocl::add_stage_bytes(*ctx_, traffic::rays(chunk.count, spec_.rays.view_dependence));
  ocl::copy(*ctx_, source.camera_ids, chunk.first, camera_ids_, 0, chunk.count);
  ocl::copy(*ctx_, source.pixel_ids, chunk.first, pixel_ids_, 0, chunk.count);
  const RngKey rng{key.seed, key.step, first_ray};
  if (source.cameras.has_lens_tables()) {
    if (!lens_rays_) {
      RaysOptions lens_options = rays_->options();
      lens_options.lens_tables = true;
      lens_rays_ = std::make_unique<ops::Rays>(*ctx_, lens_options);
    }
    lens_rays_->fwd({source.cameras.packed(), camera_ids_, pixel_ids_, chunk.count, &source.cameras.lens_tables()},
                    chunk_rays_, rng);
  } else {
    rays_->fwd({source.cameras.packed(), camera_ids_, pixel_ids_, chunk.count}, chunk_rays_, rng);
  }
  if (spec_.rays.view_dependence) {
    ocl::StageScope view_stage(*ctx_, "view encoding");
    ocl::add_stage_bytes(*ctx_, traffic::view_encoding(chunk.count, spec_.view_encoding.pe_width()));
    encode_->pe(spec_.view_encoding, {chunk_rays_.viewdirs, chunk.count}, view_features_);
  }
}

void Graph::sample_level(size_t l, size_t n_rays, StepKey key, uint32_t first_ray) {
  const LevelSpec& level = spec_.levels[l];
  LevelBuffers& out = levels_[l];
  const RngKey rng{key.seed, key.step, first_ray};
  ocl::StageScope stage(*ctx_, level.sampling == Sampling::stratified ? "sampling"
                               : level.sampling == Sampling::proposal ? "proposal sampling"
                                                                      : "resampling");
  switch (level.sampling) {
    case Sampling::stratified:
      ocl::add_stage_bytes(*ctx_, traffic::stratified_sampling(n_rays, out.intervals));
      sample_->stratified({chunk_rays_, n_rays, out.intervals}, out.t_edges, rng);
      break;
    case Sampling::resample: {
      const LevelBuffers& previous = levels_[l - 1];
      ocl::add_stage_bytes(*ctx_, traffic::resampling(n_rays, previous.intervals, level.new_samples, false));
      resample_->fwd(resample_options_,
                     {previous.t_edges, previous.weights, n_rays, previous.intervals, level.new_samples}, out.t_edges,
                     rng);
      break;
    }
    case Sampling::resample_union: {
      const LevelBuffers& previous = levels_[l - 1];
      ocl::add_stage_bytes(*ctx_, traffic::resampling(n_rays, previous.intervals, level.new_samples, true));
      resample_->fwd(resample_options_,
                     {previous.t_edges, previous.weights, n_rays, previous.intervals, level.new_samples}, drawn_edges_,
                     rng);
      sample_->merge({previous.t_edges, drawn_edges_, n_rays, previous.intervals + 1, level.new_samples + 1},
                     out.t_edges);
      break;
    }
    case Sampling::proposal: {
      const RngKey round_rng = proposal_round_key(rng, l);  // each round its own jitter
      if (l == 0) {
        sample_intervals_->fwd(sample_intervals_options_, {unit_s_edges_, unit_weights_, n_rays, 1, level.new_samples},
                               out.s_edges, round_rng);
      } else {
        // From the previous level's histogram, or (mip-NeRF 360) from that histogram max-dilated.
        const LevelBuffers& previous = levels_[l - 1];
        const ocl::DeviceArray<float>* from_edges = &previous.s_edges;
        const ocl::DeviceArray<float>* from_weights = &previous.weights;
        size_t from_intervals = previous.intervals;
        if (level.dilation > 0.0f) {
          dilate_->fwd(previous.s_edges, previous.weights, n_rays, previous.intervals, level.dilation,
                       dilated_s_edges_, dilated_weights_, dilate_scratch_);
          from_edges = &dilated_s_edges_;
          from_weights = &dilated_weights_;
          from_intervals = ops::dilated_intervals(previous.intervals);
        }
        sample_intervals_->fwd(sample_intervals_options_,
                               {*from_edges, *from_weights, n_rays, from_intervals, level.new_samples}, out.s_edges,
                               round_rng);
      }
      sample_intervals_->s_to_t(out.s_edges, chunk_rays_, n_rays, out.intervals + 1, out.t_edges);
      break;
    }
  }
}

ocl::DeviceArray<float>& Graph::level_features(size_t l) {
  return levels_[l].features.size() ? levels_[l].features : features_;
}

ocl::DeviceArray<float>& Graph::level_raw_density(size_t l) {
  return levels_[l].raw_density.size() ? levels_[l].raw_density : raw_density_;
}

void Graph::set_train_fraction(double train_frac) {
  if (mode_ != GraphMode::training) throw Error("graph: set_train_fraction on a rendering graph (it uses anneal 1)");
  if (!(train_frac >= 0.0 && train_frac <= 1.0)) {
    throw Error("graph: the train fraction must be in [0, 1], got " + std::to_string(train_frac));
  }
  sample_intervals_options_.anneal = static_cast<float>(proposal_anneal(train_frac, spec_.anneal_slope));
}

void Graph::grid_level_scales() {
  for (size_t g = 0; g < grids_.size(); ++g) {
    zip_[g]->level_scale({grids_[g]->levels(), grids_[g]->layout()}, grids_[g]->params(), level_scales_[g]);
  }
}

void Graph::encode_level(size_t l, size_t n_rays, const RngKey& key) {
  const LevelSpec& level = spec_.levels[l];
  const LevelBuffers& buffers = levels_[l];
  const ops::GaussianInputs intervals{chunk_rays_, buffers.t_edges, n_rays, buffers.intervals};
  const size_t rows = n_rays * buffers.intervals;
  ocl::StageScope stage(*ctx_, "encoding");
  ocl::add_stage_bytes(*ctx_, traffic::encoding(n_rays, buffers.intervals, spec_.feature_width(level)));
  switch (level.encoding) {
    case Encoding::zip_grid: {
      mlp::GridTable& grid = *grids_[level.grid_index];
      zip_[level.grid_index]->fwd({chunk_rays_, buffers.t_edges, n_rays, buffers.intervals},
                                  {grid.levels(), grid.layout()}, grid.params(), level_scales_[level.grid_index],
                                  level_features(l), key);
      break;
    }
    case Encoding::integrated:  // a training proposal round's into its own features (kept for its backward)
      encode_->gaussian_ipe(spec_.position_encoding, intervals, level_features(l));
      break;
    case Encoding::contracted_ipe:
      contracted_ipe_->fwd(spec_.position_encoding, intervals, level_features(l));
      break;
    case Encoding::frustum_mean_pe:
      gaussian_->fwd(intervals, {means_, covs_});
      encode_->pe(spec_.position_encoding, {means_, rows}, features_);
      break;
    case Encoding::midpoint_pe:
      gaussian_->points(intervals, {means_, covs_});
      encode_->pe(spec_.position_encoding, {means_, rows}, features_);
      break;
    case Encoding::concat_pe:
      encode_->gaussian_concat_pe(spec_.position_encoding, intervals, features_);
      break;
  }
}

void Graph::forward_level(size_t l, size_t n_rays, mlp::Workspace& ws, const DensityNoiseKey& noise,
                          bool with_colour) {
  const LevelSpec& level = spec_.levels[l];
  LevelBuffers& buffers = levels_[l];
  mlp::Network& network = *networks_[level.mlp_index];
  const size_t feature_width = network.config().input_width;
  ocl::DeviceArray<float>& raw_density = level_raw_density(l);
  mlp::MlpInputs in;
  in.features = mlp::view(level_features(l), feature_width);
  if (network.config().view_dependence) in.view_encoding = mlp::view(view_features_, network.config().view_width);
  in.n_rays = n_rays;
  in.samples_per_ray = buffers.intervals;
  // A proposal round has no colour (official disable_rgb). Training, a network's forward must still give every
  // output its backward differentiates (mlp::Network): the round's colour head writes the shared raw_rgb, which
  // nothing reads (the last level's forward overwrites it), and gets a zero gradient (backward_proposal).
  const bool proposal = level.role == LevelRole::proposal;
  if (proposal) with_colour = false;
  const bool rgb_output = with_colour || (proposal && mode_ == GraphMode::training);
  {
    ocl::StageScope mlp_stage(*ctx_, "mlp bias + ReLU");
    network.forward(in, {mlp::view(raw_density, 1), rgb_output ? mlp::view(raw_rgb_, 3) : mlp::MatrixView{}}, ws);
  }
  // The activations are fused into rendering: raw MLP outputs in, composited colour out.
  ocl::StageScope stage(*ctx_, "render");
  ocl::add_stage_bytes(*ctx_, traffic::render_forward(n_rays, buffers.intervals, with_colour));
  if (!with_colour) {
    render_->raw_weights_fwd({raw_density, buffers.t_edges, chunk_rays_, n_rays, buffers.intervals},
                             {buffers.outputs.acc, buffers.outputs.distance, buffers.weights}, noise);
    return;
  }
  render_->raw_fwd({raw_rgb_, raw_density_, buffers.t_edges, chunk_rays_, n_rays, buffers.intervals},
                   {buffers.outputs.comp_rgb, buffers.outputs.acc, buffers.outputs.distance, buffers.weights}, noise);
}

void Graph::backward_level(size_t l, size_t n_rays, const TrainTargets& targets, ChunkRange chunk,
                           const DensityNoiseKey& noise, const RngKey& key) {
  const LevelSpec& level = spec_.levels[l];
  LevelBuffers& buffers = levels_[l];
  const ops::LossChunk loss_chunk{n_rays, chunk.first, step_groups_};
  {
    ocl::StageScope stage(*ctx_, "loss");
    ocl::add_stage_bytes(*ctx_, traffic::loss(n_rays));
    loss_->fwd_bwd(buffers.outputs.comp_rgb, targets.target_rgb, targets.lossmult,
                   {level.loss_weight, step_lossmult_sum_}, d_comp_rgb_, buffers.partials, loss_chunk);
  }
  ops::RenderGradients grads{d_comp_rgb_, nullptr};
  if (level.distortion_mult > 0.0f) {
    distortion_backward(l, chunk);
    grads.d_weights = &d_w_distortion_;
  }
  ocl::StageScope stage(*ctx_, "render backward");
  ocl::add_stage_bytes(*ctx_, traffic::render_backward(n_rays, buffers.intervals));
  render_->raw_bwd({raw_rgb_, raw_density_, buffers.t_edges, chunk_rays_, n_rays, buffers.intervals}, buffers.weights,
                   grads, {d_raw_rgb_, d_raw_density_}, noise);
  const bool grid_level = level.encoding == Encoding::zip_grid;
  mlp::Network& network = *networks_[level.mlp_index];
  {
    ocl::StageScope mlp_stage(*ctx_, "mlp ReLU mask + bias sums");
    network.backward(workspace_of(l), {mlp::view(d_raw_density_, 1), mlp::view(d_raw_rgb_, 3)},
                     grid_level ? mlp::view(d_features_, network.config().input_width) : mlp::MatrixView{});
  }
  if (!grid_level) return;
  ocl::StageScope grid_stage(*ctx_, "grid backward");
  mlp::GridTable& grid = *grids_[level.grid_index];
  zip_[level.grid_index]->bwd({chunk_rays_, buffers.t_edges, n_rays, buffers.intervals},
                              {grid.levels(), grid.layout()}, d_features_, grid.grads(), key);
}

void Graph::distortion_backward(size_t l, ChunkRange chunk) {
  const LevelBuffers& buffers = levels_[l];
  const ops::DistortionInputs in{buffers.s_edges, buffers.weights, chunk.count, buffers.intervals};
  ocl::StageScope stage(*ctx_, "distortion loss");
  distortion_->fwd(in, distortion_chunk_loss_);
  ocl::copy(*ctx_, distortion_chunk_loss_, 0, distortion_ray_loss_, chunk.first, chunk.count);
  distortion_->bwd(in, spec_.levels[l].distortion_mult, step_batch_rays_, d_w_distortion_, d_t_distortion_);
}

void Graph::backward_proposal(size_t l, ChunkRange chunk, const DensityNoiseKey& noise, const RngKey& key) {
  const LevelSpec& level = spec_.levels[l];
  LevelBuffers& round = levels_[l];
  const LevelBuffers& last = levels_.back();
  const size_t n_rays = chunk.count;
  // The last level's histogram takes no gradient (official stop_gradient on w): only the round's weights do.
  const ops::InterlevelInputs in{last.s_edges, last.weights, round.s_edges, round.weights,
                                 n_rays,       last.intervals, round.intervals};
  {
    ocl::StageScope stage(*ctx_, "interlevel loss");
    if (level.interlevel.kind == ops::InterlevelKind::outer) {
      outer_interlevel_->fwd(in, chunk_ray_loss_);
      outer_interlevel_->bwd(in, level.interlevel.mult, step_batch_rays_, d_wp_);
    } else {
      interlevel_->fwd(in, level.interlevel.blur_halfwidth, w_blur_, chunk_ray_loss_);
      interlevel_->bwd(in, w_blur_, level.interlevel.mult, step_batch_rays_, d_wp_);
    }
    ocl::copy(*ctx_, chunk_ray_loss_, 0, round.ray_loss, chunk.first, n_rays);
  }
  {
    ocl::StageScope stage(*ctx_, "render backward");
    render_->raw_weights_bwd({round.raw_density, round.t_edges, chunk_rays_, n_rays, round.intervals}, round.weights,
                             d_wp_, d_raw_density_, noise);
  }
  // A grid round's features take the gradient on to its grid; IPE features have no parameters behind them.
  const bool grid_level = level.encoding == Encoding::zip_grid;
  mlp::Network& network = *networks_[level.mlp_index];
  {
    ocl::StageScope mlp_stage(*ctx_, "mlp ReLU mask + bias sums");
    network.backward(workspace_of(l), {mlp::view(d_raw_density_, 1), mlp::view(zero_d_raw_rgb_, 3)},
                     grid_level ? mlp::view(d_features_, network.config().input_width) : mlp::MatrixView{});
  }
  if (!grid_level) return;
  ocl::StageScope grid_stage(*ctx_, "grid backward");
  mlp::GridTable& grid = *grids_[level.grid_index];
  zip_[level.grid_index]->bwd({chunk_rays_, round.t_edges, n_rays, round.intervals}, {grid.levels(), grid.layout()},
                              d_features_, grid.grads(), key);
}

void Graph::begin_step(size_t batch_rays, double lossmult_sum) {
  if (mode_ != GraphMode::training) throw Error("graph: begin_step on a rendering graph");
  if (batch_rays == 0 || batch_rays > max_batch_rays_) {
    throw Error("graph: a batch of " + std::to_string(batch_rays) + " rays (the graph holds up to " +
                std::to_string(max_batch_rays_) + ")");
  }
  if (!(lossmult_sum > 0.0)) throw Error("graph: the batch's lossmult sum must be > 0");
  step_batch_rays_ = batch_rays;
  step_lossmult_sum_ = lossmult_sum;
  step_groups_ = 0;
  // A rank fills only its share of the batch's per-ray interlevel losses; end_step sums them all.
  for (auto& level : levels_) {
    if (level.ray_loss.size()) level.ray_loss.fill(*ctx_, 0.0f);
  }
  if (distortion_ray_loss_.size()) distortion_ray_loss_.fill(*ctx_, 0.0f);
  ocl::StageScope stage(*ctx_, "adam");  // zeroing the gradients is part of the optimiser's work
  for (auto* network : networks_) network->zero_grad();
  for (size_t g = 0; g < grids_.size(); ++g) {
    grids_[g]->zero_grad();
    // The regulariser's gradient once per step (it does not depend on the batch), on rank 0 only: the ranks'
    // gradients are summed (train_step), so every rank adding it would count it once per rank.
    if (spec_.grid_weight_decay > 0.0f && parallel::world().rank() == 0) {
      zip_[g]->weight_decay({grids_[g]->levels(), grids_[g]->layout()}, grids_[g]->params(), grids_[g]->grads(),
                            spec_.grid_weight_decay);
    }
  }
  grid_level_scales();
}

void Graph::train_chunk(const RaySource& source, ChunkRange chunk, const TrainTargets& targets, StepKey key) {
  if (mode_ != GraphMode::training) throw Error("graph: train_chunk on a rendering graph");
  if (chunk.first + chunk.count > step_batch_rays_) throw Error("graph: chunk outside the step's batch");
  const uint32_t first_ray = static_cast<uint32_t>(chunk.first);
  generate_rays(source, chunk, key, first_ray);
  const RngKey rng{key.seed, key.step, first_ray};
  // A level's density noise (when the spec has it): the same key for its forward and its backward.
  const auto noise_of = [&rng](size_t l) { return DensityNoiseKey{rng, static_cast<uint32_t>(l)}; };
  for (size_t l = 0; l < spec_.levels.size(); ++l) {
    sample_level(l, chunk.count, key, first_ray);
    encode_level(l, chunk.count, rng);
    forward_level(l, chunk.count, workspace_of(l), noise_of(l));
    // A proposal round's loss needs the last level's weights: its backward waits (below).
    if (spec_.levels[l].role == LevelRole::nerf) backward_level(l, chunk.count, targets, chunk, noise_of(l), rng);
  }
  for (size_t l = 0; l < spec_.levels.size(); ++l) {
    if (spec_.levels[l].role == LevelRole::proposal) backward_proposal(l, chunk, noise_of(l), rng);
  }
  step_groups_ += loss_->groups_for(chunk.count);
}

std::vector<ops::LevelLoss> Graph::end_step() {
  std::vector<ops::LevelLoss> losses;
  ocl::StageScope stage(*ctx_, "loss");
  for (size_t l = 0; l < levels_.size(); ++l) {
    auto& level = levels_[l];
    if (spec_.levels[l].role == LevelRole::proposal) {
      ops::LevelLoss round;
      round.proposal = true;
      round.n_rays = step_batch_rays_;
      round.lossmult_sum = step_lossmult_sum_;
      std::vector<float> ray_loss(step_batch_rays_);
      level.ray_loss.download(*ctx_, ray_loss.data(), ray_loss.size());  // blocking: waits for the step
      const ops::InterlevelRound& constants = spec_.levels[l].interlevel;
      // The spline loss is a mean over the round's intervals, the outer loss over the last level's.
      round.interlevel =
          constants.kind == ops::InterlevelKind::outer
              ? ops::outer_interlevel_loss_value(ray_loss, step_batch_rays_, levels_.back().intervals, constants.mult)
              : ops::interlevel_loss_value(ray_loss, step_batch_rays_, level.intervals, constants.mult);
      losses.push_back(round);
      continue;
    }
    std::vector<float> partials(2 * step_groups_);
    level.partials.download(*ctx_, partials.data(), partials.size());  // blocking: waits for the step
    losses.push_back(ops::sum_loss_partials(partials, step_groups_, step_lossmult_sum_, step_batch_rays_));
    if (spec_.levels[l].distortion_mult > 0.0f) {
      std::vector<float> ray_loss(step_batch_rays_);
      distortion_ray_loss_.download(*ctx_, ray_loss.data(), ray_loss.size());
      losses.back().distortion =
          ops::distortion_loss_value(ray_loss, step_batch_rays_, spec_.levels[l].distortion_mult);
    }
  }
  return losses;
}

void Graph::render_chunk(const RaySource& source, ChunkRange chunk, StepKey key, uint32_t first_ray_number) {
  generate_rays(source, chunk, key, first_ray_number + static_cast<uint32_t>(chunk.first));
  grid_level_scales();  // per chunk: the tables may change between chunks (a live viewer renders while training)
  for (size_t l = 0; l < spec_.levels.size(); ++l) {
    sample_level(l, chunk.count, StepKey{}, static_cast<uint32_t>(chunk.first));
    encode_level(l, chunk.count, RngKey{});
    // Only the last level's colour is shown (a proposal round has none: forward_level).
    forward_level(l, chunk.count, workspace_of(l), DensityNoiseKey{},  // no noise compiled in
                  l + 1 == spec_.levels.size() || every_level_colour_);
  }
}

}  // namespace mipnerf::graph
