// mip-NeRF 360's distortion loss (Barron et al. 2022, eq. 15; the official camp_zipnerf stepfun.lossfun_distortion and
// loss_utils.distortion_loss), forward and backward, in the paper's O(N) form.
//
// Per ray, over N intervals with edges t [N+1] (normalised s-distances, or whatever curve of them the caller chose)
// and weights w [N], with midpoints u_i = (t_i + t_{i+1}) / 2:
//   L = Σ_{i,j} w_i w_j |u_i − u_j| + (1/3) Σ_i w_i² (t_{i+1} − t_i)                         (eq. 15)
//   loss = mult · mean over rays of L
// O(N) (the paper notes eq. 15 takes linear time with prefix sums; this is such a form): with t sorted the midpoints
// are sorted, so
//   Σ_{i,j} w_i w_j |u_i − u_j| = 2 Σ_i w_i A_i,  A_i = Σ_{j<i} w_j (u_i − u_j) = A_{i−1} + W_{<i} · (u_i − u_{i−1})
// where W_{<i} = Σ_{j<i} w_j. The recurrence adds only non-negative terms (u_i − u_{i−1} = (t_{i+1} − t_{i−1}) / 2
// taken from the edges directly), where the textbook u_i · W_{<i} − Σ_{j<i} w_j u_j cancels when the ray's distances
// are large against its intervals. The backward likewise, with the suffix B_i = Σ_{j>i} w_j (u_j − u_i):
//   ∂L/∂w_k = 2 (A_k + B_k) + (2/3) w_k (t_{k+1} − t_k)
//   ∂L/∂u_k = 2 w_k (W_{<k} − W_{>k})   (W_{>k} = W − W_{<k} − w_k: an absolute error of a few ulp of W)
// and u_k = (t_k + t_{k+1}) / 2, so for the edges
//   ∂L/∂t_e = ½ ∂L/∂u_e − w_e² / 3  +  ½ ∂L/∂u_{e−1} + w_{e−1}² / 3   (the terms of intervals that exist)
// At tied midpoints |u_i − u_j| has a kink; the t-gradient takes the subgradient that counts every j < k as below u_k.
// Reference: host/ref/distortion.hpp (same names).

// One work-item per ray: ray_loss [R] = L of each ray (the loss is mult · Σ ray_loss / R).
//   t [R][N+1] sorted, w [R][N]
__kernel void distortion_fwd(__global const float* t, __global const float* w, __global float* ray_loss,
                             const uint n_rays, const uint n_intervals) {
  const uint ray = get_global_id(0);
  if (ray >= n_rays) return;
  __global const float* ray_t = t + (size_t)ray * (n_intervals + 1);
  __global const float* ray_w = w + (size_t)ray * n_intervals;
  float weight_below = 0.0f, spread_below = 0.0f, loss = 0.0f;  // W_{<i}, A_i
  for (uint i = 0; i < n_intervals; ++i) {
    if (i > 0) spread_below += weight_below * 0.5f * (ray_t[i + 1] - ray_t[i - 1]);
    const float wi = ray_w[i];
    loss += wi * (2.0f * spread_below + wi * (ray_t[i + 1] - ray_t[i]) * (1.0f / 3.0f));
    weight_below += wi;
  }
  ray_loss[ray] = loss;
}

// One work-item per ray: d_w [R][N] = grad_scale · ∂L/∂w, d_t [R][N+1] = grad_scale · ∂L/∂t (grad_scale = mult / R
// for the whole batch, times the upstream gradient). d_w first holds B_k from the backward sweep, then the gradient.
__kernel void distortion_bwd(__global const float* t, __global const float* w, const float grad_scale,
                             __global float* d_w, __global float* d_t, const uint n_rays, const uint n_intervals) {
  const uint ray = get_global_id(0);
  if (ray >= n_rays) return;
  __global const float* ray_t = t + (size_t)ray * (n_intervals + 1);
  __global const float* ray_w = w + (size_t)ray * n_intervals;
  __global float* ray_d_w = d_w + (size_t)ray * n_intervals;
  __global float* ray_d_t = d_t + (size_t)ray * (n_intervals + 1);
  // Suffix sweep: B_k = B_{k+1} + W_{>k} (u_{k+1} − u_k), parked in d_w.
  float weight_above = 0.0f, spread_above = 0.0f;
  for (uint k = n_intervals; k-- > 0;) {
    if (k + 1 < n_intervals) spread_above += weight_above * 0.5f * (ray_t[k + 2] - ray_t[k]);
    ray_d_w[k] = spread_above;
    weight_above += ray_w[k];
  }
  const float weight_total = weight_above;
  // Prefix sweep: A_k and W_{<k}; each edge's gradient gathers its two intervals' terms.
  float weight_below = 0.0f, spread_below = 0.0f, d_t_from_left = 0.0f;  // d_t_from_left: interval k−1's share of t_k
  for (uint k = 0; k < n_intervals; ++k) {
    if (k > 0) spread_below += weight_below * 0.5f * (ray_t[k + 1] - ray_t[k - 1]);
    const float wk = ray_w[k], width = ray_t[k + 1] - ray_t[k];
    ray_d_w[k] = grad_scale * (2.0f * (spread_below + ray_d_w[k]) + (2.0f / 3.0f) * wk * width);
    const float d_u = 2.0f * wk * (weight_below - (weight_total - weight_below - wk));
    const float self = wk * wk * (1.0f / 3.0f);
    ray_d_t[k] = grad_scale * (d_t_from_left + 0.5f * d_u - self);
    d_t_from_left = 0.5f * d_u + self;
    weight_below += wk;
  }
  ray_d_t[n_intervals] = grad_scale * d_t_from_left;
}
