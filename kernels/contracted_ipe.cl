// mip-NeRF 360's encoding of a frustum (Barron et al. 2022, §2; the official multinerf MLP.predict_density with
// warp_fn = coord.contract): the interval's Gaussian with its full covariance (official cast_rays with diag = False),
// through the contraction linearised at its mean (contract.cl: μ' = contract(μ), Σ' = J Σ Jᵀ), projected onto K unit
// directions b_k (official lift_and_diagonalize: m_k = b_k·μ', v_k = b_kᵀ Σ' b_k), then the IPE of each projection
// (official integrated_pos_enc, expected_sin):
//   features [rows][2LK]: the LK sines exp(−½·4^l·v_k)·sin(2^l·m_k), then the LK cosines, index (l − min_deg)·K + k
// inside each block (the official order: the MLP's first layer depends on it). Official: K = 21 (the icosahedron
// tessellated twice, core/geodesic_basis.hpp), degrees 0..11: 504 features. Needs gaussian.cl, contract.cl and
// encode.cl (its attenuation) before it in the program. Reference: host/ref/contracted_ipe.hpp (same names).
//
// Forward only: nothing trained lies before the features (the intervals are stop-gradient, as the official's), so
// the network's input gradient is never needed.
//
// Accuracy: every contracted mean lies in the ball of radius 2, so |m_k| ≤ 2 and the largest argument is 2^11·2 =
// 4096 at degree 11: one ulp of m_k (2.4e−7) moves it by 5e−4 rad, against 0.004 rad of mip-NeRF's degree 15 in a
// world of radius 1. The official's safe_sin reduces arguments past 100π by `x % 100π` in float32 first (a rounding
// of up to 1e−5 rad at 4096); we call sin and cos on the argument itself (4 ulp over the whole range), the exact
// function's value. Far out the contraction shrinks Σ by J's a ≈ 2/r across and b = 1/r² along the ray (contract.cl
// applies its factors so nothing underflows first), so far frustums keep finite, small variances in the ball.

#ifndef MIPNERF_CONTRACTED_IPE_CL
#define MIPNERF_CONTRACTED_IPE_CL

#pragma OPENCL FP_CONTRACT OFF

// The contracted Gaussian of row = ray·N + i (interval i of `ray`): mean' and the symmetric Σ' = (diag', off').
inline void contracted_row_gaussian(__global const float* origins, __global const float* directions,
                                    __global const float* radii, __global const float* t_edges, size_t row,
                                    uint n_samples, float3* mean, float3* diag, float3* off) {
  float3 world_mean, world_diag, world_off;
  row_full_gaussian(origins, directions, radii, t_edges, row, n_samples, &world_mean, &world_diag, &world_off);
  contract_gaussian(world_mean, world_diag, world_off, mean, diag, off);
}

// Directions are encoded 8 at a time (float8 projections through the vector built-ins exp and sincos: PoCL's CPU device
// runs them in full-width registers, 6x faster than a direction at a time), the basis padded to a multiple of 8 on
// the host (the padding's features are never written).
#define CONTRACTED_IPE_LANES 8

// exp(−½·scale²·v) per lane, 0 below exp(IPE_MIN_EXPONENT) as encode.cl's attenuation (the same cut and reason).
inline float8 projected_attenuation(float8 v, float scale) {
  const float8 exponent = -0.5f * (v * (scale * scale));
  return select(exp(fmax(exponent, IPE_MIN_EXPONENT)), (float8)(0.0f), isless(exponent, (float8)(IPE_MIN_EXPONENT)));
}

// Lanes 0..n−1 of x at out[0..n−1] (n ≤ 8): the last group of a basis whose size 8 does not divide.
inline void store_lanes(float8 x, uint n, __global float* out) {
  if (n == CONTRACTED_IPE_LANES) {
    vstore8(x, 0, out);
    return;
  }
  float lanes[CONTRACTED_IPE_LANES];
  vstore8(x, 0, lanes);
  for (uint i = 0; i < n; ++i) out[i] = lanes[i];
}

// Tunable CONTRACTED_IPE_SINCOS_EVERY = K: one sincos every K degrees, the K − 1 after it by angle doubling, with
// encode.cl's DOUBLE_ANGLE and its bound (E_j < 2^j·11u after j doublings); 1: a sincos per degree.
#ifndef CONTRACTED_IPE_SINCOS_EVERY
#define CONTRACTED_IPE_SINCOS_EVERY 1
#endif

// One item per row: features [R·N][2·L·K] from the rays [R] (origins, directions [R][3], radii [R]), the interval
// edges t_edges [R][N+1] and the directions basis [K_padded][3] (K_padded a multiple of 8; rows past K are zeros).
__kernel void contracted_ipe_fwd(__global const float* origins, __global const float* directions,
                                 __global const float* radii, __global const float* t_edges,
                                 __global const float* basis, __global float* features, const uint n_rays,
                                 const uint n_samples, const uint n_basis, const int min_deg, const int max_deg) {
  const size_t row = get_global_id(0);
  if (row >= (size_t)n_rays * n_samples) return;
  float3 mean, diag, off;
  contracted_row_gaussian(origins, directions, radii, t_edges, row, n_samples, &mean, &diag, &off);
  const uint n_degrees = (uint)(max_deg - min_deg), block = n_degrees * n_basis;
  __global float* sines = features + row * 2 * block;
  __global float* cosines = sines + block;
  for (uint first = 0; first < n_basis; first += CONTRACTED_IPE_LANES) {
    // The projections of 8 directions: b = (bx, by, bz) per lane, from the basis' rows first..first + 7.
    const float8 bx = (float8)(basis[3 * first], basis[3 * first + 3], basis[3 * first + 6], basis[3 * first + 9],
                               basis[3 * first + 12], basis[3 * first + 15], basis[3 * first + 18],
                               basis[3 * first + 21]);
    const float8 by = (float8)(basis[3 * first + 1], basis[3 * first + 4], basis[3 * first + 7],
                               basis[3 * first + 10], basis[3 * first + 13], basis[3 * first + 16],
                               basis[3 * first + 19], basis[3 * first + 22]);
    const float8 bz = (float8)(basis[3 * first + 2], basis[3 * first + 5], basis[3 * first + 8],
                               basis[3 * first + 11], basis[3 * first + 14], basis[3 * first + 17],
                               basis[3 * first + 20], basis[3 * first + 23]);
    // Per lane: m = b·mean', v = bᵀΣ'b = Σ_i b_i² Σ'_ii + 2 Σ_i<j b_i b_j Σ'_ij.
    const float8 m = bx * mean.x + by * mean.y + bz * mean.z;
    const float8 v = bx * bx * diag.x + by * by * diag.y + bz * bz * diag.z +
                     2.0f * (bx * by * off.x + bx * bz * off.y + by * bz * off.z);
    const uint lanes = min((uint)CONTRACTED_IPE_LANES, n_basis - first);
    float8 s = (float8)(0.0f), c = (float8)(1.0f);
    for (uint l = 0; l < n_degrees; ++l) {
      const float scale = ldexp(1.0f, min_deg + (int)l);  // 2^l, exact
      if (l % CONTRACTED_IPE_SINCOS_EVERY == 0) {
        SIN_COS(m * scale, s, c);  // exact argument: a power-of-two scaling
      } else {
        DOUBLE_ANGLE(float8, s, c);
      }
      const float8 atten = projected_attenuation(v, scale);
      store_lanes(atten * s, lanes, sines + l * n_basis + first);
      store_lanes(atten * c, lanes, cosines + l * n_basis + first);
    }
  }
}

#endif
