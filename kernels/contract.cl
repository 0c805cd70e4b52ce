// mip-NeRF 360's contraction of Gaussians and its ray warps (Barron et al. 2022, eqs. 10–11; the official multinerf
// coord.contract, coord.track_linearize and coord.construct_ray_warps with raydist_fn = reciprocal). Standalone stages;
// contracted_ipe.cl inlines the forward for the model. Reference: host/ref/contract.hpp (same names).
//
// contract(x) = x for |x| ≤ 1, (2 − 1/|x|) x/|x| outside (eq. 10): all of space into the ball of radius 2.
// A Gaussian (μ, Σ) goes through the contraction linearised at its mean (track_linearize, a Kalman filter's step):
//   μ' = contract(μ),  Σ' = J Σ Jᵀ,  J = ∂contract/∂x at μ.
// Outside the unit ball, with r = |μ|, u = μ/r and P = u uᵀ, the Jacobian splits into a radial and a tangential scale:
//   J = a (I − P) + b P,   a = (2r − 1)/r² = (2 − 1/r)/r (across the ray from the origin),  b = 1/r² (along it)
// (J = I on the sphere: a = b = 1 at r = 1, so J is continuous there; its derivative is not, b' jumps from 0 to −2).
// Σ' is computed in that split, never with the matrix entries a δ_ij + (b − a) u_i u_j, whose a + (b − a) loses all of
// b's digits once r ≫ 1 (b/a = 1/(2r − 1)): with v = Σu, s = uᵀΣu, w = v − s u (the tangential part of Σu),
//   Σ' = a² Σ⊥ + a b (u wᵀ + w uᵀ) + b² s P,   Σ⊥ = (I − P) Σ (I − P) = Σ − (u wᵀ + w uᵀ) − s P.
// The scale factors are applied one at a time (a·(a·X), X·1/r·1/r…), so nothing underflows before the result does:
// a ≈ 2/r is a normal float up to r ≈ 1.7e38, while a² or b = 1/r² alone would underflow from r ≈ 1e19.
//
// Covariances are symmetric 3x3 matrices stored as our Gaussian stage stores them: diag (xx, yy, zz) [rows][3] and off
// (xy, xz, yz) [rows][3] (host/ref/gaussian.hpp covariance_off_diagonal). The official contracts the full covariance
// (models.py lifts with diag=False, then lift_and_diagonalize); a diagonal one is off = 0, and Σ' is full either way.

#ifndef MIPNERF_CONTRACT_CL
#define MIPNERF_CONTRACT_CL

// The bounds of tests/ops/test_contract.cpp count the roundings of the expressions as written.
#pragma OPENCL FP_CONTRACT OFF

// The symmetric (p qᵀ + q pᵀ) off the diagonal: (xy, xz, yz).
inline float3 contract_sym_pair_off(float3 p, float3 q) {
  return (float3)(p.x * q.y + q.x * p.y, p.x * q.z + q.x * p.z, p.y * q.z + q.y * p.z);
}

// X·v for the symmetric X = (diag, off).
inline float3 contract_sym_times(float3 diag, float3 off, float3 v) {
  return (float3)(diag.x * v.x + off.x * v.y + off.y * v.z, off.x * v.x + diag.y * v.y + off.z * v.z,
                  off.y * v.x + off.z * v.y + diag.z * v.z);
}

// The direction and scales of a point outside the unit ball: u = x/|x| and inv_r = 1/|x|, with |x|² never formed in
// float (it overflows from |x| ≈ 1.8e19): x is scaled by 2^−k, k = ilogb(max |x_i|), exactly, so that the largest
// component lies in [1, 2) and the sum of squares q in [1, 12].
inline void contract_direction(float3 x, float3* u, float* inv_r) {
  const float biggest = fmax(fabs(x.x), fmax(fabs(x.y), fabs(x.z)));
  const int k = ilogb(biggest);
  // Per component: oclgrind 21.10 scales the lanes of ldexp(float3, int) wrongly (the direction came out wrong there).
  const float3 scaled = (float3)(ldexp(x.x, -k), ldexp(x.y, -k), ldexp(x.z, -k));
  const float q = scaled.x * scaled.x + scaled.y * scaled.y + scaled.z * scaled.z;
  const float inv_norm = rsqrt(q);
  *u = scaled * inv_norm;
  *inv_r = ldexp(inv_norm, -k);
}

// Outside the ball iff |x|² > 1, as the official's where(x_mag_sq <= 1, ...): any |x_i| > 1 is outside, and otherwise
// |x|² ≤ 3 is formed safely.
inline bool contract_is_outside(float3 x) {
  if (fmax(fabs(x.x), fmax(fabs(x.y), fabs(x.z))) > 1.0f) return true;
  return x.x * x.x + x.y * x.y + x.z * x.z > 1.0f;
}

// The three parts of the symmetric X in the split of J (see the top): the tangential block X⊥ = X − cross − radial,
// the cross terms u wᵀ + w uᵀ and the radial s P, each as (diag, off). Also v = Xu, s and w for the backward.
typedef struct {
  float3 perp_diag, perp_off, cross_diag, cross_off, radial_diag, radial_off;
  float3 v, w;
  float s;
} ContractSplit;

inline ContractSplit contract_split(float3 u, float3 diag, float3 off) {
  ContractSplit p;
  p.v = contract_sym_times(diag, off, u);
  p.s = u.x * p.v.x + u.y * p.v.y + u.z * p.v.z;
  p.w = p.v - p.s * u;
  p.cross_diag = 2.0f * u * p.w;
  p.cross_off = contract_sym_pair_off(u, p.w);
  p.radial_diag = p.s * (u * u);
  p.radial_off = p.s * (float3)(u.x * u.y, u.x * u.z, u.y * u.z);
  p.perp_diag = diag - p.cross_diag - p.radial_diag;
  p.perp_off = off - p.cross_off - p.radial_off;
  return p;
}

// J X J (J symmetric) for a point outside the ball: a²·X⊥ + a b·cross + b²·radial, factors applied one at a time.
inline void contract_jacobian_sandwich(float3 u, float inv_r, float3 diag, float3 off, float3* out_diag,
                                       float3* out_off) {
  const float a = (2.0f - inv_r) * inv_r;
  const ContractSplit p = contract_split(u, diag, off);
  *out_diag = (p.perp_diag * a) * a + ((p.cross_diag * a) * inv_r) * inv_r +
              (((p.radial_diag * inv_r) * inv_r) * inv_r) * inv_r;
  *out_off = (p.perp_off * a) * a + ((p.cross_off * a) * inv_r) * inv_r +
             (((p.radial_off * inv_r) * inv_r) * inv_r) * inv_r;
}

// One Gaussian through the contraction: (mean', diag', off') = (contract(mean), J Σ Jᵀ); inside the ball a copy.
inline void contract_gaussian(float3 mean, float3 diag, float3 off, float3* out_mean, float3* out_diag,
                              float3* out_off) {
  if (!contract_is_outside(mean)) {  // J = I: the Gaussian unchanged
    *out_mean = mean;
    *out_diag = diag;
    *out_off = off;
    return;
  }
  float3 u;
  float inv_r;
  contract_direction(mean, &u, &inv_r);
  contract_jacobian_sandwich(u, inv_r, diag, off, out_diag, out_off);
  *out_mean = (2.0f - inv_r) * u;
}

// One item per row: out_means = contract(means), (out_covs, out_cov_off) = J Σ Jᵀ.
//   means, covs, cov_off, out_means, out_covs, out_cov_off: [rows][3]
__kernel void contract_gaussians_fwd(__global const float* means, __global const float* covs,
                                     __global const float* cov_off, __global float* out_means,
                                     __global float* out_covs, __global float* out_cov_off, const uint n_rows) {
  const size_t row = get_global_id(0);
  if (row >= n_rows) return;
  float3 mean, diag, off;
  contract_gaussian(load3(means, row), load3(covs, row), load3(cov_off, row), &mean, &diag, &off);
  store3(out_means, row, mean);
  store3(out_covs, row, diag);
  store3(out_cov_off, row, off);
}

// One item per row: the gradients of a scalar L w.r.t. the stored inputs, given its gradients w.r.t. the outputs.
// off is one stored number for two matrix entries, so with G the symmetric ∂L/∂Σ' (G_ii = d_out_covs_i,
// G_ij = d_out_cov_off/2) and Σ' = JΣJ:
//   ∂L/∂Σ = J G J   (d_covs = its diagonal, d_cov_off = 2× its off-diagonal)
//   ∂L/∂μ = J g + [a′ tr((I − P) H) + b′ uᵀHu] u + 2 a′ (I − P) H u,   H = G J Σ + Σ J G,  g = d_out_means,
// from dJ = a′ dr (I − P) + b′ dr P + (b − a) dP, dr = uᵀdμ, dP = (du uᵀ + u duᵀ), du = (I − P) dμ / r, and
// (b − a)/r = a′ = −2(r − 1)/r³, b′ = −2/r³. With K = JΣ, v = Σu, p = Gu, s = uᵀv, w = v − s u:
//   Ku = a w + b s u,  Kᵀp = a (Σp − (u·p) v) + b (u·p) v,  Hu = G Ku + Kᵀp,  uᵀHu = 2 p·Ku,
//   tr((I − P) H) = 2 [a tr(G Σ⊥) + b p·w].
// Inside the ball J = I and J' = 0: the gradients pass through. On the sphere itself (|μ|² = 1) the inside branch, as
// the official's where(x_mag_sq <= 1, ...).
__kernel void contract_gaussians_bwd(__global const float* means, __global const float* covs,
                                     __global const float* cov_off, __global const float* d_out_means,
                                     __global const float* d_out_covs, __global const float* d_out_cov_off,
                                     __global float* d_means, __global float* d_covs, __global float* d_cov_off,
                                     const uint n_rows) {
  const size_t row = get_global_id(0);
  if (row >= n_rows) return;
  const float3 x = load3(means, row), g = load3(d_out_means, row);
  const float3 g_diag = load3(d_out_covs, row), g_off_stored = load3(d_out_cov_off, row);
  if (!contract_is_outside(x)) {
    store3(d_means, row, g);
    store3(d_covs, row, g_diag);
    store3(d_cov_off, row, g_off_stored);
    return;
  }
  const float3 diag = load3(covs, row), off = load3(cov_off, row);
  const float3 g_off = 0.5f * g_off_stored;  // G_ij of the matrix
  float3 u, dc_diag, dc_off;
  float inv_r;
  contract_direction(x, &u, &inv_r);
  contract_jacobian_sandwich(u, inv_r, g_diag, g_off, &dc_diag, &dc_off);
  store3(d_covs, row, dc_diag);
  store3(d_cov_off, row, 2.0f * dc_off);

  const float a = (2.0f - inv_r) * inv_r;
  const float a_slope_over_r2 = -2.0f * (1.0f - inv_r);  // a′ = this · inv_r²
  // J g = a (g − (u·g) u) + b (u·g) u
  const float g_along = u.x * g.x + u.y * g.y + u.z * g.z;
  float3 d_x = (g - g_along * u) * a + ((g_along * u) * inv_r) * inv_r;

  const ContractSplit sigma = contract_split(u, diag, off);
  const float3 p = contract_sym_times(g_diag, g_off, u);
  const float p_u = p.x * u.x + p.y * u.y + p.z * u.z;
  const float p_w = p.x * sigma.w.x + p.y * sigma.w.y + p.z * sigma.w.z;
  const float3 k_u = sigma.w * a + ((sigma.s * u) * inv_r) * inv_r;
  const float3 sigma_p = contract_sym_times(diag, off, p);
  const float3 kt_p = (sigma_p - p_u * sigma.v) * a + ((p_u * sigma.v) * inv_r) * inv_r;
  const float3 h_u = contract_sym_times(g_diag, g_off, k_u) + kt_p;
  const float h_uu = 2.0f * (p.x * k_u.x + p.y * k_u.y + p.z * k_u.z);
  const float3 gp = g_diag * sigma.perp_diag;
  const float3 go = g_off * sigma.perp_off;
  const float tr_g_perp = gp.x + gp.y + gp.z + 2.0f * (go.x + go.y + go.z);
  const float tr_perp_h = 2.0f * (tr_g_perp * a + (p_w * inv_r) * inv_r);
  // a′ tr⊥(H) + b′ uᵀHu, and 2 a′ (I − P) H u, with a′ = a_slope_over_r2 · inv_r², b′ = −2 inv_r³
  const float radial = ((tr_perp_h * inv_r) * inv_r) * a_slope_over_r2 + (((h_uu * inv_r) * inv_r) * inv_r) * -2.0f;
  const float3 tangential = (((h_u - h_uu * u) * inv_r) * inv_r) * (2.0f * a_slope_over_r2);
  d_x += radial * u + tangential;
  store3(d_means, row, d_x);
}

// The ray warps of construct_ray_warps with fn = reciprocal (configs/360.gin's raydist_fn), between near > 0 and
// far > near (far = INFINITY allowed; near = 0 makes the official NaN and is refused on the host):
//   s = (1/t − 1/near) / (1/far − 1/near),   t = 1 / (s/far + (1 − s)/near)   (the paper's eq. 11 with g = 1/x)
// t_to_s is evaluated as (1 − near/t)/(1 − near/far) written (t − near)/t ÷ (far − near)/far: the same value, whose
// differences of distances are exact near near (Sterbenz) where 1/t − 1/near would cancel; t = ∞ or far = ∞ take
// their limits (the fraction → 1). s_to_t adds two non-negative terms, as the official does.
inline float ray_warp_t_to_s_of(float t, float near, float far) {
  const float along = isinf(t) ? 1.0f : (t - near) / t;
  const float span = isinf(far) ? 1.0f : (far - near) / far;
  return along / span;
}

inline float ray_warp_s_to_t_of(float s, float inv_near, float inv_far) {
  return 1.0f / (s * inv_far + (1.0f - s) * inv_near);
}

// dt/ds = t² (1/near − 1/far): +∞ at t = ∞ (the official's jax.grad gives NaN there, 0 · ∞).
inline float ray_warp_dt_ds_of(float t, float inv_near, float inv_far) { return t * t * (inv_near - inv_far); }

// One item per value: s [n] = t_to_s(t [n]).
__kernel void ray_warp_t_to_s(__global const float* t, __global float* s, const float near, const float far,
                              const uint n) {
  const size_t i = get_global_id(0);
  if (i >= n) return;
  s[i] = ray_warp_t_to_s_of(t[i], near, far);
}

// One item per value: t [n] = s_to_t(s [n]) and dt_ds [n], its derivative (what a gradient w.r.t. metric distances
// needs to reach the normalised ones).
__kernel void ray_warp_s_to_t(__global const float* s, __global float* t, __global float* dt_ds, const float near,
                              const float far, const uint n) {
  const size_t i = get_global_id(0);
  if (i >= n) return;
  const float inv_near = 1.0f / near, inv_far = 1.0f / far;  // 1/∞ = 0
  const float ti = ray_warp_s_to_t_of(s[i], inv_near, inv_far);
  t[i] = ti;
  dt_ds[i] = ray_warp_dt_ds_of(ti, inv_near, inv_far);
}

#endif
