// The MLP's element-wise stages around its CLBlast products (host/mlp/mlp.cpp): bias + activation forward,
// and the backward's activation mask fused with per-block column sums (bias gradients, per-ray sums).
// Matrices are row-major views: element (r, c) of a view is at base[offset + r·ld + c]. No atomics: every
// sum is written to its own partials slot and reduced in a fixed order, so results never depend on timing.

// ReLU that keeps NaN (NaN < 0 is false), so a non-finite value reaches the outputs and the host can see it;
// fmax(NaN, 0) would return 0 and hide it.
inline float relu_keep_nan(const float v) { return v < 0.0f ? 0.0f : v; }

// z[r][c] = act(z[r][c] + params[bias_offset + c]) with act = ReLU when apply_relu, identity otherwise.
// 2-D launch: x = column c < cols, y = row r < rows.
__kernel void mlp_bias_act_fwd(__global float* z, const uint z_offset, const uint ld, const uint rows,
                               const uint cols, __global const float* params, const uint bias_offset,
                               const uint apply_relu) {
  const uint c = get_global_id(0);
  const uint r = get_global_id(1);
  if (c >= cols || r >= rows) return;
  const size_t at = z_offset + (size_t)r * ld + c;
  const float v = z[at] + params[bias_offset + c];
  z[at] = apply_relu ? relu_keep_nan(v) : v;
}

// The view branch's layer: its input is [bottleneck | view_encoding], and the view encoding is the same for
// every sample of a ray, so its product is computed once per ray (ray_term [rays][cols]) and added here:
// z[r][c] = ReLU(z[r][c] + ray_term[r / samples_per_ray][c] + params[bias_offset + c]).
// 2-D launch: x = column, y = row.
__kernel void mlp_bias_ray_relu_fwd(__global float* z, const uint z_offset, const uint ld, const uint rows,
                                    const uint cols, __global const float* params, const uint bias_offset,
                                    __global const float* ray_term, const uint samples_per_ray) {
  const uint c = get_global_id(0);
  const uint r = get_global_id(1);
  if (c >= cols || r >= rows) return;
  const size_t at = z_offset + (size_t)r * ld + c;
  const uint ray = r / samples_per_ray;
  z[at] = relu_keep_nan(z[at] + ray_term[(size_t)ray * cols + c] + params[bias_offset + c]);
}

// Backward of an activation, fused with the column sums the bias gradient needs:
//   apply_relu: dz[r][c] = act[r][c] > 0 ? dz[r][c] : 0, in place (act is the layer's ReLU output, so
//               act > 0 exactly where the pre-activation was > 0); otherwise dz is only read.
//   partials[b][c] = Σ dz[r][c] over the rows r of block b (rows b·rows_per_block … + rows_per_block − 1).
// With rows_per_block = samples_per_ray the partials are per-ray sums (the view branch's per-ray product).
// 2-D launch: x = column c < cols, y = block b < ceil(rows / rows_per_block).
__kernel void mlp_act_bwd_partial(__global float* dz, const uint dz_offset, const uint dz_ld,
                                  __global const float* act, const uint act_offset, const uint act_ld,
                                  const uint rows, const uint cols, const uint rows_per_block,
                                  const uint apply_relu, __global float* partials) {
  const uint c = get_global_id(0);
  const uint block = get_global_id(1);
  const uint n_blocks = (rows + rows_per_block - 1) / rows_per_block;
  if (c >= cols || block >= n_blocks) return;
  const uint first = block * rows_per_block;
  const uint last = min(rows, first + rows_per_block);
  float sum = 0.0f;
  for (uint r = first; r < last; ++r) {
    const size_t at = dz_offset + (size_t)r * dz_ld + c;
    float g = dz[at];
    if (apply_relu) {
      g = act[act_offset + (size_t)r * act_ld + c] > 0.0f ? g : 0.0f;
      dz[at] = g;
    }
    sum += g;
  }
  partials[(size_t)block * cols + c] = sum;
}

// grad[grad_offset + c] += Σ_b partials[b][c], b = 0 … n_blocks − 1 in order: the bias gradient, accumulated
// (beta = 1) over chunks and levels like the weight gradients. 1-D launch over columns.
__kernel void mlp_sum_partials(__global const float* partials, const uint n_blocks, const uint cols,
                               __global float* grad, const uint grad_offset) {
  const uint c = get_global_id(0);
  if (c >= cols) return;
  float sum = 0.0f;
  for (uint b = 0; b < n_blocks; ++b) sum += partials[(size_t)b * cols + c];
  grad[grad_offset + c] += sum;
}
