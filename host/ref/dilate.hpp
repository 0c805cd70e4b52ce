// CPU reference (double) of kernels/dilate.cl, same names: mip-NeRF 360's max-dilation of a proposal histogram
// (multinerf stepfun.max_dilate_weights with renormalize, then [1:-1] as Model.__call__ keeps). Written as the
// official writes it: the knots sorted from the concatenation, each knot's pooled pdf a max over every interval.
#pragma once

#include <cstddef>
#include <vector>

namespace mipnerf::ref {

// One ray: s [N+1], w [N] → s_out [3N−1], w_out [3N−2] (see kernels/dilate.cl).
void max_dilate_weights_ray(const double* s, const double* w, size_t n_intervals, double dilation, double domain_near,
                            double domain_far, double* s_out, double* w_out);

// Mirrors max_dilate_weights_fwd over R rays: s_edges [R][N+1], weights [R][N] → s_out [R][3N−1], w_out [R][3N−2].
void max_dilate_weights_fwd(const std::vector<double>& s_edges, const std::vector<double>& weights, double dilation,
                            double domain_near, double domain_far, std::vector<double>& s_out,
                            std::vector<double>& w_out, size_t n_rays, size_t n_intervals);

}  // namespace mipnerf::ref
