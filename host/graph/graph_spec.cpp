// Checks and descriptions of a graph spec.
#include "graph/graph_spec.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "core/geodesic_basis.hpp"
#include "ops/contracted_ipe.hpp"

namespace mipnerf::graph {

size_t GraphSpec::feature_width(Encoding encoding) const {
  switch (encoding) {
    case Encoding::integrated:
      return static_cast<size_t>(position_encoding.ipe_width());
    case Encoding::concat_pe:
      return static_cast<size_t>(position_encoding.concat_pe_width());
    case Encoding::contracted_ipe:
      return ops::contracted_ipe_width(position_encoding, basis_tessellation);
    case Encoding::zip_grid:
      throw Error("graph: a grid level's feature width is its grid's (GraphSpec::feature_width(level))");
    case Encoding::frustum_mean_pe:
    case Encoding::midpoint_pe:
      break;
  }
  return static_cast<size_t>(position_encoding.pe_width());
}

ops::ZipFeatureOptions GraphSpec::zip_options(size_t index) const {
  if (index >= grids.size()) {
    throw Error("graph: grid " + std::to_string(index) + " named, " + std::to_string(grids.size()) + " in the spec");
  }
  ops::ZipFeatureOptions options = zip;
  options.features = grids[index].features;
  options.init_range = grids[index].init_range;
  options.precondition = grids[index].precondition;
  return options;
}

size_t GraphSpec::feature_width(const LevelSpec& level) const {
  if (level.encoding != Encoding::zip_grid) return feature_width(level.encoding);
  return mlp::grid_level_sizes(grids.at(level.grid_index)).size() * zip_options(level.grid_index).level_width();
}

std::vector<size_t> GraphSpec::intervals_per_level() const {
  std::vector<size_t> out;
  size_t previous = 0;
  for (const auto& level : levels) {
    previous = level.intervals(previous);
    out.push_back(previous);
  }
  return out;
}

size_t GraphSpec::max_intervals() const {
  const auto all = intervals_per_level();
  return all.empty() ? 0 : *std::max_element(all.begin(), all.end());
}

bool GraphSpec::has_proposal_levels() const {
  return std::any_of(levels.begin(), levels.end(), [](const LevelSpec& l) { return l.role == LevelRole::proposal; });
}

namespace {

// The rules of proposal sampling: s-edges exist only on levels that sample by `proposal`, so a proposal-sampled level
// reads a proposal-sampled (or no) previous level; a proposal round needs the last level's s-histogram, its own
// network or one shared with other rounds only (each round's forward waits in a workspace of its own for the backward
// after the last level's: Graph's workspace slots) and a grid or IPE features.
void validate_proposal_level(const GraphSpec& spec, size_t l, const std::string& where) {
  const auto& level = spec.levels[l];
  if (level.sampling == Sampling::proposal) {
    if (l > 0 && spec.levels[l - 1].sampling != Sampling::proposal) {
      throw Error(where + ": proposal sampling reads the previous level's s-edges, so that level must sample by "
                          "proposal too");
    }
    if (level.new_samples < 2) throw Error(where + ": proposal sampling draws at least 2 intervals");
  }
  if (level.dilation != 0.0f && (l == 0 || level.sampling != Sampling::proposal || !(level.dilation > 0.0f) ||
                                 !std::isfinite(level.dilation))) {
    throw Error(where + ": a dilation (finite, > 0) dilates the previous level's histogram before proposal sampling: "
                        "only a proposal-sampled level after the first takes one");
  }
  if (level.distortion_mult != 0.0f) {
    if (!(level.distortion_mult > 0.0f)) throw Error(where + ": the distortion loss weight must be ≥ 0");
    if (l + 1 != spec.levels.size() || level.sampling != Sampling::proposal) {
      throw Error(where + ": only the last level takes the distortion loss, and only when it samples by proposal (the "
                          "loss is over its s-edges)");
    }
  }
  if (level.role != LevelRole::proposal) return;
  if (l + 1 == spec.levels.size()) throw Error(where + ": the last level is shown, it cannot be a proposal round");
  if (level.sampling != Sampling::proposal || spec.levels.back().sampling != Sampling::proposal) {
    throw Error(where + ": a proposal round and the last level must sample by proposal (the interlevel loss compares "
                        "their s-histograms)");
  }
  if (level.encoding != Encoding::zip_grid && level.encoding != Encoding::integrated &&
      level.encoding != Encoding::contracted_ipe) {
    throw Error(where + ": a proposal round reads a grid (Zip-NeRF) or the IPE of its frustums (mip-NeRF 360)");
  }
  for (size_t k = 0; k < spec.levels.size(); ++k) {
    if (k != l && spec.levels[k].mlp_index == level.mlp_index && spec.levels[k].role != LevelRole::proposal) {
      throw Error(where + ": a proposal round's network may be shared only with other proposal rounds, but level " +
                  std::to_string(k) + " uses network " + std::to_string(level.mlp_index) + " too");
    }
  }
  const bool spline = level.interlevel.kind == ops::InterlevelKind::spline;
  if ((spline && !(level.interlevel.blur_halfwidth > 0.0f)) || !(level.interlevel.mult >= 0.0f)) {
    throw Error(where + ": the interlevel blur half-width must be > 0 and its mult ≥ 0");
  }
}

}  // namespace

void GraphSpec::validate() const {
  if (levels.empty()) throw Error("graph: at least one level is needed");
  if (ray_distance != RayDistance::linear && levels.front().sampling != Sampling::proposal) {
    throw Error("graph: ray_distance " + std::string(enum_name(ray_distance)) +
                " is proposal sampling's s → t, but the levels sample from t directly (sampler=proposal)");
  }
  if (levels.front().sampling != Sampling::stratified && levels.front().sampling != Sampling::proposal) {
    throw Error("graph: the first level must sample stratified or by proposal (from the whole ray)");
  }
  for (size_t l = 0; l < levels.size(); ++l) {
    const auto& level = levels[l];
    const std::string where = "graph level " + std::to_string(l);
    if (level.new_samples < 1) throw Error(where + ": needs at least one sample");
    validate_proposal_level(*this, l, where);
    if (level.mlp_index >= mlps.size())
      throw Error(where + ": names network " + std::to_string(level.mlp_index) + " but there are " +
                  std::to_string(mlps.size()));
    const auto& mlp = mlps[level.mlp_index];
    if (level.encoding == Encoding::zip_grid && level.grid_index >= grids.size()) {
      throw Error(where + ": names grid " + std::to_string(level.grid_index) + " but there are " +
                  std::to_string(grids.size()));
    }
    const size_t width = feature_width(level);
    if (mlp.input_width != width) {
      throw Error(where + ": the encoding gives " + std::to_string(width) + " features but network " +
                  std::to_string(level.mlp_index) + " expects " + std::to_string(mlp.input_width));
    }
    if ((level.encoding == Encoding::integrated || level.encoding == Encoding::contracted_ipe) &&
        position_encoding.append_identity) {
      throw Error(where + ": IPE has no identity features; set pos_identity = false or use PE");
    }
    if (level.encoding != Encoding::zip_grid &&
        (level.encoding == Encoding::concat_pe) != (position_encoding.covariance_degrees > 0)) {
      throw Error(where +
                  ": covariance degrees (cov_max_deg = " + std::to_string(position_encoding.covariance_degrees) +
                  ") go with the concatenated PE and only with it");
    }
    // A proposal round's network has no colour to condition (official disable_rgb): no view branch.
    if (level.role == LevelRole::proposal) continue;
    if (mlp.view_dependence != rays.view_dependence) {
      throw Error(where + ": the network's view dependence does not match the rays'");
    }
    if (mlp.view_dependence && mlp.view_width != static_cast<size_t>(view_encoding.pe_width())) {
      throw Error(where + ": the view encoding gives " + std::to_string(view_encoding.pe_width()) +
                  " features but the network expects " + std::to_string(mlp.view_width));
    }
  }
}

std::string GraphSpec::describe() const {
  std::ostringstream out;
  const auto intervals = intervals_per_level();
  for (size_t l = 0; l < levels.size(); ++l) {
    const auto& level = levels[l];
    const char* sampling = level.sampling == Sampling::stratified ? "stratified"
                           : level.sampling == Sampling::resample ? "resampled"
                           : level.sampling == Sampling::proposal ? "proposal-sampled"
                                                                  : "resampled + previous";
    const char* encoding = level.encoding == Encoding::integrated        ? "IPE"
                           : level.encoding == Encoding::contracted_ipe  ? "IPE of contracted frustums"
                           : level.encoding == Encoding::frustum_mean_pe ? "PE of frustum means"
                           : level.encoding == Encoding::concat_pe       ? "PE of frustum means ++ PE of sqrt(cov)"
                           : level.encoding == Encoding::zip_grid        ? (zip.multisample ? "multisampled grid"
                                                                                            : "grid at frustum means")
                                                                         : "PE of midpoints";
    out << (l ? "; " : "") << "level " << l << ": " << sampling << " " << intervals[l] << " intervals"
        << (level.sampling != Sampling::proposal           ? ""
            : ray_distance == RayDistance::power_ladder ? " (power ladder s→t)"
            : ray_distance == RayDistance::reciprocal   ? " (reciprocal s→t)"
                                                        : "")
        << (level.dilation > 0.0f ? " from the previous histogram dilated by " + std::to_string(level.dilation) : "")
        << ", " << encoding;
    if (level.encoding == Encoding::zip_grid) {
      out << " " << level.grid_index << " (" << mlp::describe(grids[level.grid_index])
          << (zip.downweight ? ", footprint-weighted" : ", not footprint-weighted")
          << (zip.contract ? ", points contracted (unbounded)" : "") << ")";
    } else {
      out << " degrees " << position_encoding.min_deg << ".." << position_encoding.max_deg - 1;
      if (level.encoding == Encoding::contracted_ipe) {
        out << " on " << icosahedron_basis(basis_tessellation).size() << " directions";
      }
    }
    out << ", network " << level.mlp_index;
    if (level.role == LevelRole::proposal) {
      if (level.interlevel.kind == ops::InterlevelKind::outer) {
        out << ", proposal round (density only; outer interlevel loss, mult " << level.interlevel.mult << ")";
      } else {
        out << ", proposal round (density only; interlevel loss, blur " << level.interlevel.blur_halfwidth << ", mult "
            << level.interlevel.mult << ")";
      }
    } else {
      out << ", loss weight " << level.loss_weight;
      if (level.distortion_mult > 0.0f) out << ", distortion loss mult " << level.distortion_mult;
    }
  }
  // What differs from mip-NeRF's training, said once (the mipnerf360 preset's pieces): the data term, the background.
  if (loss.charbonnier_padding > 0.0f) out << "; Charbonnier loss (padding " << loss.charbonnier_padding << ")";
  if (loss.channel_mean) out << (loss.charbonnier_padding > 0.0f ? ", " : "; loss ") << "a mean over channels";
  if (render.opaque_background) out << "; opaque background (the last interval takes what is left)";
  return out.str();
}

}  // namespace mipnerf::graph
