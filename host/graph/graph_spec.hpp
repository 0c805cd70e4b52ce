// The host graph as data: which stages each level runs and with which options. Coarse and fine are two
// entries of one list, run by one loop (graph.hpp); variants (NeRF, ablations) are other lists.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/stage_options.hpp"
#include "mlp/grid_table.hpp"
#include "mlp/mlp_config.hpp"
#include "ops/interlevel.hpp"
#include "ops/loss.hpp"
#include "ops/zip_features.hpp"

namespace mipnerf::graph {

// How a level gets its interval edges.
enum class Sampling {
  stratified,      // N + 1 edges between near and far (the first level)
  resample,        // N + 1 edges drawn from the previous level's weights (mip-NeRF's fine level)
  resample_union,  // N_new + 1 drawn edges merged with the previous level's edges (NeRF's fine level)
  // Zip-NeRF's proposal sampling: N + 1 edges in normalised s = (t − near)/(far − near) drawn by sample_intervals
  // (the step's anneal) from the previous level's s-edges and weights, or at the first level from the whole ray [0, 1]
  // with weight 1 (official Model.__call__'s initial sdist); then t per ray (bounded scenes: raydist_fn = None).
  proposal,
};

// What a level's output is for.
enum class LevelRole {
  nerf,      // colour: its loss is the photometric one (mip-NeRF's coarse and fine levels, Zip-NeRF's last)
  // Zip-NeRF's proposal round: density only, its weights pick where the next level samples; its loss is the spline
  // interlevel loss of its histogram against the last level's (stop-gradient), through its own network and grid.
  proposal,
};

// How an interval becomes the MLP's input features.
enum class Encoding {
  integrated,       // IPE of the frustum Gaussian (mip-NeRF), fused Gaussian + IPE kernel
  frustum_mean_pe,  // PE of the Gaussian's mean, covariance ignored (mip-NeRF "w/o IPE")
  midpoint_pe,      // PE of the interval's midpoint on the ray (NeRF's point samples)
  concat_pe,        // PE of the Gaussian's mean ++ PE of its covariance's signed square roots (supplement §7)
  zip_grid,         // Zip-NeRF: the interval's multisamples looked up in a trained grid (zip_features.cl)
  // mip-NeRF 360: the frustum's full Gaussian through the contraction, projected onto the tessellated icosahedron's
  // directions, then IPE (contracted_ipe.cl; GraphSpec::basis_tessellation, position_encoding's degrees)
  contracted_ipe,
};

struct LevelSpec {
  Sampling sampling = Sampling::stratified;
  size_t new_samples = 128;  // edges drawn by this level's sampling: new_samples + 1
  Encoding encoding = Encoding::integrated;
  size_t mlp_index = 0;      // which network evaluates this level (mip-NeRF: one shared; NeRF: one each)
  size_t grid_index = 0;     // which grid a zip_grid level reads (GraphSpec::grids)
  float loss_weight = 1.0f;  // λ = 0.1 on coarse levels, 1 on the last (nerf levels)
  LevelRole role = LevelRole::nerf;
  ops::InterlevelRound interlevel;  // a proposal level's loss: its blur half-width (in s) and mult
  // A proposal-sampled level after the first: the previous level's histogram is max-dilated by this much (normalised
  // s) before this level samples from it (mip-NeRF 360's stepfun.max_dilate_weights; 0: not dilated, Zip-NeRF).
  float dilation = 0.0f;
  // The last level's distortion loss weight (mip-NeRF 360 eq. 15 over its s edges, so proposal-sampled only; 0: none).
  float distortion_mult = 0.0f;
  // Intervals this level renders: new_samples, or previous + new_samples + 1 for a union of edge sets.
  size_t intervals(size_t previous_intervals) const {
    return sampling == Sampling::resample_union ? previous_intervals + new_samples + 1 : new_samples;
  }
};

struct GraphSpec {
  std::vector<LevelSpec> levels;
  std::vector<mlp::MlpConfig> mlps;  // the networks, indexed by LevelSpec::mlp_index
  std::vector<mlp::GridConfig> grids;  // Zip-NeRF's grids, indexed by LevelSpec::grid_index (empty for mip-NeRF)
  // The grids' feature stage (its `features`, `init_range` and `precondition` follow each grid's config; `randomized`
  // is set per graph: training draws the multisample patterns, rendering uses the fixed one).
  ops::ZipFeatureOptions zip;
  float grid_weight_decay = 0.1f;  // mult of each grid level's ½·mean(value²) in the loss (official param_regularizers)
  RaysOptions rays;
  SampleOptions sample;      // `randomized` is set per call (training vs rendering)
  ResampleOptions resample;  // idem
  // Proposal sampling (Sampling::proposal): `anneal` and `randomized` are set per graph and step (training: the
  // step's proposal_anneal(train_frac, anneal_slope); rendering: 1 and deterministic, the official at train_frac 1
  // with no rng).
  SampleIntervalsOptions sample_intervals;
  float anneal_slope = 10.0f;  // Schlick's bias slope of the anneal (official Model.anneal_slope)
  // How proposal sampling's s maps to t (official Model.raydist_fn): linear for bounded scenes, the power ladder for
  // unbounded ones (with zip.contract, near 0 and a far bound out at 1e6), the reciprocal for mip-NeRF 360's
  // (contracted_ipe, near 0.2).
  RayDistance ray_distance = RayDistance::linear;
  GaussianOptions gaussian;
  EncodingOptions position_encoding;  // IPE or PE degrees of sample positions
  int basis_tessellation = 2;         // contracted_ipe's directions: the icosahedron tessellated this often (2: 21)
  EncodingOptions view_encoding;      // PE of view directions (identity + degrees 0..3)
  ActivationOptions activation;
  RenderOptions render;
  ops::LossOptions loss;

  // Features per row of `encoding` with position_encoding's degrees (not zip_grid: its width is its grid's).
  size_t feature_width(Encoding encoding) const;
  // Features per row of `level`: its encoding's, or its grid's levels × (features + the scale feature).
  size_t feature_width(const LevelSpec& level) const;
  // The feature stage options of grid `index` (zip with the grid's features, init range and precondition).
  ops::ZipFeatureOptions zip_options(size_t index) const;
  // Intervals of each level, in order.
  std::vector<size_t> intervals_per_level() const;
  size_t max_intervals() const;
  // True when some level is a proposal round (Zip-NeRF's proposal sampling).
  bool has_proposal_levels() const;
  // Throws mipnerf::Error when levels, networks and encodings do not fit together.
  void validate() const;
  // One line per level, for logs: "level 0: stratified 128, IPE 0..15 (96), MLP 0, weight 0.1".
  std::string describe() const;
};

}  // namespace mipnerf::graph
