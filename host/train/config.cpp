// The table of training settings, presets and variants, and their resolution into a TrainConfig.
#include "train/config.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <optional>
#include <sstream>
#include <variant>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "mlp/grid_table.hpp"
#include "core/suggest.hpp"

namespace mipnerf::train {
namespace {

using Member = std::variant<bool TrainConfig::*, int TrainConfig::*, int64_t TrainConfig::*, uint64_t TrainConfig::*,
                            double TrainConfig::*, Background TrainConfig::*, RayShape TrainConfig::*,
                            ops::Batching TrainConfig::*, ModelFamily TrainConfig::*, DensityActivation TrainConfig::*,
                            gemm::GemmBackend TrainConfig::*, Sampler TrainConfig::*,
                            DataLoss TrainConfig::*, mlp::WeightInit TrainConfig::*>;

// One row of the table. An enum setting's `help` says what it does; its allowed values are prepended from the
// enum's name table (with_full_help), so they are written once.
struct Entry {
  Setting setting;
  Member member;
};

constexpr const char* kVariantBundleKey = "variant_bundle";  // the record's JSON key (TrainConfig::variant_bundle)
constexpr const char* kSceneEffectsKey = "scene_effects";  // the record's JSON key (TrainConfig::scene_effects)
constexpr const char* kTimeBudgetKey = "time_budget";  // the record's JSON key (TrainConfig::time_budget)
constexpr const char* kNdcProjectionKey = "ndc_projection";  // the record's JSON key (TrainConfig::ndc_projection)

const std::vector<Entry>& table() {
  static const std::vector<Entry> entries = {
      {{"background", "what shows where the scene is empty", "scene"}, &TrainConfig::background},
      {{"opaque_background",
        "make each ray's last interval opaque, so its weights sum to 1 and no background shows (mip-NeRF 360's "
        "opaque_background, official for its 360-degree and forward-facing configs)",
        "model"},
       &TrainConfig::opaque_background},
      {{"factor", "box-downsample the stored images by this power of two first (official factor)", "scene"},
       &TrainConfig::factor},
      {{"multiscale", "build x2 x4 x8 box-downsampled copies of the data on the fly", "scene"},
       &TrainConfig::multiscale},
      {{"multiscale_scales", "scales the multiscale copy has, full resolution included (the paper's 4: x1 x2 x4 x8)",
        "scene"},
       &TrainConfig::multiscale_scales},
      {{"area_loss", "weight each pixel's loss by its area relative to full resolution", "scene"},
       &TrainConfig::area_loss},
      {{"near", "near bound of the sampling range in t (0 = from the dataset)", "scene"}, &TrainConfig::near},
      {{"far", "far bound of the sampling range in t (0 = from the dataset)", "scene"}, &TrainConfig::far},
      {{"ray_shape", "conical frustums, or cylinders in NDC space (forward-facing scenes)", "scene"},
       &TrainConfig::ray_shape},
      {{"spherify", "LLFF: re-pose a 360-degree capture around its centre (official spherify)", "scene"},
       &TrainConfig::spherify},
      {{"unbounded",
        "sampler=proposal: a scene without bounds (a 360-degree capture's background) through mip-NeRF 360's "
        "contraction into the ball of radius 2. zipnerf: each grid point contracted, samples spaced by camp_zipnerf's "
        "power ladder from near 0 to far 1e6 (explicit near, far and grid_bound win); mipnerf: mip-NeRF 360's model, "
        "each frustum's Gaussian contracted and its IPE taken on 21 directions (pos_max_deg 12 is the official), "
        "samples spaced in disparity from near 0.2 to far 1e6",
        "scene"},
       &TrainConfig::unbounded},
      {{"lindisp", "sample linearly in disparity instead of depth", "scene"}, &TrainConfig::lindisp},
      {{"batching", "a step's rays come from every image, or from one image", "scene"}, &TrainConfig::batching},
      {{"pixel_center", "offset of a pixel's ray inside the pixel (0.5 = centre)", "scene"},
       &TrainConfig::pixel_center},
      {{"jitter_pixels", "train on rays through random points of their pixels (supersampling)", "scene"},
       &TrainConfig::jitter_pixels},
      {{"unit_viewdirs",
        "normalise the view directions (false: the world ray directions as they are, as the official forward-facing "
        "LLFF loader passes them)",
        "scene"},
       &TrainConfig::unit_viewdirs},
      {{"variant", "model family: frustums with IPE, or NeRF's points with PE (--variant sets it)", "model"},
       &TrainConfig::variant},
      {{"num_samples", "intervals per level", "model"}, &TrainConfig::num_samples},
      {{"num_levels", "sampling levels (coarse + fine = 2)", "model"}, &TrainConfig::num_levels},
      {{"single_mlp", "one MLP shared by all levels", "model"}, &TrainConfig::single_mlp},
      {{"integrated_encoding", "IPE of frustum Gaussians (false: PE of their means)", "model"},
       &TrainConfig::integrated_encoding},
      {{"pos_min_deg", "lowest positional-encoding degree", "model"}, &TrainConfig::pos_min_deg},
      {{"pos_max_deg", "positional-encoding degrees end before this", "model"}, &TrainConfig::pos_max_deg},
      {{"pos_identity", "append the raw position to its encoding", "model"}, &TrainConfig::pos_identity},
      {{"cov_max_deg",
        "without IPE: PE degrees of the frustum covariance's signed square roots, concatenated to the PE of the means "
        "(supplement section 7; 0 = means only)",
        "model"},
       &TrainConfig::cov_max_deg},
      {{"view_dependence", "condition colour on the view direction", "model"}, &TrainConfig::view_dependence},
      {{"view_max_deg", "view-direction encoding degrees end before this", "model"}, &TrainConfig::view_max_deg},
      {{"density_activation", "activation of the raw density", "model"}, &TrainConfig::density_activation},
      {{"density_bias", "added to the raw density before its activation", "model"}, &TrainConfig::density_bias},
      {{"density_noise",
        "standard deviation of the normal noise added to the raw density before its activation while training "
        "(0 = off; official LLFF: 1)",
        "model"},
       &TrainConfig::density_noise},
      {{"rgb_padding", "epsilon of the widened colour sigmoid", "model"}, &TrainConfig::rgb_padding},
      {{"resample_padding", "alpha added to the weights before resampling", "model"}, &TrainConfig::resample_padding},
      {{"resample_blur", "blur-pool the weights before resampling", "model"}, &TrainConfig::resample_blur},
      {{"mlp_depth", "dense layers of the MLP trunk", "model"}, &TrainConfig::mlp_depth},
      {{"mlp_width", "width of the MLP trunk", "model"}, &TrainConfig::mlp_width},
      {{"mlp_skip", "trunk layer (0-based) after which the input is concatenated again", "model"},
       &TrainConfig::mlp_skip},
      {{"view_branch_width", "width of the view-dependent colour branch", "model"}, &TrainConfig::view_branch_width},
      {{"bottleneck_width",
        "units of the layer between the trunk and the view branch (0 = the trunk's width, mip-NeRF's; mip-NeRF 360: "
        "256 after a 1024-wide trunk)",
        "model"},
       &TrainConfig::bottleneck_width},
      {{"weight_init",
        "how every network's weights start, uniform on (-a, a): glorot_uniform a = sqrt(6/(in+out)) (google/mipnerf, "
        "the paper), he_uniform a = sqrt(6/in) (multinerf's and camp_zipnerf's MLPs); biases start at 0",
        "model"},
       &TrainConfig::weight_init},
      {{"grid_min", "zipnerf: cells a side of the grid's coarsest level", "model"}, &TrainConfig::grid_min},
      {{"grid_max", "zipnerf: cells a side of the grid's finest level", "model"}, &TrainConfig::grid_max},
      {{"grid_supersample", "zipnerf: levels per doubling of the grid size (official scale_supersample)", "model"},
       &TrainConfig::grid_supersample},
      {{"grid_hash_log2", "zipnerf: log2 of the entries of a hashed grid level (official hash_map_size 2^21)", "model"},
       &TrainConfig::grid_hash_log2},
      {{"grid_features", "zipnerf: features per grid level", "model"}, &TrainConfig::grid_features},
      {{"grid_bound", "zipnerf: the grid covers [-b, b]^3 (0 = from the scene: NDC 1, world rays 1.5)", "model"},
       &TrainConfig::grid_bound},
      {{"grid_multisample",
        "zipnerf: look up each frustum's 6 multisamples (false: one point at its mean with their mean footprint; with "
        "grid_downweight=false, a plain hash grid)",
        "model"},
       &TrainConfig::grid_multisample},
      {{"grid_downweight",
        "zipnerf: fade each grid level by the frustum's footprint (Zip-NeRF's anti-aliasing; false: a plain hash grid)",
        "model"},
       &TrainConfig::grid_downweight},
      {{"grid_append_scale", "zipnerf: append each level's footprint weight as a feature", "model"},
       &TrainConfig::grid_append_scale},
      {{"grid_scale_mult",
        "zipnerf: a multisample's footprint (the standard deviation each level is faded by) as a multiple of its "
        "distance from the ray's axis (official unscented_scale_mult 0.5; with grid_multisample=false, 0.866 gives the "
        "one point the whole footprint of the six it stands for)",
        "model"},
       &TrainConfig::grid_scale_mult},
      {{"grid_weight_decay", "zipnerf: weight of each grid level's mean squared value in the loss", "optimisation"},
       &TrainConfig::grid_weight_decay},
      {{"sampler",
        "how later levels choose their intervals: resampling the previous level's weights (mip-NeRF), or proposal "
        "rounds (density-only networks trained by an interlevel loss: Zip-NeRF's on grids of their own, mip-NeRF "
        "360's on the IPE)",
        "model"},
       &TrainConfig::sampler},
      {{"proposal_rounds", "sampler=proposal: density-only proposal rounds before the NeRF level (official 2)", "model"},
       &TrainConfig::proposal_rounds},
      {{"proposal_samples", "sampler=proposal: intervals each proposal round draws (official 64)", "model"},
       &TrainConfig::proposal_samples},
      {{"proposal_grid_max",
        "sampler=proposal: cells a side of the last round's finest grid level; each earlier round's is 4x coarser "
        "(official 2048, 512)",
        "model"},
       &TrainConfig::proposal_grid_max},
      {{"proposal_mlp_depth", "mipnerf, sampler=proposal: layers of each proposal round's MLP (official mip-NeRF 360: 4)",
        "model"},
       &TrainConfig::proposal_mlp_depth},
      {{"proposal_mlp_width", "mipnerf, sampler=proposal: units per layer of each proposal round's MLP (official 256)",
        "model"},
       &TrainConfig::proposal_mlp_width},
      {{"proposal_mlp_shared",
        "mipnerf, sampler=proposal: every proposal round through one network (multinerf's mip-NeRF 360: one PropMLP) "
        "instead of one network each",
        "model"},
       &TrainConfig::proposal_mlp_shared},
      {{"basis_subdivisions",
        "mipnerf, unbounded: how often the icosahedron's faces are tessellated for the directions its contracted IPE "
        "projects onto (official 2: 21 directions, 504 features at pos_max_deg 12; 1: 6 directions, 144)",
        "model"},
       &TrainConfig::basis_subdivisions},
      {{"anneal_slope",
        "sampler=proposal: slope of Schlick's bias annealing the proposal weights over training (<= 0: off; official "
        "10)",
        "model"},
       &TrainConfig::anneal_slope},
      {{"interlevel_mult",
        "sampler=proposal: weight of each proposal round's interlevel loss (< 0: the official, Zip-NeRF 0.01, "
        "mip-NeRF 360 1)",
        "optimisation"},
       &TrainConfig::interlevel_mult},
      {{"dilation_bias",
        "sampler=proposal: dilation of each proposal histogram before the next level samples it, plus dilation_mult / "
        "the samples before (< 0: the official, mip-NeRF 360 0.0025, Zip-NeRF 0)",
        "model"},
       &TrainConfig::dilation_bias},
      {{"dilation_mult",
        "sampler=proposal: see dilation_bias (< 0: the official, mip-NeRF 360 0.5, Zip-NeRF 0)", "model"},
       &TrainConfig::dilation_mult},
      {{"distortion_mult",
        "sampler=proposal: weight of mip-NeRF 360's distortion loss on the NeRF level's weights over normalised "
        "distance (against floaters; 0 = off; official Zip-NeRF 360° scenes 0.01)",
        "optimisation"},
       &TrainConfig::distortion_mult},
      {{"batch_size", "rays per optimisation step", "optimisation"}, &TrainConfig::batch_size},
      {{"steps", "optimisation steps of the run", "optimisation"}, &TrainConfig::steps},
      {{"lr_init", "initial learning rate", "optimisation"}, &TrainConfig::lr_init},
      {{"lr_final", "final learning rate", "optimisation"}, &TrainConfig::lr_final},
      {{"lr_warmup_steps", "steps of the sine warm-up", "optimisation"}, &TrainConfig::lr_warmup_steps},
      {{"lr_warmup_mult", "learning-rate multiplier at step 0 of the warm-up", "optimisation"},
       &TrainConfig::lr_warmup_mult},
      {{"grad_max_norm", "clip the global gradient norm (0 = off)", "optimisation"}, &TrainConfig::grad_max_norm},
      {{"adam_beta2", "Adam's second-moment decay", "optimisation"}, &TrainConfig::adam_beta2},
      {{"adam_epsilon", "Adam's epsilon", "optimisation"}, &TrainConfig::adam_epsilon},
      {{"coarse_loss_mult", "lambda: weight of the coarse level's loss", "optimisation"},
       &TrainConfig::coarse_loss_mult},
      {{"data_loss",
        "each colour channel's loss term: the squared error (mip-NeRF's), or Charbonnier's sqrt(residual^2 + "
        "charb_padding^2) (mip-NeRF 360's and Zip-NeRF's)",
        "optimisation"},
       &TrainConfig::data_loss},
      {{"charb_padding", "data_loss=charbonnier: the padding (official 0.001)", "optimisation"},
       &TrainConfig::charb_padding},
      {{"loss_channel_mean",
        "divide the photometric loss's channel sum by 3 (multinerf's and camp_zipnerf's per-channel mean, which sets "
        "its weight against their interlevel and distortion losses; false: mip-NeRF's sum)",
        "optimisation"},
       &TrainConfig::loss_channel_mean},
      {{"randomized", "jitter samples during training", "optimisation"}, &TrainConfig::randomized},
      {{"seed", "seed of every random choice", "optimisation"}, &TrainConfig::seed},
      {{"chunk_rays", "rays per chunk of a training step (0 = from device memory)", "execution"},
       &TrainConfig::chunk_rays},
      {{"render_chunk_rays", "rays per chunk when rendering", "execution"}, &TrainConfig::render_chunk_rays},
      {{"gemm_backend",
        "who runs the MLP's matrix products: CLBlast, or the CPU BLAS on the buffers of a device that shares host "
        "memory (auto: host on such CPU devices)",
        "execution"},
       &TrainConfig::gemm_backend},
      {{"log_every", "steps between log rows", "execution"}, &TrainConfig::log_every},
      {{"checkpoint_every", "steps between checkpoints", "execution"}, &TrainConfig::checkpoint_every},
      {{"keep_checkpoints", "checkpoint files to keep", "execution"}, &TrainConfig::keep_checkpoints},
      {{"max_bad_steps", "consecutive non-finite steps before stopping", "execution"}, &TrainConfig::max_bad_steps},
      {{"val_views", "val views rendered after training (0 = all)", "execution"}, &TrainConfig::val_views},
      {{"val_every",
        "steps between val scores on val_views views during training, written to val_log.csv and timed apart from "
        "training (0 = off)",
        "execution"},
       &TrainConfig::val_every},
  };
  return entries;
}

const Entry& find(const std::string& name) {
  for (const auto& e : table()) {
    if (e.setting.name == name) return e;
  }
  // The nearest names, not the whole list: 54 names would hide them (--help has the list, with what each does).
  std::vector<std::string> names;
  for (const auto& e : table()) names.push_back(e.setting.name);
  const std::string hint = did_you_mean(name, names);
  throw Error("unknown setting '" + name + "'" + (hint.empty() ? "" : "; " + hint) +
              " (mipnerf-cl train --help lists every setting)");
}

[[noreturn]] void bad_value(const std::string& name, const std::string& value, const std::string& expected) {
  throw Error("setting '" + name + "' = '" + value + "': expected " + expected);
}

bool parse_bool(const std::string& name, const std::string& v) {
  if (v == "true" || v == "1" || v == "yes" || v == "on") return true;
  if (v == "false" || v == "0" || v == "no" || v == "off") return false;
  bad_value(name, v, "true or false");
}

long long parse_integer(const std::string& name, const std::string& v) {
  errno = 0;
  char* end = nullptr;
  const long long parsed = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno == ERANGE) bad_value(name, v, "an integer");
  return parsed;
}

double parse_double(const std::string& name, const std::string& v) {
  errno = 0;
  char* end = nullptr;
  const double parsed = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(parsed)) bad_value(name, v, "a finite number");
  return parsed;
}

std::string format_double(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

template <typename E>
E parse_enum(const std::string& name, const std::string& v) {
  const std::optional<E> parsed = enum_from_name<E>(v);
  if (!parsed) bad_value(name, v, enum_choices<E>());
  return *parsed;
}

// The entry as --help shows it: an enum setting's allowed values, then what it does; the type of its value.
Setting with_full_help(const Entry& e) {
  Setting s = e.setting;
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(TrainConfig{}.*member)>;
        if constexpr (has_enum_names_v<T>) {
          s.help = enum_choices<T>() + ": " + s.help;
          s.type = "NAME";
        } else if constexpr (std::is_same_v<T, bool>) {
          s.type = "BOOL";
        } else if constexpr (std::is_same_v<T, double>) {
          s.type = "FLOAT";
        } else {
          s.type = "INT";
        }
      },
      e.member);
  return s;
}

Variant parse_variant(const std::string& name) {
  const std::optional<Variant> parsed = enum_from_name<Variant>(name);
  if (!parsed) throw Error("unknown variant '" + name + "'; the variants are: " + enum_choices<Variant>(", "));
  return *parsed;
}

// A configuration JSON's "variant_bundle": a --variant name; anything else names the file and what is accepted.
Variant variant_bundle_from_json(const nlohmann::json& value, const std::string& where) {
  const std::string text = value.is_string() ? value.get<std::string>() : value.dump();
  const std::optional<Variant> parsed = enum_from_name<Variant>(text);
  if (!parsed) {
    throw Error(where + ": '" + kVariantBundleKey + "' = '" + text + "': expected " + enum_choices<Variant>());
  }
  return *parsed;
}

}  // namespace

const std::vector<Setting>& settings() {
  static const std::vector<Setting> list = [] {
    std::vector<Setting> out;
    for (const auto& e : table()) out.push_back(with_full_help(e));
    return out;
  }();
  return list;
}

const Setting& find_setting(const std::string& name) {
  const Entry& entry = find(name);
  return settings()[static_cast<size_t>(&entry - table().data())];
}

void set_value(TrainConfig& config, const std::string& name, const std::string& value) {
  const Entry& e = find(name);
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(config.*member)>;
        if constexpr (has_enum_names_v<T>) {
          config.*member = parse_enum<T>(name, value);
        } else if constexpr (std::is_same_v<T, bool>) {
          config.*member = parse_bool(name, value);
        } else if constexpr (std::is_same_v<T, double>) {
          config.*member = parse_double(name, value);
        } else if constexpr (std::is_same_v<T, uint64_t>) {
          if (!value.empty() && value[0] == '-') bad_value(name, value, "a non-negative integer");
          errno = 0;
          char* end = nullptr;
          const unsigned long long parsed = std::strtoull(value.c_str(), &end, 10);
          if (value.empty() || *end != '\0' || errno == ERANGE) bad_value(name, value, "a non-negative integer");
          config.*member = parsed;
        } else {
          const long long parsed = parse_integer(name, value);
          if (parsed < static_cast<long long>(std::numeric_limits<T>::min()) ||
              parsed > static_cast<long long>(std::numeric_limits<T>::max())) {
            bad_value(name, value, "an integer in range");
          }
          config.*member = static_cast<T>(parsed);
        }
      },
      e.member);
}

std::string get_value(const TrainConfig& config, const std::string& name) {
  const Entry& e = find(name);
  return std::visit(
      [&](auto member) -> std::string {
        using T = std::decay_t<decltype(config.*member)>;
        if constexpr (has_enum_names_v<T>) {
          return enum_name(config.*member);
        } else if constexpr (std::is_same_v<T, bool>) {
          return config.*member ? "true" : "false";
        } else if constexpr (std::is_same_v<T, double>) {
          return format_double(config.*member);
        } else {
          return std::to_string(config.*member);
        }
      },
      e.member);
}

const std::map<std::string, Bundle>& presets() {
  // Sizes and budgets. `paper` is exactly the paper's settings (the defaults); the others trade
  // accuracy for time on small devices (see README: "Presets" for their measured cost).
  static const std::map<std::string, Bundle> bundles = {
      {"paper", {}},
      {"tiny",  // the test suite's: trains a few hundred steps of a 64×64 scene in under a minute
       {{"num_samples", "16"}, {"mlp_depth", "4"}, {"mlp_width", "64"}, {"mlp_skip", "2"},
        {"view_branch_width", "32"}, {"pos_max_deg", "10"}, {"batch_size", "256"}, {"steps", "300"},
        {"lr_init", "2e-3"}, {"lr_final", "2e-4"}, {"lr_warmup_steps", "20"}, {"log_every", "25"},
        {"checkpoint_every", "100"}, {"val_views", "2"}}},
      {"quick",  // the README's quick start: about 5 minutes on two CPU cores (307k rays at ~900 rays/s, tuned GEMMs)
       {{"num_samples", "32"}, {"mlp_depth", "4"}, {"mlp_width", "128"}, {"mlp_skip", "2"},
        {"view_branch_width", "64"}, {"pos_max_deg", "12"}, {"batch_size", "512"}, {"steps", "600"},
        {"lr_init", "2e-3"}, {"lr_final", "5e-5"}, {"lr_warmup_steps", "50"}, {"log_every", "50"},
        {"checkpoint_every", "200"}, {"val_views", "4"},
        // sampler=proposal (a 360° capture's mip-NeRF 360): proposal MLPs 4×64 and rounds of 32 instead of the
        // official 4×256 and 64, the best at equal time on flower and on the 360° scene (bench/results/
        // proposal_sampling, unbounded_mipnerf)
        {"proposal_mlp_width", "64"}, {"proposal_samples", "32"}}},
      {"small",  // the paper's depth at half width: under an hour on two CPU cores (2M rays at ~750 rays/s)
       {{"num_samples", "32"}, {"mlp_depth", "8"}, {"mlp_width", "128"}, {"view_branch_width", "64"},
        {"batch_size", "1024"}, {"steps", "2000"}, {"lr_init", "1e-3"}, {"lr_final", "1e-5"},
        {"lr_warmup_steps", "200"}, {"log_every", "100"}, {"checkpoint_every", "500"}, {"val_views", "8"}}},
      // mip-NeRF 360 exactly (multinerf configs/360.gin and the Config defaults it keeps): proposal rounds of 64 through
      // one 4×256 density MLP, the NeRF level's 32 on an 8×1024 MLP with a 256 bottleneck, contraction with the reciprocal
      // warp, an opaque background, Charbonnier's loss as a per-channel mean, Adam ε 1e-6, the gradient clipped to norm
      // 1e-3, 2e-3 → 2e-5 over 250,000 steps after a 512-step warm-up, 16,384 rays a step, He-uniform weights. Days a
      // scene on a GPU.
      {"mipnerf360",
       {{"sampler", "proposal"}, {"unbounded", "true"}, {"opaque_background", "true"}, {"num_samples", "32"},
        {"proposal_rounds", "2"}, {"proposal_samples", "64"}, {"proposal_mlp_depth", "4"},
        {"proposal_mlp_width", "256"}, {"proposal_mlp_shared", "true"}, {"weight_init", "he_uniform"},
        {"mlp_depth", "8"}, {"mlp_width", "1024"}, {"mlp_skip", "4"},
        {"bottleneck_width", "256"}, {"view_branch_width", "128"}, {"pos_max_deg", "12"}, {"view_max_deg", "4"},
        {"basis_subdivisions", "2"}, {"distortion_mult", "0.01"}, {"data_loss", "charbonnier"},
        {"charb_padding", "0.001"}, {"loss_channel_mean", "true"}, {"batch_size", "16384"}, {"steps", "250000"},
        {"lr_init", "2e-3"}, {"lr_final", "2e-5"}, {"lr_warmup_steps", "512"}, {"lr_warmup_mult", "0.01"},
        {"adam_beta2", "0.999"}, {"adam_epsilon", "1e-6"}, {"grad_max_norm", "1e-3"}, {"checkpoint_every", "25000"}}},
      // Zip-NeRF's for two CPU cores (--model zipnerf picks it): a smaller grid, fewer samples, and one footprint-
      // weighted point per interval instead of 6 multisamples (bench/results/time_to_quality: +1.2 to +2.4 dB on
      // flower at every budget; zip_antialiasing: the multisamples' 5.9x dearer steps lose at equal time).
      {"fast",
       {{"num_samples", "32"}, {"grid_multisample", "false"}, {"grid_max", "2048"}, {"grid_hash_log2", "17"},
        {"batch_size", "1024"},
        {"steps", "3000"}, {"lr_init", "1e-2"}, {"lr_final", "5e-4"}, {"lr_warmup_steps", "100"},
        {"log_every", "100"}, {"checkpoint_every", "500"}, {"val_views", "4"}}},
  };
  return bundles;
}

namespace {
// Rows of the paper's tables. The NeRF baseline follows the original NeRF: point samples with PE of
// degree 0..9 plus identity, a coarse and a fine MLP, ReLU density, plain sigmoid, resampling without
// blur or padding, fine samples added to the coarse ones, corner-offset pixels, no area loss.
// A bundle less some of its settings: those keep their defaults, which are mip-NeRF's.
Bundle without(Bundle bundle, std::initializer_list<const char*> names) {
  for (const char* name : names) bundle.erase(name);
  return bundle;
}

Bundle variant_settings(Variant variant) {
  switch (variant) {
    case Variant::mipnerf:
      return {};
    case Variant::nerf:
      return {{"variant", "nerf"},        {"single_mlp", "false"},  {"integrated_encoding", "false"},
              {"pos_max_deg", "10"},      {"pos_identity", "true"}, {"density_activation", "relu"},
              {"density_bias", "0"},      {"rgb_padding", "0"},     {"resample_padding", "0"},
              {"resample_blur", "false"}, {"pixel_center", "0"},    {"area_loss", "false"}};
    case Variant::mipnerf_no_ipe:  // w/o IPE
      return {{"integrated_encoding", "false"}};
    case Variant::mipnerf_two_mlps:  // w/o the single MLP
      return {{"single_mlp", "false"}};
    case Variant::mipnerf_no_misc:  // w/o misc.
      return {{"density_activation", "relu"}, {"density_bias", "0"}, {"rgb_padding", "0"}};
    case Variant::mipnerf_no_area_loss:  // w/o the area loss
      return {{"area_loss", "false"}};
    case Variant::mipnerf_concat_pe:  // supplement §7, Table 2: PE (L = 12) of the mean ++ PE (L = 2) of √Σ
      return {{"integrated_encoding", "false"}, {"pos_max_deg", "12"}, {"cov_max_deg", "2"}};
    // Table 3's rows below mip-NeRF, each one more change to the NeRF baseline: the area loss, then pixel centres
    // at +0.5, then "misc" (softplus(x − 1) density and the widened sigmoid: what mipnerf-no-misc takes away).
    case Variant::nerf_area:
      return without(variant_settings(Variant::nerf), {"area_loss"});
    case Variant::nerf_area_center:
      return without(variant_settings(Variant::nerf_area), {"pixel_center"});
    case Variant::nerf_area_center_misc:
      return without(variant_settings(Variant::nerf_area_center),
                     {"density_activation", "density_bias", "rgb_padding"});
    // Zip-NeRF (camp_zipnerf configs/zipnerf/360.gin): the grid's features into a tiny MLP (one hidden layer of 64),
    // a 64-wide view branch, Adam with β2 = 0.99 and ε = 1e-15. Sizes and learning rates come from the preset.
    case Variant::zipnerf:
      return {{"variant", "zipnerf"}, {"mlp_depth", "1"}, {"mlp_width", "64"}, {"mlp_skip", "0"},
              {"view_branch_width", "64"}, {"adam_beta2", "0.99"}, {"adam_epsilon", "1e-15"}};
  }
  throw Error("internal error: variant " + std::to_string(static_cast<int>(variant)) + " has no settings");
}
}  // namespace

const std::map<std::string, Bundle>& variants() {
  static const std::map<std::string, Bundle> bundles = [] {
    std::map<std::string, Bundle> out;
    for (const auto& row : enum_names(Variant{})) out[row.name] = variant_settings(row.value);
    return out;
  }();
  return bundles;
}

std::string preset_variant(const std::string& preset) { return preset == "fast" ? "zipnerf" : "mipnerf"; }

int proposal_round_grid_max(const TrainConfig& c, int round) {
  return c.proposal_grid_max >> (2 * (c.proposal_rounds - 1 - round));
}

std::string describe_bundles() {
  std::string out = "presets:";
  for (const auto& [name, b] : presets()) out += " " + name;
  out += "; variants:";
  for (const auto& [name, b] : variants()) out += " " + name;
  return out;
}

namespace {
const Bundle& find_bundle(const std::map<std::string, Bundle>& bundles, const std::string& name, const char* kind) {
  auto found = bundles.find(name);
  if (found != bundles.end()) return found->second;
  std::string names;
  for (const auto& [n, b] : bundles) names += (names.empty() ? "" : ", ") + n;
  throw Error(std::string("unknown ") + kind + " '" + name + "'; the " + kind + "s are: " + names);
}
}  // namespace

TrainConfig resolve_config(const std::string& preset, const std::string& variant,
                           const std::map<std::string, std::string>& explicit_settings) {
  TrainConfig config;
  for (const auto& [name, value] : find_bundle(presets(), preset, "preset")) set_value(config, name, value);
  const Variant parsed_variant = parse_variant(variant);
  for (const auto& [name, value] : variant_settings(parsed_variant)) set_value(config, name, value);
  for (const auto& [name, value] : explicit_settings) set_value(config, name, value);
  config.variant_bundle = parsed_variant;
  if (preset_variant(preset) == "zipnerf" && config.variant != ModelFamily::zipnerf) {
    throw Error("the fast preset is Zip-NeRF's (a grid and a tiny MLP): give --model zipnerf with it, or a mip-NeRF "
                "preset (quick, small, paper, mipnerf360) without");
  }
  try {
    validate(config);
  } catch (const Error& e) {
    // A row of the paper's tables on mip-NeRF 360's sampler: say which two were combined, not only the setting.
    if (preset != "mipnerf360" || parsed_variant == Variant::mipnerf) throw;
    throw Error("the mipnerf360 preset (mip-NeRF 360's proposal sampler on the contracted IPE) does not combine with "
                "--variant " + variant + ": " + e.what());
  }
  return config;
}

void validate(const TrainConfig& c) {
  auto require = [](bool ok, const std::string& message) {
    if (!ok) throw Error("invalid configuration: " + message);
  };
  require(c.factor >= 1 && c.factor <= 64 && (c.factor & (c.factor - 1)) == 0, "factor must be a power of two, 1 to 64");
  require(c.num_samples >= 2, "num_samples must be at least 2");
  require(c.multiscale_scales >= 2 && c.multiscale_scales <= 8, "multiscale_scales must be in 2..8");
  require(c.num_levels >= 1, "num_levels must be at least 1");
  require(c.variant != ModelFamily::nerf || c.num_samples % 2 == 0,
          "the nerf variant needs an even num_samples (coarse = half)");
  require(c.pos_max_deg > c.pos_min_deg && c.pos_min_deg >= 0, "need 0 <= pos_min_deg < pos_max_deg");
  require(c.pos_max_deg <= 24, "pos_max_deg above 24 makes 2^deg exceed float32's exact integers");
  require(c.cov_max_deg >= 0 && c.cov_max_deg <= 24, "cov_max_deg must be in 0..24");
  require(c.cov_max_deg == 0 || (!c.integrated_encoding && c.variant == ModelFamily::mipnerf),
          "cov_max_deg (the concatenated PE of the covariance) needs integrated_encoding = false and the mipnerf "
          "model family (frustums, not NeRF's points)");
  require(c.view_max_deg >= 1, "view_max_deg must be at least 1");
  require(c.grid_hash_log2 >= 4 && c.grid_hash_log2 <= 26, "grid_hash_log2 must be in 4..26");
  if (c.variant == ModelFamily::zipnerf) {
    mlp::GridConfig grid;
    grid.min_grid_size = c.grid_min;
    grid.max_grid_size = c.grid_max;
    grid.scale_supersample = c.grid_supersample;
    grid.features = c.grid_features;
    try {
      grid.validate();
    } catch (const Error& e) {
      require(false, e.what());
    }
  }
  require(c.distortion_mult >= 0, "distortion_mult must be >= 0 (0 = off)");
  require(c.distortion_mult == 0 || c.sampler == Sampler::proposal,
          "distortion_mult needs sampler=proposal (the distortion loss is taken over the normalised distances its "
          "levels are drawn in): add --set sampler=proposal, or leave distortion_mult at 0");
  if (c.sampler == Sampler::proposal) {
    require(c.variant != ModelFamily::nerf,
            "sampler=proposal is Zip-NeRF's and mip-NeRF 360's (density-only proposal networks on grids or on the IPE); "
            "the nerf model family samples points by resampling: keep sampler=resample, or train --model mipnerf or "
            "zipnerf");
    require(c.variant == ModelFamily::zipnerf || c.integrated_encoding,
            "sampler=proposal with --model mipnerf encodes every level by IPE (mip-NeRF 360): leave "
            "integrated_encoding=true");
    require(c.proposal_rounds >= 1 && c.proposal_rounds <= 4, "proposal_rounds must be in 1..4 (official 2)");
    require(c.proposal_samples >= 2, "proposal_samples must be at least 2 (proposal sampling draws >= 2 intervals)");
    require(c.proposal_mlp_depth >= 1 && c.proposal_mlp_width >= 1, "proposal_mlp_depth and _width must be positive");
    require(!c.proposal_mlp_shared || c.variant == ModelFamily::mipnerf,
            "proposal_mlp_shared is mip-NeRF 360's (one PropMLP on the IPE of every round); Zip-NeRF's rounds each read "
            "a grid of their own through their own network: leave proposal_mlp_shared=false with --model zipnerf");
    mlp::GridConfig grid;
    grid.min_grid_size = c.grid_min;
    grid.scale_supersample = c.grid_supersample;
    grid.features = 1;
    for (int round = 0; c.variant == ModelFamily::zipnerf && round < c.proposal_rounds; ++round) {
      grid.max_grid_size = proposal_round_grid_max(c, round);
      try {
        grid.validate();
      } catch (const Error& e) {
        require(false, "proposal_grid_max = " + std::to_string(c.proposal_grid_max) + " gives proposal round " +
                           std::to_string(round) + " a finest grid of " + std::to_string(grid.max_grid_size) +
                           " cells (each earlier round 4x coarser): " + e.what());
      }
    }
  }
  if (c.unbounded) {
    require(c.variant != ModelFamily::nerf,
            "unbounded is mip-NeRF 360's contraction of frustums (mipnerf) or of grid points (zipnerf): the nerf "
            "baseline has neither; train with --model mipnerf or zipnerf, or leave unbounded=false");
    require(c.sampler == Sampler::proposal,
            "unbounded needs sampler=proposal (its samples are spaced in the normalised distance proposal sampling "
            "draws): add --set sampler=proposal");
    require(c.ray_shape == RayShape::cone,
            "unbounded needs ray_shape=cone (world rays): NDC's cylinders are a forward-facing capture's, bounded "
            "already");
  }
  require(c.basis_subdivisions >= 1 && c.basis_subdivisions <= 8,
          "basis_subdivisions must be 1 to 8 (the icosahedron tessellated 1 to 8 times: 6 to 321 directions)");
  require(c.grid_bound >= 0, "grid_bound must be >= 0 (0 = from the scene)");
  require(c.grid_weight_decay >= 0, "grid_weight_decay must be >= 0");
  require(c.grid_scale_mult > 0 && c.grid_scale_mult <= 100,
          "grid_scale_mult must be in (0, 100] (the official 0.5; grid_downweight=false turns the fading off)");
  require(c.adam_beta2 > 0 && c.adam_beta2 < 1 && c.adam_epsilon > 0, "need 0 < adam_beta2 < 1 and adam_epsilon > 0");
  require(c.mlp_depth >= 1 && c.mlp_width >= 1 && c.view_branch_width >= 1, "MLP sizes must be positive");
  require(c.mlp_skip >= 0, "mlp_skip must be >= 0 (use a value >= mlp_depth for no skip)");
  require(c.batch_size >= 1, "batch_size must be positive");
  require(c.steps >= 1, "steps must be positive");
  require(c.lr_init > 0 && c.lr_final > 0, "learning rates must be positive");
  require(c.lr_warmup_steps >= 0, "lr_warmup_steps must be >= 0");
  require(c.lr_warmup_mult > 0 && c.lr_warmup_mult <= 1, "lr_warmup_mult must be in (0, 1]");
  require(c.grad_max_norm >= 0, "grad_max_norm must be >= 0");
  require(c.bottleneck_width >= 0, "bottleneck_width must be >= 0 (0 = the trunk's width)");
  require(c.data_loss != DataLoss::charbonnier || (c.charb_padding > 0 && std::isfinite(c.charb_padding)),
          "data_loss=charbonnier needs charb_padding > 0 (official 0.001)");
  require(c.coarse_loss_mult >= 0, "coarse_loss_mult must be >= 0");
  require(c.chunk_rays >= 0 && c.render_chunk_rays >= 1, "chunk sizes must be positive (chunk_rays 0 = auto)");
  require(c.log_every >= 1 && c.checkpoint_every >= 1, "log_every and checkpoint_every must be positive");
  require(c.keep_checkpoints >= 1, "keep_checkpoints must be at least 1");
  require(c.max_bad_steps >= 1, "max_bad_steps must be at least 1");
  require(c.val_views >= 0, "val_views must be >= 0");
  require(c.val_every >= 0, "val_every must be >= 0 (0 = no val scores during training)");
  require(c.resample_padding >= 0 && c.rgb_padding >= 0, "paddings must be >= 0");
  require(c.density_noise >= 0, "density_noise must be >= 0 (0 = no noise)");
  require(c.pixel_center >= 0 && c.pixel_center < 1, "pixel_center must be in [0, 1)");
  require(c.near >= 0 && c.far >= 0 && (c.far == 0 || c.far > c.near), "need 0 <= near < far (0 = from data)");
  // A frustum's variances grow as t²: past t ≈ 1e19 they overflow float32 (kernels/gaussian.cl), so its IPE would be
  // NaN; mip-NeRF 360's far of 1e6 is far inside.
  require(c.far <= 1e18, "far = " + std::to_string(c.far) + " is beyond 1e18, where a frustum's variances overflow "
                         "float32; an unbounded scene's far of 1e6 already reaches the contraction's edge");
}

nlohmann::ordered_json config_json(const TrainConfig& config) {
  nlohmann::ordered_json j;
  for (const auto& e : table()) {
    const std::string text = get_value(config, e.setting.name);
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(config.*member)>;
          if constexpr (has_enum_names_v<T>) {
            j[e.setting.name] = text;
          } else {
            j[e.setting.name] = config.*member;
          }
        },
        e.member);
    if (e.setting.name == "variant" && config.variant_bundle) {
      j[kVariantBundleKey] = enum_name(*config.variant_bundle);
    }
  }
  if (!config.scene_effects.empty()) j[kSceneEffectsKey] = config.scene_effects;
  if (!config.time_budget.empty()) j[kTimeBudgetKey] = config.time_budget;
  if (config.ndc_projection[0] > 0.0) j[kNdcProjectionKey] = {config.ndc_projection[0], config.ndc_projection[1]};
  return j;
}

std::string to_json(const TrainConfig& config) { return config_json(config).dump(2); }

TrainConfig from_json(const std::string& json_text, const std::string& where) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(where + ": malformed configuration JSON: " + e.what());
  }
  return config_from_json(j, where);
}

TrainConfig config_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw Error(where + ": the configuration must be a JSON object");
  TrainConfig config;
  for (const auto& [name, value] : j.items()) {
    if (name == kVariantBundleKey) {
      config.variant_bundle = variant_bundle_from_json(value, where);
      continue;
    }
    if (name == kSceneEffectsKey) {
      if (!value.is_string()) throw Error(where + ": \"" + kSceneEffectsKey + "\" must be a string");
      config.scene_effects = value.get<std::string>();
      continue;
    }
    if (name == kNdcProjectionKey) {
      if (!value.is_array() || value.size() != 2 || !value[0].is_number() || !value[1].is_number() ||
          !(value[0].get<double>() > 0.0) || !(value[1].get<double>() > 0.0) ||
          !std::isfinite(value[0].get<double>()) || !std::isfinite(value[1].get<double>())) {
        throw Error(where + ": \"" + kNdcProjectionKey + "\" must be two positive numbers (2f/width, 2f/height)");
      }
      config.ndc_projection = {value[0].get<double>(), value[1].get<double>()};
      continue;
    }
    if (name == kTimeBudgetKey) {
      if (!value.is_string()) throw Error(where + ": \"" + kTimeBudgetKey + "\" must be a string");
      config.time_budget = value.get<std::string>();
      continue;
    }
    try {
      set_value(config, name, value.is_string() ? value.get<std::string>() : value.dump());
    } catch (const Error& e) {
      throw Error(where + ": " + e.what());
    }
  }
  try {
    validate(config);
  } catch (const Error& e) {
    throw Error(where + ": " + e.what());  // the file holds the invalid combination
  }
  return config;
}

std::vector<std::string> differences(const TrainConfig& a, const TrainConfig& b) {
  std::vector<std::string> out;
  for (const auto& e : table()) {
    const auto va = get_value(a, e.setting.name), vb = get_value(b, e.setting.name);
    if (va != vb) out.push_back(e.setting.name + ": " + va + " -> " + vb);
  }
  return out;
}

}  // namespace mipnerf::train
