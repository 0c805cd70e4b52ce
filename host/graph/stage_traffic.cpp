// The least memory traffic of the graph's stages (see stage_traffic.hpp).
#include "graph/stage_traffic.hpp"

namespace mipnerf::graph::traffic {
namespace {

constexpr double kWord = 4.0;  // bytes of a float32 or a uint32

double words(double count) { return kWord * count; }

}  // namespace

double rays(size_t n_rays, bool view_dependence) {
  const double r = static_cast<double>(n_rays);
  const double ray_floats = 3 + 3 + 1 + 1 + 1 + 1 + (view_dependence ? 3 : 0);
  return words(2 * 2 * r)          // the camera and pixel ids copied: read + write each
         + words(2 * r)            // the ids read by the ray kernel
         + words(ray_floats * r);  // the ray bundle written
}

double view_encoding(size_t n_rays, size_t view_width) {
  return words(static_cast<double>(n_rays) * (3.0 + static_cast<double>(view_width)));
}

double stratified_sampling(size_t n_rays, size_t intervals) {
  return words(static_cast<double>(n_rays) * (2.0 + static_cast<double>(intervals + 1)));
}

double resampling(size_t n_rays, size_t previous_intervals, size_t new_intervals, bool union_with_previous) {
  const double previous_edges = static_cast<double>(previous_intervals + 1);
  const double previous_weights = static_cast<double>(previous_intervals);
  const double drawn_edges = static_cast<double>(new_intervals + 1);
  double per_ray = previous_edges + previous_weights + drawn_edges;
  if (union_with_previous) per_ray += previous_edges + drawn_edges + (previous_edges + drawn_edges);
  return words(static_cast<double>(n_rays) * per_ray);
}

double encoding(size_t n_rays, size_t intervals, size_t feature_width) {
  const double per_ray = 7.0 + static_cast<double>(intervals + 1) +
                         static_cast<double>(intervals) * static_cast<double>(feature_width);
  return words(static_cast<double>(n_rays) * per_ray);
}

double render_forward(size_t n_rays, size_t intervals, bool with_colour) {
  const double colours = with_colour ? 3.0 : 0.0;
  const double per_sample = colours + 1.0 + 1.0 + 1.0;  // raw colour, raw density, an edge; the weight
  const double per_ray = 1.0 + 3.0 + colours + 1.0 + 1.0;  // the last edge, the direction; colour, opacity, distance
  return words(static_cast<double>(n_rays) * (per_ray + per_sample * static_cast<double>(intervals)));
}

double loss(size_t n_rays) { return words(static_cast<double>(n_rays) * (3.0 + 3.0 + 1.0 + 3.0)); }

double render_backward(size_t n_rays, size_t intervals) {
  const double per_sample = 3.0 + 1.0 + 1.0 + 1.0 + 3.0 + 1.0;  // raw colour, density, edge, weight; 2 gradients
  const double per_ray = 1.0 + 3.0 + 3.0;                       // the last edge, the direction, the colour gradient
  return words(static_cast<double>(n_rays) * (per_ray + per_sample * static_cast<double>(intervals)));
}

double adam(size_t parameters) {
  return words(static_cast<double>(parameters) * (1.0 + 1.0 + 4.0 + 3.0));  // zeroed; checked; read 4, write 3
}

double batch(size_t n_rays) { return words(static_cast<double>(n_rays) * (1.0 + 1.0 + 3.0 + 1.0 + 3.0)); }

}  // namespace mipnerf::graph::traffic
