// Checks and descriptions of a graph spec.
#include "graph/graph_spec.hpp"

#include <algorithm>
#include <sstream>

#include "core/error.hpp"

namespace mipnerf::graph {

size_t GraphSpec::feature_width(Encoding encoding) const {
  switch (encoding) {
    case Encoding::integrated:
      return static_cast<size_t>(position_encoding.ipe_width());
    case Encoding::concat_pe:
      return static_cast<size_t>(position_encoding.concat_pe_width());
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

void GraphSpec::validate() const {
  if (levels.empty()) throw Error("graph: at least one level is needed");
  if (levels.front().sampling != Sampling::stratified) throw Error("graph: the first level must sample stratified");
  for (size_t l = 0; l < levels.size(); ++l) {
    const auto& level = levels[l];
    const std::string where = "graph level " + std::to_string(l);
    if (level.new_samples < 1) throw Error(where + ": needs at least one sample");
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
    if (level.encoding == Encoding::integrated && position_encoding.append_identity) {
      throw Error(where + ": IPE has no identity features; set pos_identity = false or use PE");
    }
    if (level.encoding != Encoding::zip_grid &&
        (level.encoding == Encoding::concat_pe) != (position_encoding.covariance_degrees > 0)) {
      throw Error(where +
                  ": covariance degrees (cov_max_deg = " + std::to_string(position_encoding.covariance_degrees) +
                  ") go with the concatenated PE and only with it");
    }
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
                                                                  : "resampled + previous";
    const char* encoding = level.encoding == Encoding::integrated        ? "IPE"
                           : level.encoding == Encoding::frustum_mean_pe ? "PE of frustum means"
                           : level.encoding == Encoding::concat_pe       ? "PE of frustum means ++ PE of sqrt(cov)"
                           : level.encoding == Encoding::zip_grid        ? (zip.multisample ? "multisampled grid"
                                                                                            : "grid at frustum means")
                                                                         : "PE of midpoints";
    out << (l ? "; " : "") << "level " << l << ": " << sampling << " " << intervals[l] << " intervals, " << encoding;
    if (level.encoding == Encoding::zip_grid) {
      out << " " << level.grid_index << " (" << mlp::describe(grids[level.grid_index])
          << (zip.downweight ? ", footprint-weighted" : ", not footprint-weighted") << ")";
    } else {
      out << " degrees " << position_encoding.min_deg << ".." << position_encoding.max_deg - 1;
    }
    out << ", network " << level.mlp_index << ", loss weight " << level.loss_weight;
  }
  return out.str();
}

}  // namespace mipnerf::graph
