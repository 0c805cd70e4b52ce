// The host graph: rays → samples → features → MLP → render (→ loss → backward), looped over the levels of
// a GraphSpec, one chunk of rays at a time, all on the device. The host only orchestrates.
//
// Training, per step:  begin_step(); train_chunk(...) for each chunk of the batch; end_step() → losses.
// Per chunk and level l: sample (stratified, or resampled from level l−1's weights: a constant, the
// stop-gradient) → encode → MLP forward → fused activation (with the spec's density noise, training only) + render
// → loss and ∂loss/∂colour → render backward → MLP backward (gradients accumulate over chunks and levels into each
// network's one buffer).
// A level's backward runs before the next level's forward: stop-gradient means no gradient crosses levels,
// so one MLP workspace per network is enough, whatever the number of levels.
// Zip-NeRF's proposal rounds (LevelRole::proposal) are the exception: their loss compares their histograms with the
// last level's, so per chunk every proposal round runs its forward first (keeping its own features, raw density,
// edges and weights), then the last level its forward and backward as above, then each round its interlevel loss →
// weights backward → network backward (density only) → grid backward. Each round has a network of its own
// (GraphSpec::validate), so its workspace holds its forward until then.
#pragma once

#include <memory>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "data/device_cameras.hpp"
#include "graph/graph_spec.hpp"
#include "mlp/grid_table.hpp"
#include "mlp/network.hpp"
#include "ops/contracted_ipe.hpp"
#include "ops/dilate.hpp"
#include "ops/distortion.hpp"
#include "ops/encode.hpp"
#include "ops/gaussian.hpp"
#include "ops/interlevel.hpp"
#include "ops/interlevel_outer.hpp"
#include "ops/loss.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/rays.hpp"
#include "ops/render.hpp"
#include "ops/resample.hpp"
#include "ops/sample.hpp"
#include "ops/sample_intervals.hpp"
#include "ops/zip_features.hpp"

namespace mipnerf::graph {

// Where a chunk's rays come from: cameras and, per ray of the batch (or image), its camera and pixel.
struct RaySource {
  const data::DeviceCameras& cameras;            // packed, with the lens tables when any camera has a lens
  const ocl::DeviceArray<uint32_t>& camera_ids;  // [B]
  const ocl::DeviceArray<uint32_t>& pixel_ids;   // [B] y·width + x
};

// Rays first .. first + count − 1 of the source.
struct ChunkRange {
  size_t first = 0;
  size_t count = 0;
};

// What the loss compares against, for the whole batch (indexed like the source).
struct TrainTargets {
  const ocl::DeviceArray<float>& target_rgb;  // [B][3]
  const ocl::DeviceArray<float>* lossmult;    // [B], read only when the spec's loss is multiscale
};

// Everything random is keyed by (seed, step, ray index in the batch), so chunking never changes results.
struct StepKey {
  uint64_t seed = 0;
  uint32_t step = 0;
};

// A level's rendered chunk, on the device.
struct LevelOutputs {
  ocl::DeviceArray<float> comp_rgb;  // [R][3]
  ocl::DeviceArray<float> acc;       // [R]
  ocl::DeviceArray<float> distance;  // [R] expected distance in t
};

enum class GraphMode {
  training,   // randomized sampling (per the spec), saved activations, loss and backward
  inference,  // deterministic sampling, forward only (rendering, evaluation)
  // As inference, but each ray passes through a uniformly random point of its pixel (SUBPIXEL_JITTER) keyed by
  // render_chunk's key and ray numbers: K renders with K different steps, averaged, are K× jittered
  // supersampling (the NeRF supersampling baseline). Sampling along the rays stays deterministic.
  inference_jittered,
};

class Graph {
 public:
  // `networks[i]` evaluates the levels with mlp_index i; they outlive the graph. Buffers are sized for
  // chunks of up to max_chunk_rays and (training) batches of up to max_batch_rays.
  Graph(ocl::Context& ctx, const GraphSpec& spec, std::vector<mlp::Network*> networks, GraphMode mode,
        size_t max_chunk_rays, size_t max_batch_rays = 0);
  // With Zip-NeRF's grids: `grids[i]` is the table of spec.grids[i] (they outlive the graph); a training graph adds
  // each grid level's table gradient (the weight decay's too) to its grads().
  Graph(ocl::Context& ctx, const GraphSpec& spec, std::vector<mlp::Network*> networks,
        std::vector<mlp::GridTable*> grids, GraphMode mode, size_t max_chunk_rays, size_t max_batch_rays = 0);
  ~Graph();

  // Device bytes the graph's own buffers and workspaces take (networks and datasets not included).
  static size_t bytes_for(const GraphSpec& spec, GraphMode mode, size_t max_chunk_rays, size_t max_batch_rays);

  const GraphSpec& spec() const { return spec_; }
  size_t max_chunk_rays() const { return max_chunk_rays_; }

  // ---- training ----
  // Starts a step over a batch of batch_rays rays whose Σ lossmult is lossmult_sum (the loss normaliser,
  // known before any chunk runs). Zeroes every network's and grid's gradients, adds the grids' weight decay
  // gradient, and takes each grid's level scales (the step's constant).
  void begin_step(size_t batch_rays, double lossmult_sum);
  // Proposal sampling's anneal for the coming steps: proposal_anneal(train_frac, spec.anneal_slope), train_frac in
  // [0, 1] the fraction of training done (official train.py: (step − 1)/(max_steps − 1), clipped). Training graphs
  // only (rendering uses 1); without proposal levels nothing reads it. Starts at 1 until set.
  void set_train_fraction(double train_frac);
  void train_chunk(const RaySource& source, ChunkRange chunk, const TrainTargets& targets, StepKey key);
  // Waits for the step's work and returns each level's loss sums over the batch (a proposal round's: its interlevel
  // loss, LevelLoss::proposal).
  std::vector<ops::LevelLoss> end_step();

  // ---- rendering ----
  // Runs every level's forward for the chunk (deterministic sampling); the outputs of each level stay in
  // level_outputs(l) until the next call. An inference_jittered graph jitters ray i of the chunk by
  // (key.seed, key.step, ray number first_ray_number + chunk.first + i); other graphs ignore both.
  // Only the last level's colour is shown, so by default the levels before it run for their weights alone (what
  // the next level's resampling reads): the MLP skips its colour head (view branch and rgb layer) and the render
  // writes no composite, so their comp_rgb stays unwritten while acc, distance and weights are the full forward's
  // values. With every_level_colour each level's colour is computed too (comparisons of the levels, tests), but a
  // proposal round's never (it has no colour: its comp_rgb stays unwritten).
  void render_chunk(const RaySource& source, ChunkRange chunk, StepKey key = {}, uint32_t first_ray_number = 0);
  void set_every_level_colour(bool every_level) { every_level_colour_ = every_level; }
  const LevelOutputs& level_outputs(size_t level) const { return levels_.at(level).outputs; }

 private:
  struct LevelBuffers {
    size_t intervals = 0;
    ocl::DeviceArray<float> t_edges;   // [R][N+1]
    ocl::DeviceArray<float> s_edges;   // [R][N+1] normalised (proposal-sampled levels only)
    ocl::DeviceArray<float> weights;   // [R][N]
    ocl::DeviceArray<float> partials;  // [slots][2] loss sums per work-group (training, colour levels)
    // A proposal round's own, kept from its forward to its backward after the last level (training only; rendering
    // uses the shared chunk buffers).
    ocl::DeviceArray<float> features;     // [R·N][its grid's width]
    ocl::DeviceArray<float> raw_density;  // [R·N]
    ocl::DeviceArray<float> ray_loss;     // [B] its interlevel loss per ray of the batch, Σ over its intervals
    LevelOutputs outputs;
  };

  // Ray i of the chunk draws its sub-pixel jitter (when compiled in) as ray number first_ray + i.
  void generate_rays(const RaySource& source, ChunkRange chunk, StepKey key, uint32_t first_ray);
  void sample_level(size_t level, size_t n_rays, StepKey key, uint32_t first_ray);
  // `key` draws a grid level's multisample patterns (training graphs only).
  void encode_level(size_t level, size_t n_rays, const RngKey& key);
  void grid_level_scales();  // every grid's level_scale from its current table
  // `noise` keys the level's density noise (RenderOptions::density_noise; training graphs only). Without
  // `with_colour` (inference only) the level's density alone: its weights, acc and distance, no comp_rgb.
  void forward_level(size_t level, size_t n_rays, mlp::Workspace& ws, const DensityNoiseKey& noise,
                     bool with_colour = true);
  void backward_level(size_t level, size_t n_rays, const TrainTargets& targets, ChunkRange chunk,
                      const DensityNoiseKey& noise, const RngKey& key);
  // The last level's distortion loss over its s-edges (edges held: stop-gradient): the chunk's share of the batch's
  // per-ray losses, and ∂loss/∂weights into d_w_distortion_ for the render backward.
  void distortion_backward(size_t level, ChunkRange chunk);
  // A proposal round's backward (after the last level's): interlevel loss and ∂loss/∂weights → raw density →
  // network (density only) → grid.
  void backward_proposal(size_t level, ChunkRange chunk, const DensityNoiseKey& noise, const RngKey& key);
  // The features and raw density a level's forward writes: a training proposal round's own, else the shared ones.
  ocl::DeviceArray<float>& level_features(size_t level);
  ocl::DeviceArray<float>& level_raw_density(size_t level);

  ocl::Context* ctx_;
  GraphSpec spec_;
  std::vector<mlp::Network*> networks_;
  std::vector<mlp::GridTable*> grids_;
  GraphMode mode_;
  size_t max_chunk_rays_;
  size_t max_batch_rays_;
  bool every_level_colour_ = false;  // rendering: also the colour of levels before the last

  // Stages (each builds its specialisation once).
  std::unique_ptr<ops::Rays> rays_;
  // The ray stage with LENS_TABLES, built the first time a source brings lens tables: pinhole scenes never pay for it.
  std::unique_ptr<ops::Rays> lens_rays_;
  std::unique_ptr<ops::Sample> sample_;
  std::unique_ptr<ops::Resample> resample_;
  std::unique_ptr<ops::Gaussian> gaussian_;
  std::unique_ptr<ops::Encode> encode_;
  std::unique_ptr<ops::ContractedIpe> contracted_ipe_;  // when a level encodes contracted frustums (mip-NeRF 360)
  std::unique_ptr<ops::Render> render_;
  std::unique_ptr<ops::Loss> loss_;
  std::vector<std::unique_ptr<ops::ZipFeatures>> zip_;  // one per grid (its features are compiled in)
  std::unique_ptr<ops::SampleIntervals> sample_intervals_;  // proposal sampling (when a level samples so)
  std::unique_ptr<ops::SplineInterlevel> interlevel_;       // Zip-NeRF proposal rounds' loss (training)
  std::unique_ptr<ops::OuterInterlevel> outer_interlevel_;  // mip-NeRF 360 proposal rounds' loss (training)
  std::unique_ptr<ops::Distortion> distortion_;             // the last level's distortion loss (training, when asked)
  ResampleOptions resample_options_;
  SampleIntervalsOptions sample_intervals_options_;  // anneal: the step's (training) or 1 (rendering)

  // Chunk buffers, R = max_chunk_rays, S = R · max intervals.
  ocl::DeviceArray<uint32_t> camera_ids_, pixel_ids_;  // [R]
  ops::RayBundle chunk_rays_;                          // R rays: the chunk's, from rays_
  ocl::DeviceArray<float> view_features_;              // [R][view width]
  ocl::DeviceArray<float> features_;                   // [S][position features]
  ocl::DeviceArray<float> means_, covs_;               // [S][3] (PE encodings only)
  ocl::DeviceArray<float> drawn_edges_;                // [R][new + 1] (union levels only)
  ocl::DeviceArray<float> raw_density_, raw_rgb_;      // [S], [S][3]
  ocl::DeviceArray<float> d_comp_rgb_;                 // [R][3] (training)
  ocl::DeviceArray<float> d_raw_density_, d_raw_rgb_;  // [S], [S][3] (training)
  ocl::DeviceArray<float> d_features_;                 // [S][F] (training with a grid level)
  std::vector<ocl::DeviceArray<float>> level_scales_;  // per grid: [its levels]
  // The distortion loss (training, when the last level has one): ∂/∂w [R][N], ∂/∂edges [R][N+1] (unused: the edges
  // take no gradient), the chunk's per-ray losses [R] and the batch's [B].
  ocl::DeviceArray<float> d_w_distortion_, d_t_distortion_, distortion_chunk_loss_, distortion_ray_loss_;
  // Proposal sampling: the first round's histogram, the whole ray [0, 1] with weight 1 (official initial sdist).
  ocl::DeviceArray<float> unit_s_edges_, unit_weights_;  // [R][2], [R]
  // mip-NeRF 360's dilation of a previous histogram before proposal sampling (when a level asks for it).
  std::unique_ptr<ops::MaxDilate> dilate_;
  ocl::DeviceArray<float> dilated_s_edges_, dilated_weights_;  // [R][3N−1], [R][3N−2]
  ocl::DeviceArray<uint32_t> dilate_scratch_;                  // [R][N] each ray's sliding-window deque
  // The proposal rounds' backward, shared (one round at a time), M = the rounds' most intervals.
  ocl::DeviceArray<float> w_blur_, d_wp_;      // [R][M]
  ocl::DeviceArray<float> chunk_ray_loss_;     // [R]
  ocl::DeviceArray<float> zero_d_raw_rgb_;     // [R·M][3] zeros: a round's colour head gets no gradient
  std::vector<LevelBuffers> levels_;
  // One per network for the levels that are not proposal rounds (a shared network's forward and backward follow each
  // other level by level), one per proposal round (its forward waits for the backward after the last level's, even when
  // the rounds share a network): workspace_slots().
  std::vector<mlp::Workspace> workspaces_;
  std::vector<size_t> level_workspace_;  // [levels]: index into workspaces_
  mlp::Workspace& workspace_of(size_t level) { return workspaces_[level_workspace_[level]]; }

  // The step in progress (training).
  size_t step_batch_rays_ = 0;
  double step_lossmult_sum_ = 0.0;
  size_t step_groups_ = 0;  // loss partial slots written so far this step
};

}  // namespace mipnerf::graph
