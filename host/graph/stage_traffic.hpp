// The least memory traffic of each stage the graph runs, in bytes: every input array element read once and every
// output element written once (float32 and uint32: 4 bytes). What a stage's kernels actually move can only be more
// (re-reads, caches missed); dividing these bytes by a stage's time therefore gives a lower bound on the bandwidth it
// achieved, which the stage profile compares with the machine's STREAM triad (bench/machine_probe.hpp): a stage near
// that figure is memory-bound, one far below it spends its time computing. The MLP's stages (products, bias + ReLU)
// are left out: they work on 256-row blocks in cache and their limit is the FMA rate, reported as GFLOP/s.
#pragma once

#include <cstddef>

namespace mipnerf::graph::traffic {

// "rays": the chunk's camera and pixel ids copied in (read + write), read by the ray kernel, which writes the ray
// bundle's floats (ops/ray_bundle.hpp): origin, direction (3 each), radius, near, far, loss multiplier, and with
// `view_dependence` the view direction (3; the kernel leaves it out otherwise).
double rays(size_t n_rays, bool view_dependence);

// "view encoding": each ray's view direction (3 floats) in, `view_width` features out.
double view_encoding(size_t n_rays, size_t view_width);

// "sampling" (stratified): each ray's near and far in, `intervals` + 1 edges out.
double stratified_sampling(size_t n_rays, size_t intervals);

// "resampling": the previous level's edges and weights in, `new_intervals` + 1 edges out; with `union_with_previous`
// (resample_union) the drawn edges are then merged with the previous ones: both read again, the union written.
double resampling(size_t n_rays, size_t previous_intervals, size_t new_intervals, bool union_with_previous);

// "encoding": a ray's origin, direction and radius (7 floats) and edges in, `feature_width` features a sample out.
double encoding(size_t n_rays, size_t intervals, size_t feature_width);

// "render" (activations fused): per sample the raw colour (3), raw density, an edge in and the weight out; per ray
// the direction in, colour (3), accumulated opacity and distance out. Without the colour (a level rendered for its
// weights only, render_raw_weights_fwd) neither colour is moved.
double render_forward(size_t n_rays, size_t intervals, bool with_colour = true);

// "loss": per ray the rendered colour (3), target colour (3) and loss multiplier in, the colour's gradient (3) out.
double loss(size_t n_rays);

// "render backward": per sample raw colour (3), raw density, an edge and the weight in, their gradients (3 + 1) out;
// per ray the direction and the colour's gradient (3) in.
double render_backward(size_t n_rays, size_t intervals);

// "adam": per parameter the gradient zeroed before the step (a write), read once for the finiteness check and its
// norm, then parameter, gradient and both moments read and parameter and moments written.
double adam(size_t parameters);

// "batch": per ray a camera id, a pixel id, an RGB target and a loss multiplier written, the pixel (RGB) read.
double batch(size_t n_rays);

}  // namespace mipnerf::graph::traffic
