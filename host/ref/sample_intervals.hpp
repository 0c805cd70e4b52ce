// CPU reference of kernels/sample_intervals.cl in double precision: proposal sampling's sampler (official
// stepfun.sample_intervals with models.py's annealed, padded logits), and the float32 kernel's error envelope.
#pragma once

#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// Step 1 for one ray, s [N+1], w [N] → logits [N]: anneal · log(clip(w + padding, FLT_MIN, FLT_MAX)) where
// s_{i+1} > s_i, else −∞ (official models.py logits_resample with math.safe_log).
std::vector<double> sample_intervals_logits(const SampleIntervalsOptions& options, const double* s_edges,
                                            const double* weights, size_t n_intervals);

// Step 2: cdf [N+1] of softmax(logits) (official stepfun.integrate_weights: 0, min(1, cumsum), 1); empty when every
// logit is −∞ (no non-empty interval: the official's softmax is NaN there).
std::vector<double> sample_intervals_cdf(const std::vector<double>& logits);

// Step 3: the M = n_new sorted u of one ray (sample with deterministic_center; randomised: ξ from rng_uniform4 with
// rng_stream_proposal, one per sample or ξ_0 for all when single_jitter), item = key.first_ray + ray.
std::vector<double> sample_intervals_u(const SampleIntervalsOptions& options, size_t n_new, const RngKey& key,
                                       size_t ray);

// Step 4: the inverse CDF at u (official math.sorted_interp: k = the last with cdf_k ≤ u, searchsorted 'right').
double sample_intervals_invert(const std::vector<double>& cdf, const double* s_edges, double u);

// Step 5: M centres → M + 1 edges (midpoints, reflected ends), clipped to [domain_near, domain_far].
std::vector<double> sample_intervals_edges(const SampleIntervalsOptions& options, const std::vector<double>& centres);

// One ray, given its u [M]: edges [M+1]. No non-empty interval: every edge clip(s_0) (the kernel's choice).
std::vector<double> sample_intervals_ray(const SampleIntervalsOptions& options, const double* s_edges,
                                         const double* weights, size_t n_intervals, const std::vector<double>& u);

// Mirror of sample_intervals_fwd: s_edges [R][N+1], weights [R][N] → s_new [R][M+1] (M = n_new ≥ 2). Written as the
// official code: the whole CDF, then a search per u (not the kernel's merge walk).
void sample_intervals_fwd(const SampleIntervalsOptions& options, const std::vector<double>& s_edges,
                          const std::vector<double>& weights, std::vector<double>& s_new, size_t n_rays,
                          size_t n_intervals, size_t n_new, const RngKey& key);

// One value of sample_intervals_s_to_t (kernels/sample_intervals.cl ray_distance_s_to_t): linear clip(s·far + (1 − s)·near,
// near, far) (the official identity ray warp of bounded scenes, coord.construct_ray_warps with fn = None), or the power
// ladder 1.25·(G^(−2/3) − 1), G = s·h(far) + (1 − s)·h(near), h(t) = (1 + 2t/2.5)^(−3/2), clipped likewise (camp_zipnerf
// 360.gin's power_ladder p = −3/2, premult 2), with the official's float32 constants: G shifted by −(κ − 1)(1 − G) and
// held ≥ inv_power_ladder's clip (kernels/sample_intervals.cl says why).
double ray_distance_s_to_t(RayDistance ray_distance, double s, double near, double far);

// Mirror of sample_intervals_s_to_t: t [R][K] from s [R][K] by ray_distance_s_to_t with each ray's near and far.
void sample_intervals_s_to_t(const std::vector<double>& s, const std::vector<double>& near,
                             const std::vector<double>& far, std::vector<double>& t, size_t n_rays, size_t n_per_ray,
                             RayDistance ray_distance = RayDistance::linear);

// The float32 kernel's power ladder within this of the exact t (absolute): 32·2^−23·(t + 1.25). Derivation (each
// operation within OpenCL's ulp bound, s exact): b = 1 + 2t/2.5 (2 roundings), h = 1/(b·√b) (√ 3 ulp, product,
// reciprocal 2.5 ulp): ≤ 10 ε relative; G = s·h_f + (1 − s)·h_n, non-negative terms: ≤ 13 ε; the official's shift
// G' = G − (κ − 1)(1 − G) (a product and a difference; where the clip does not hold, (κ − 1) ≤ 0.29·G' as G' ≥ min G =
// 3.5·(κ − 1)): ≤ 13 ε·1.29 + 2 ε·0.29 + ε < 19 ε; G'^(−1/3) by cbrt (2 ulp) and a reciprocal (2.5 ulp): < 11 ε;
// squared: ≤ 23 ε on Q = G'^(−2/3); Q − 1 and × 1.25 add ε·(Q − 1) each: |δt| ≤ 1.25·23 ε·Q + 2 ε·t =
// 23 ε·(t + 1.25) + 2 ε·t < 32 ε·(t + 1.25). The clips (G' at its minimum, t to [near, far]) are 1-Lipschitz and add
// nothing.
double ray_distance_power_ladder_float32_bound(double t);

// Where an implementation whose operations are each within one ulp-relative `eps` (the machine epsilon: 2^-23 for the
// float32 kernel, 2^-52 for the float64 official) may put one ray's edges, given the exact u [M]: lo [M+1] ≤ edge ≤ hi
// [M+1]. Derivation (per ray, p = softmax(l), S = max|s|):
//  - logit l_i: w + padding rounds (relative eps → eps in the log), log is within 3 ulp (OpenCL's bound, |l|·3eps/a
//    before the anneal a), the product rounds (eps·|l_i|): |δl_i| ≤ eps·(a + 4|l_i|);
//  - exp(l_i − max l) (the max's own error cancels in the softmax, only the subtraction's rounding eps·|l_i − max l|
//    stays; exp within 3 ulp): relative error r_i = |δl_i| + eps·|l_i − max l| + 3eps;
//  - the sum's relative error r_S ≤ Σ p_i r_i + (N − 1)·eps, each p_i's ≤ r_i + r_S + eps, the cumulative sum adds
//    ≤ N·eps: every cdf_k is within δ_cdf = 2Σ p_i r_i + (2N + 1)·eps of the exact one;
//  - u itself: at most five roundings of values ≤ 1 (linspace step, product, jitter product, sums) plus `u_slack`
//    for a caller whose constants differ (the official's float32 eps, pad and u_max under float64): δ = δ_cdf +
//    6eps + u_slack;
//  - a piecewise-linear CDF within δ of the exact one everywhere has its inverse at u between the exact inverse's
//    leftmost point at u − δ and its rightmost at u + δ: where a CDF step is flat (an empty or weightless interval)
//    that spans the whole step, and where it is steep it is a fraction δ/p_k of the bin — the bin width is the bound
//    of an ill-conditioned position, never more;
//  - the interpolation s_k + frac·(s_{k+1} − s_k) rounds: frac to 3eps, the result to 2eps of S: 8eps·S per centre;
//  - the edges are (c_{j−1} + c_j)/2 and the reflections 1.5c_0 − 0.5c_1, 1.5c_{M−1} − 0.5c_{M−2} (the extremes of
//    the centres' intervals, weighted so), with 2 more roundings (≤ 2eps·S) and the 1.5× of the centres' 8eps·S;
//  - clip to the domain is monotone: applied to lo and hi.
struct SampleIntervalsEnvelope {
  std::vector<double> lo, hi;  // [M+1] each
  double cdf_error = 0.0;      // δ used (u-space)
};
SampleIntervalsEnvelope sample_intervals_envelope(const SampleIntervalsOptions& options, const double* s_edges,
                                                  const double* weights, size_t n_intervals,
                                                  const std::vector<double>& u, double eps, double u_slack = 0.0);

}  // namespace mipnerf::ref
