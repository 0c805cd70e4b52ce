// The training configuration: typed fields with the paper's defaults, and the one table of settings
// (name, help, parse, print) that flags, config files, presets, checkpoints and run records all use.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/enum_names.hpp"
#include "core/stage_options.hpp"
#include "gemm/gemm_backend.hpp"
#include "mlp/mlp_config.hpp"
#include "ops/batch.hpp"

namespace mipnerf::train {

// The `variant` setting: which family of model the levels are built from (train/model.cpp).
enum class ModelFamily {
  mipnerf,  // conical frustums: IPE of their Gaussians, N stratified then N resampled intervals
  nerf,     // points: PE of interval midpoints, N/2 stratified then N more merged with them (original NeRF)
  zipnerf,  // Zip-NeRF: each frustum's multisamples looked up in a multi-resolution grid, a tiny MLP (grid_* settings)
};
constexpr std::array<EnumName<ModelFamily>, 3> enum_names(ModelFamily) {
  return {{{ModelFamily::mipnerf, "mipnerf"}, {ModelFamily::nerf, "nerf"}, {ModelFamily::zipnerf, "zipnerf"}}};
}

// The `sampler` setting: how the levels after the first choose their intervals.
enum class Sampler {
  resample,  // mip-NeRF's: the next level resamples the previous one's weights, every level through the one network
  // Zip-NeRF's proposal rounds (zipnerf only): density-only networks on grids of their own, trained by the interlevel
  // loss, pick where the last level samples (proposal_* settings)
  proposal,
};
constexpr std::array<EnumName<Sampler>, 2> enum_names(Sampler) {
  return {{{Sampler::resample, "resample"}, {Sampler::proposal, "proposal"}}};
}

// The `data_loss` setting: each colour channel's term of the photometric loss (ops::LossOptions).
enum class DataLoss {
  mse,          // residual²: google/mipnerf's (the paper's)
  charbonnier,  // √(residual² + charb_padding²): mip-NeRF 360's and Zip-NeRF's official default
};
constexpr std::array<EnumName<DataLoss>, 2> enum_names(DataLoss) {
  return {{{DataLoss::mse, "mse"}, {DataLoss::charbonnier, "charbonnier"}}};
}

// The --variant bundles: rows of the paper's tables, each a set of settings (variants()).
enum class Variant {
  mipnerf,
  mipnerf_concat_pe,
  mipnerf_no_area_loss,
  mipnerf_no_ipe,
  mipnerf_no_misc,
  mipnerf_two_mlps,
  nerf,
  nerf_area,
  nerf_area_center,
  nerf_area_center_misc,
  zipnerf
};
// Alphabetical: the order --help and the unknown-variant error have always listed them in.
constexpr std::array<EnumName<Variant>, 11> enum_names(Variant) {
  return {{{Variant::mipnerf, "mipnerf"},
           {Variant::mipnerf_concat_pe, "mipnerf-concat-pe"},
           {Variant::mipnerf_no_area_loss, "mipnerf-no-area-loss"},
           {Variant::mipnerf_no_ipe, "mipnerf-no-ipe"},
           {Variant::mipnerf_no_misc, "mipnerf-no-misc"},
           {Variant::mipnerf_two_mlps, "mipnerf-two-mlps"},
           {Variant::nerf, "nerf"},
           {Variant::nerf_area, "nerf-area"},
           {Variant::nerf_area_center, "nerf-area-center"},
           {Variant::nerf_area_center_misc, "nerf-area-center-misc"},
           {Variant::zipnerf, "zipnerf"}}};
}

// Every setting of a run. Defaults are the paper's (mip-NeRF, Blender); see presets() for smaller ones.
struct TrainConfig {
  // --- scene: what the data calls for (each switch compiles a path in or out of the kernels) ---
  Background background = Background::white;  // white for Blender scenes (paper §5)
  bool opaque_background = false;  // the last interval takes what is left of each ray (mip-NeRF 360's 360.gin)
  int factor = 1;                    // box-downsample the stored images by this power of two first (lego 400 → 100: 4)
  bool multiscale = false;           // build ×2 ×4 ×8 box-downsampled copies of every image on the fly
  int multiscale_scales = 4;         // how many scales `multiscale` builds, full resolution included (paper: 4)
  bool area_loss = true;             // weight each pixel's loss by its area (lossmult); the "w/o area loss" ablation turns it off
  double near = 0.0;                 // sampling range in t; 0 takes the dataset's value (Blender: 2)
  double far = 0.0;                  // 0 takes the dataset's value (Blender: 6)
  RayShape ray_shape = RayShape::cone;  // cylinder: forward-facing scenes in NDC
  bool spherify = false;             // LLFF: re-pose a 360° capture around its centre (world rays, cones)
  // A scene without bounds (sampler = proposal, cones), through mip-NeRF 360's contraction into the ball of radius 2.
  // zipnerf (camp_zipnerf configs/zipnerf/360.gin): the grid's points contracted (grid_bound 2 unless given), proposal
  // sampling's s spaced by the power ladder (RayDistance::power_ladder), near 0 and far 1e6 unless given.
  // mipnerf (multinerf configs/360.gin): every level's frustums contracted and encoded on the icosahedron's 21
  // directions (Encoding::contracted_ipe), s spaced by the reciprocal (RayDistance::reciprocal), near 0.2, far 1e6.
  bool unbounded = false;
  bool lindisp = false;              // sample linearly in disparity instead of depth
  ops::Batching batching = ops::Batching::all_images;  // where a batch's rays come from
  double pixel_center = 0.5;         // rays through pixel centres (x + 0.5); original NeRF used 0 (corners)
  bool jitter_pixels = false;        // each training ray through a random point of its pixel (supersampling baselines)
  // View directions as unit vectors (official Blender, spherified LLFF); false: the world ray directions as they are
  // (camera-frame z = −1), as the official forward-facing LLFF loader passes them. Render and eval use the run's.
  bool unit_viewdirs = true;

  // --- model ---
  ModelFamily variant = ModelFamily::mipnerf;  // set by --variant's bundle (nerf for the NeRF baseline)
  int num_samples = 128;            // intervals per level (NeRF: coarse num_samples/2, fine num_samples on top)
  int num_levels = 2;               // coarse + fine
  bool single_mlp = true;           // one MLP shared by both levels (mip-NeRF) or one per level (NeRF)
  bool integrated_encoding = true;  // IPE of the frustum Gaussian; false = PE of its mean (the "w/o IPE" ablation)
  int pos_min_deg = 0;              // positional encoding degrees [min, max): L = 16 → 96 features
  int pos_max_deg = 16;
  bool pos_identity = false;        // append the raw position (NeRF does, mip-NeRF does not)
  // With integrated_encoding = false: PE degrees 0..cov_max_deg-1 of the frustum covariance's signed square roots,
  // concatenated to the PE of the means (supplement §7, Table 2: 2). 0 = the means alone ("w/o IPE").
  int cov_max_deg = 0;
  bool view_dependence = true;      // condition colour on the view direction (PE degrees 0..view_max_deg-1 + identity)
  int view_max_deg = 4;
  DensityActivation density_activation = DensityActivation::softplus;
  double density_bias = -1.0;       // added to the raw density before the activation
  // σ of the N(0, 1) noise added to the raw density before the activation while training, never when rendering
  // (official density_noise: 0 for Blender, the paper's setup; llff.gin: 1). 0 compiles it out.
  double density_noise = 0.0;
  double rgb_padding = 0.001;       // ε of the widened sigmoid (1 + 2ε)·sigmoid − ε
  double resample_padding = 0.01;   // α added to the blurred weights before resampling (mip-NeRF; NeRF: 0)
  bool resample_blur = true;        // blur-pool (max of neighbours, mean of pairs) before resampling (NeRF: false)
  int mlp_depth = 8;                // dense ReLU layers of the trunk
  int mlp_width = 256;
  int mlp_skip = 4;                 // the input is concatenated again after trunk layer index mlp_skip (0-based)
  int view_branch_width = 128;
  int bottleneck_width = 0;         // the layer feeding the view branch; 0 = the trunk's width (mip-NeRF's)
  // Every network's initial weights (mlp::WeightInit): Glorot's (google/mipnerf's) or He's (multinerf's, camp_zipnerf's)
  mlp::WeightInit weight_init = mlp::WeightInit::glorot_uniform;
  // Zip-NeRF's grid (variant zipnerf; camp_zipnerf's HashEncoding, its 360.gin values): levels of grid_min …
  // grid_max cells a side, 1 + grid_supersample · log2(grid_max / grid_min) of them, each a dense grid up to
  // 2^grid_hash_log2 cells and hashed into that many entries beyond; grid_features per level.
  int grid_min = 16;
  int grid_max = 8192;
  double grid_supersample = 1.0;
  int grid_hash_log2 = 21;
  int grid_features = 4;
  double grid_bound = 0.0;        // the grid covers [−b, b]³; 0 = from the scene (NDC: 1, world rays: 1.5)
  bool grid_multisample = true;   // each frustum's 6 multisamples (false: one point at its mean, same footprint)
  bool grid_downweight = true;    // fade each level by the multisample's footprint (false: a plain hash grid)
  bool grid_append_scale = true;  // append each level's footprint weight as a feature (official append_scale)
  // A multisample's footprint (the standard deviation its levels are faded by) = grid_scale_mult · its distance from
  // the axis (official unscented_scale_mult 0.5). With grid_multisample=false the one point stands for six whose
  // average also blurs by their hexagon's spread: √3 · 0.5 ≈ 0.866 gives the point the six's whole footprint.
  double grid_scale_mult = 0.5;
  double grid_weight_decay = 0.1;  // mult of each grid level's ½·mean(value²) in the loss (official param_regularizers)
  // Zip-NeRF's proposal sampling (sampler = proposal; camp_zipnerf configs/zipnerf/360.gin): proposal_rounds
  // density-only rounds of proposal_samples intervals each, then the NeRF level's num_samples (official
  // sampling_strategy ((0,0,64),(1,1,64),(2,2,32))). Each round has its own tiny MLP (mlp_depth × mlp_width, no colour
  // head: official disable_rgb) and its own grid of 1 feature a level (official num_features 1), the last round's
  // finest level proposal_grid_max cells a side and each earlier round's 4× coarser (official max_grid_size 512,
  // 2048); their loss is the spline interlevel loss, interlevel_mult per round (official mults 0.01), blurred by the
  // official half-widths (graph/proposal blur table in train/model.cpp), with weights annealed by Schlick's bias of
  // slope anneal_slope (official 10).
  // With --model mipnerf (mip-NeRF 360's sampler, multinerf's Model and PropMLP): every level encodes its frustums by
  // IPE, each round has a density-only MLP of proposal_mlp_depth × proposal_mlp_width (official 4 × 256), the NeRF
  // level the mip-NeRF MLP, and the rounds take mip-NeRF 360's outer interlevel loss (eq. 13).
  Sampler sampler = Sampler::resample;
  int proposal_rounds = 2;
  int proposal_samples = 64;
  int proposal_grid_max = 2048;
  int proposal_mlp_depth = 4;
  int proposal_mlp_width = 256;
  // mipnerf, sampler=proposal: the rounds share one network (multinerf's Model builds one PropMLP and calls it in
  // every round) instead of one each (this tool's first choice, kept as the default: its figures were measured so)
  bool proposal_mlp_shared = false;
  int basis_subdivisions = 2;  // unbounded mipnerf: the contracted IPE's directions (official 2: 21; GraphSpec)
  double anneal_slope = 10.0;
  double interlevel_mult = -1.0;  // < 0: the model's official (Zip-NeRF's spline loss 0.01, mip-NeRF 360's outer 1)
  // mip-NeRF 360's dilation of each proposal histogram before the next level samples from it: by dilation_bias +
  // dilation_mult / (the samples drawn by the levels before), in normalised s (official Model.dilation_bias 0.0025,
  // dilation_multiplier 0.5). < 0: the model's official (mip-NeRF 360 those; Zip-NeRF none: camp_zipnerf has none).
  double dilation_bias = -1.0;
  double dilation_mult = -1.0;
  // mip-NeRF 360's distortion loss (eq. 15) on the NeRF level's weights over normalised distance s, this weight (0 =
  // off; sampler = proposal only: its levels are drawn in s). Official camp_zipnerf 360.gin: 0.01 (on a curve of t).
  double distortion_mult = 0.0;

  // --- optimisation ---
  int batch_size = 4096;            // rays per step
  int64_t steps = 1000000;          // optimisation steps of the run (the schedule spans them)
  double lr_init = 5e-4;            // supplement eq. 24: log-linear from lr_init to lr_final ...
  double lr_final = 5e-6;
  int64_t lr_warmup_steps = 2500;   // ... times a sine warm-up from lr_warmup_mult over these steps
  double lr_warmup_mult = 0.01;
  double grad_max_norm = 0.0;       // clip the global gradient norm; 0 disables
  double adam_beta2 = 0.999;        // Adam's second-moment decay (flax default; Zip-NeRF: 0.99)
  double adam_epsilon = 1e-8;       // Adam's ε (flax default; Zip-NeRF: 1e-15)
  double coarse_loss_mult = 0.1;    // λ on the coarse level's loss
  // The photometric term (kernels/loss.cl): squared error or Charbonnier's (padding charb_padding, official 0.001), and
  // whether the channel sum is divided by 3 (multinerf's and camp_zipnerf's per-channel mean, which weighs the data
  // term against their interlevel and distortion losses; false: google/mipnerf's sum, which its λ and rates assume).
  DataLoss data_loss = DataLoss::mse;
  double charb_padding = 0.001;
  bool loss_channel_mean = false;
  bool randomized = true;           // jittered stratified sampling and resampling during training
  uint64_t seed = 20200823;         // everything random is a function of (seed, step, ray)

  // --- execution ---
  int chunk_rays = 0;               // rays per chunk of a training step; 0 chooses from device memory
  int render_chunk_rays = 4096;     // rays per chunk when rendering
  gemm::GemmBackend gemm_backend = gemm::GemmBackend::automatic;  // who runs the MLP's products (mlp/gemm_backend.hpp)
  int64_t log_every = 100;          // steps between CSV log rows and progress updates
  int64_t checkpoint_every = 1000;  // steps between checkpoints (one is always written at the end)
  int keep_checkpoints = 3;         // how many checkpoint files to keep
  int max_bad_steps = 5;            // consecutive non-finite steps before the run stops
  int val_views = 0;                // val views rendered at the end of training; 0 = all
  int64_t val_every = 0;            // steps between val scores on val_views views during training (val_log.csv); 0 = off

  // --- record, not a setting ---
  // The --variant bundle resolve_config applied, written to config.json and every checkpoint so a run says which
  // row of the paper's tables it is. Empty for configurations written before it was recorded (they load as
  // "unknown") and for configs not made by resolve_config. No flag, file or --set can change it, and
  // differences() leaves it out: runs with the same settings are the same run however they were spelled.
  std::optional<Variant> variant_bundle;
  // The scene effects `train` chose from the data (train/scene_effects.hpp), as the line it printed; recorded in
  // config.json and checkpoints as "scene_effects". A record, not a setting: empty when none was applied.
  std::string scene_effects;
  // The wall-clock budget `train --minutes` sized this run's steps by (train/step_budget.hpp), as the line it
  // printed: the measured s/step and the steps chosen. A record, not a setting (the steps are in `steps`): empty when
  // the steps were given.
  std::string time_budget;
  // A run of NDC rays (ray_shape = cylinder): the NDC map its training cameras share, 2·f/width and 2·f/height as the
  // ray kernel computes them in float, recorded by the trainer as "ndc_projection" so a render camera of another field
  // of view is mapped into the same NDC (RaysOptions::ndc_scale_x/y). {0, 0}: not recorded (each camera's own, as
  // runs written before it render).
  std::array<double, 2> ndc_projection{0.0, 0.0};
};

// One named setting: how to read it from text and write it back, with its help line.
struct Setting {
  std::string name;
  std::string help;   // one line; an enum setting's starts with its allowed values, "white | black | none: ..."
  std::string group;  // "scene", "model", "optimisation", "execution"
  std::string type = {};  // of its value, for --help: INT, FLOAT, BOOL or NAME (an enum's, listed in `help`)
};

// Every setting, in a stable order.
const std::vector<Setting>& settings();
// The setting called `name`; throws mipnerf::Error naming the closest settings ("did you mean") when there is none.
const Setting& find_setting(const std::string& name);

// Sets `name` from text; throws mipnerf::Error naming the setting, the value and the accepted values. This is
// where enum settings are parsed (by their name tables), so no later code sees an unknown value.
void set_value(TrainConfig& config, const std::string& name, const std::string& value);
// The setting's value as text (parsable by set_value).
std::string get_value(const TrainConfig& config, const std::string& name);

// Named bundles of settings, applied over the defaults: presets (sizes and budgets) and variants
// (the rows of the paper's tables). Both are data: name → {setting → value}.
using Bundle = std::map<std::string, std::string>;
const std::map<std::string, Bundle>& presets();
const std::map<std::string, Bundle>& variants();
// The variant bundle a preset is made for: "zipnerf" for fast (Zip-NeRF's), "mipnerf" for the others.
std::string preset_variant(const std::string& preset);

// Cells a side of proposal round `round`'s finest grid level (0 ≤ round < proposal_rounds): proposal_grid_max for the
// round before the NeRF level, each earlier round's 4× coarser (official max_grid_size 512, 2048).
int proposal_round_grid_max(const TrainConfig& c, int round);
// A one-line description of each preset and variant, for --help.
std::string describe_bundles();

// defaults → preset → variant → explicit settings (config file, then flags), recording the variant in
// variant_bundle. Unknown names and bad values throw mipnerf::Error saying which and what is accepted.
TrainConfig resolve_config(const std::string& preset, const std::string& variant,
                           const std::map<std::string, std::string>& explicit_settings);

// Checks the combination (positive sizes, ranges, sample counts vs the model family, ...).
void validate(const TrainConfig& config);

// All settings as a flat JSON object (checkpoints and run records hold it as such; enums by name, as the settings
// spell them) with "variant_bundle" after "variant" when recorded, and back: unknown keys and bad values throw
// mipnerf::Error naming `where`; a missing "variant_bundle" leaves it unknown (configurations written before it).
nlohmann::ordered_json config_json(const TrainConfig& config);
TrainConfig config_from_json(const nlohmann::json& object, const std::string& where);
// The same as text (OUT/config.json), and back from text.
std::string to_json(const TrainConfig& config);
TrainConfig from_json(const std::string& json_text, const std::string& where);

// Settings that differ between two configs, "name: a → b" each (for resume checks); variant_bundle is no setting.
std::vector<std::string> differences(const TrainConfig& a, const TrainConfig& b);

}  // namespace mipnerf::train
