// Volume rendering (kernels/render.cl): forward and backward against the double reference with derived float32
// bounds, the backward against central finite differences, the hard cases (σ = 0, σ = 1e10, δ = 0, acc = 0, σ·δ
// overflowing to +∞, t around 1e4), every background, the fused activation + render kernels against the
// composition, the fused kernels' density noise (its draws, its keys, its backward), and the weights' backward
// (render_raw_weights_bwd: ∂L/∂raw_density from ∂L/∂w) against the reference, finite differences and render_raw_bwd.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "cl/launch.hpp"
#include "core/rng.hpp"
#include "kernel_checks.hpp"
#include "ops/activations.hpp"
#include "ops/render.hpp"
#include "ref/activations.hpp"
#include "ref/render.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

// One batch of rendering inputs, float as uploaded.
struct Batch {
  size_t n_rays = 0, n_samples = 0;
  std::vector<float> rgb, density, t_edges, directions, d_comp_rgb, d_acc;
};

// Edges from t_0 ∈ [0.5, 3] with log-uniform gaps (and some empty intervals), directions of norm 0.5..2,
// densities log-uniform over `density_lo..density_hi` with 20 % zeros, colours in [0, 1], and random upstream
// gradients.
Batch random_batch(size_t n_rays, size_t n_samples, unsigned seed, double density_lo = 1e-3, double density_hi = 1e3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  Batch b;
  b.n_rays = n_rays;
  b.n_samples = n_samples;
  for (size_t r = 0; r < n_rays; ++r) {
    float t = static_cast<float>(0.5 + 2.5 * unit(rng));
    b.t_edges.push_back(t);
    for (size_t i = 0; i < n_samples; ++i) {
      if (unit(rng) > 0.05) t += static_cast<float>(test::log_uniform(rng, 1e-3, 0.5));
      b.t_edges.push_back(t);
      b.density.push_back(unit(rng) < 0.2 ? 0.0f : static_cast<float>(test::log_uniform(rng, density_lo, density_hi)));
      for (int c = 0; c < 3; ++c) b.rgb.push_back(static_cast<float>(unit(rng)));
    }
    const double norm = 0.5 + 1.5 * unit(rng);
    double d[3] = {signed_unit(rng), signed_unit(rng), signed_unit(rng) - 0.1};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (double v : d) b.directions.push_back(static_cast<float>(v / len * norm));
    for (int c = 0; c < 3; ++c) b.d_comp_rgb.push_back(static_cast<float>(signed_unit(rng)));
    b.d_acc.push_back(static_cast<float>(signed_unit(rng)));
  }
  return b;
}

struct DeviceResult {
  std::vector<float> comp_rgb, acc, distance, weights, d_rgb, d_density;
};

// Runs Render::fwd and ::bwd (or the fused raw_* kernels, on raw inputs, with `noise` keying their density noise)
// for one batch, walking the samples as `loop` says.
DeviceResult run_device(const RenderOptions& options, const Batch& b, bool with_d_acc, bool raw = false,
                        const ActivationOptions& activation = {}, const DensityNoiseKey& noise = {},
                        ops::RenderSampleLoop loop = ops::RenderSampleLoop::device_default) {
  auto& ctx = test::test_context();
  auto rgb = test::upload(ctx, b.rgb, "rgb"), density = test::upload(ctx, b.density, "density");
  auto t_edges = test::upload(ctx, b.t_edges, "t_edges");
  ops::RayBundle rays(ctx, b.n_rays);  // only the directions are read
  rays.directions.upload(ctx, b.directions);
  auto d_comp = test::upload(ctx, b.d_comp_rgb, "d_comp_rgb"), d_acc = test::upload(ctx, b.d_acc, "d_acc");
  const size_t rows = b.n_rays * b.n_samples;
  ocl::DeviceArray<float> comp(ctx, 3 * b.n_rays, "comp_rgb"), acc(ctx, b.n_rays, "acc");
  ocl::DeviceArray<float> distance(ctx, b.n_rays, "distance"), weights(ctx, rows, "weights");
  ocl::DeviceArray<float> d_rgb(ctx, 3 * rows, "d_rgb"), d_density(ctx, rows, "d_density");
  ops::Render render(ctx, options, activation, loop);
  const ops::RenderInputs in{rgb, density, t_edges, rays, b.n_rays, b.n_samples};
  const ops::RenderOutputs out{comp, acc, distance, weights};
  const ops::RenderGradients grads{d_comp, with_d_acc ? &d_acc : nullptr};
  if (raw) {
    render.raw_fwd(in, out, noise);
    render.raw_bwd(in, weights, grads, {d_rgb, d_density}, noise);
  } else {
    render.fwd(in, out);
    render.bwd(in, weights, grads, {d_rgb, d_density});
  }
  return {comp.download(ctx),    acc.download(ctx),   distance.download(ctx),
          weights.download(ctx), d_rgb.download(ctx), d_density.download(ctx)};
}

// Render::bwd alone on the given weights (with d_acc), walking the samples as `loop` says: d_rgb and d_density.
DeviceResult run_backward_on(const RenderOptions& options, const Batch& b, const std::vector<float>& weight_values,
                             ops::RenderSampleLoop loop) {
  auto& ctx = test::test_context();
  auto rgb = test::upload(ctx, b.rgb, "rgb"), density = test::upload(ctx, b.density, "density");
  auto t_edges = test::upload(ctx, b.t_edges, "t_edges"), weights = test::upload(ctx, weight_values, "weights");
  ops::RayBundle rays(ctx, b.n_rays);
  rays.directions.upload(ctx, b.directions);
  auto d_comp = test::upload(ctx, b.d_comp_rgb, "d_comp_rgb"), d_acc = test::upload(ctx, b.d_acc, "d_acc");
  const size_t rows = b.n_rays * b.n_samples;
  ocl::DeviceArray<float> d_rgb(ctx, 3 * rows, "d_rgb"), d_density(ctx, rows, "d_density");
  ops::Render(ctx, options, {}, loop)
      .bwd({rgb, density, t_edges, rays, b.n_rays, b.n_samples}, weights, {d_comp, &d_acc}, {d_rgb, d_density});
  DeviceResult result;
  result.d_rgb = d_rgb.download(ctx);
  result.d_density = d_density.download(ctx);
  return result;
}

// Every output of two device runs, bit for bit.
void check_bit_equal(const DeviceResult& a, const DeviceResult& b) {
  CHECK(a.comp_rgb == b.comp_rgb);
  CHECK(a.acc == b.acc);
  CHECK(a.distance == b.distance);
  CHECK(a.weights == b.weights);
  CHECK(a.d_rgb == b.d_rgb);
  CHECK(a.d_density == b.d_density);
}

struct RefResult {
  std::vector<double> comp_rgb, acc, distance, weights, d_rgb, d_density;
};

// The central-difference step of the reference's derivative checks: h = 1e-6·max(|x|, 1) (each use says why its
// truncation and rounding errors stay below 1e-9 with it).
double central_step(double x) { return 1e-6 * std::max(std::abs(x), 1.0); }

// ∂loss/∂x by central differences with central_step(x); x is restored.
double central_difference(double& x, const std::function<double()>& loss) {
  const double x0 = x, h = central_step(x0);
  x = x0 + h;
  const double up = loss();
  x = x0 - h;
  const double down = loss();
  x = x0;
  return (up - down) / (2 * h);
}

RefResult run_ref(const RenderOptions& options, const Batch& b, bool with_d_acc) {
  RefResult r;
  const auto rgb = test::to_double(b.rgb), density = test::to_double(b.density);
  const auto t_edges = test::to_double(b.t_edges), directions = test::to_double(b.directions);
  const auto d_acc = test::to_double(b.d_acc);
  ref::render_fwd(options, rgb, density, t_edges, directions, r.comp_rgb, r.acc, r.distance, r.weights, b.n_rays,
                  b.n_samples);
  ref::render_bwd(options, rgb, density, t_edges, directions, r.weights, test::to_double(b.d_comp_rgb),
                  with_d_acc ? &d_acc : nullptr, r.d_rgb, r.d_density, b.n_rays, b.n_samples);
  return r;
}

// Float32 error bounds of the forward and backward, per element, from the exact (double) quantities.
//  - s_i = σ_i·δ_i: δ = (t1 − t0)·sqrt(d·d) is ≤ 13 roundoffs (subtraction; dot product; sqrt ≤ 3 ulp = 6u;
//    two products), so |Δs|/s ≤ 16u.
//  - S_i = Σ_{j<i} s_j summed in order: |ΔS_i| ≤ (16 + i)·u·S_i (positive terms).
//  - T_i = exp(−S_i): relative error |ΔS_i| + 6u (exp ≤ 3 ulp). α_i = −expm1(−s_i): 6u + 16u (its condition
//    number s·e^−s/α ≤ 1). So e_w,i = (30 + (16 + N)·S_i)·u bounds the relative error of w_i (+1u product).
//  - Sums over N terms add N·u relative to the sum of magnitudes.
// Every tolerance below is twice the bound, so the tests fail on a real error, not on a tight estimate.
struct Bounds {
  std::vector<double> weights, comp_rgb, acc, distance, d_rgb, d_density;
};

Bounds float_bounds(const RenderOptions& options, const Batch& b, const RefResult& r, bool with_d_acc) {
  const size_t n = b.n_samples;
  const double u = kUnitRoundoff;
  const double tiny = 1e-43;  // a few float denormal ulps, for values that underflow
  const bool white = options.background == Background::white;
  Bounds out;
  out.weights.resize(b.n_rays * n);
  out.comp_rgb.resize(3 * b.n_rays);
  out.acc.resize(b.n_rays);
  out.distance.resize(b.n_rays);
  out.d_rgb.resize(3 * b.n_rays * n);
  out.d_density.resize(b.n_rays * n);
  std::vector<double> e_w(n), prefix(n + 1), delta(n), g(n), g_mag(n);
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    const float* dir = b.directions.data() + 3 * ray;
    const double dir_norm = std::sqrt(double(dir[0]) * dir[0] + double(dir[1]) * dir[1] + double(dir[2]) * dir[2]);
    const float* t = b.t_edges.data() + ray * (n + 1);
    const float* d_comp = b.d_comp_rgb.data() + 3 * ray;
    const double d_comp_sum = double(d_comp[0]) + d_comp[1] + d_comp[2];
    const double d_comp_mag = std::abs(d_comp[0]) + std::abs(d_comp[1]) + std::abs(d_comp[2]);
    const double d_acc_total = (with_d_acc ? b.d_acc[ray] : 0.0) - (white ? d_comp_sum : 0.0);
    const double d_acc_mag = (with_d_acc ? std::abs(b.d_acc[ray]) : 0.0) + (white ? d_comp_mag : 0.0);
    double acc_err = 0.0, comp_err[3] = {0, 0, 0}, comp_mag[3] = {0, 0, 0};
    prefix[0] = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const size_t at = ray * n + i;
      delta[i] = (double(t[i + 1]) - t[i]) * dir_norm;
      const bool opaque_last = options.opaque_background && i + 1 == n;  // s = ∞: α = 1 exactly, T_N = 0 exactly
      prefix[i + 1] = prefix[i] + (opaque_last ? INFINITY : delta[i] > 0 ? b.density[at] * delta[i] : 0.0);
      e_w[i] = (30.0 + (16.0 + n) * prefix[i]) * u;
      const double w = r.weights[at];
      out.weights[at] = 2 * e_w[i] * w + tiny;
      acc_err += e_w[i] * w;
      g[i] = d_acc_total;
      g_mag[i] = d_acc_mag;
      for (int c = 0; c < 3; ++c) {
        const double color = b.rgb[3 * at + c];
        g[i] += d_comp[c] * color;
        g_mag[i] += std::abs(d_comp[c] * color);
        comp_err[c] += e_w[i] * w * std::abs(color);
        comp_mag[c] += w * std::abs(color);
        out.d_rgb[3 * at + c] = 2 * (e_w[i] + u) * w * std::abs(d_comp[c]) + tiny;
      }
    }
    const double acc = r.acc[ray];
    out.acc[ray] = 2 * (acc_err + n * u * acc) + tiny;
    for (int c = 0; c < 3; ++c) {
      out.comp_rgb[3 * ray + c] =
          2 * (comp_err[c] + n * u * comp_mag[c] + (white ? acc_err + n * u * acc + u : 0.0)) + tiny;
    }
    // distance = Σ w·t_mid / Σ w: relative weight errors ε_i move it by Σ w_i·ε_i·|t_mid_i − distance| / acc.
    double dist_err = (n + 4) * u * std::abs(double(t[n]));
    if (acc > 0) {
      for (size_t i = 0; i < n; ++i) {
        const double mid = 0.5 * (double(t[i]) + t[i + 1]);
        dist_err += r.weights[ray * n + i] * e_w[i] * std::abs(mid - r.distance[ray]) / acc;
      }
    }
    out.distance[ray] = 2 * dist_err;
    // Backward, reverse sweep as the kernel: T_{i+1} = T_N + A_i, A_i = Σ_{k>i} w_k, B_i = Σ_{k>i} g_k·w_k, each
    // with its float error from the weights' (e_w), g's (4 roundoffs of its magnitude) and the running sums (N·u).
    const double trans_last = std::exp(-prefix[n]);
    const double trans_last_err = trans_last > 0.0 ? ((16.0 + n) * prefix[n] + 6.0) * u * trans_last : 0.0;
    double a = 0.0, a_err = 0.0, bsum = 0.0, b_err = 0.0;
    for (size_t rr = 0; rr < n; ++rr) {
      const size_t i = n - 1 - rr, at = ray * n + i;
      const double trans_next = trans_last + a;
      const double trans_next_err = trans_last_err + a_err + n * u * a + u * trans_next;
      const double d_s = g[i] * trans_next - bsum;
      const double d_s_err = std::abs(g[i]) * trans_next_err + 4 * u * g_mag[i] * trans_next + b_err +
                             n * u * std::abs(bsum) + u * (std::abs(g[i]) * trans_next + std::abs(bsum));
      out.d_density[at] = delta[i] > 0 ? 2 * (delta[i] * d_s_err + 16 * u * delta[i] * std::abs(d_s)) + tiny : tiny;
      const double w = r.weights[at];
      a += w;
      a_err += e_w[i] * w;
      bsum += g[i] * w;
      b_err += (std::abs(g[i]) * e_w[i] + 4 * u * g_mag[i]) * w;
    }
  }
  return out;
}

std::function<double(size_t)> from(const std::vector<double>& bounds) {
  return [&bounds](size_t i) { return bounds[i]; };
}

const ops::RenderSampleLoop kSampleLoops[] = {ops::RenderSampleLoop::per_ray, ops::RenderSampleLoop::lockstep,
                                              ops::RenderSampleLoop::per_vector};

const char* loop_name(ops::RenderSampleLoop loop) {
  switch (loop) {
    case ops::RenderSampleLoop::lockstep:
      return "samples in lockstep";
    case ops::RenderSampleLoop::per_vector:
      return "samples by vectors of 16";
    default:
      return "a ray per item";
  }
}

// Every output of a device run against the reference within its bounds.
void check_within_bounds(const DeviceResult& dev, const RefResult& r, const Bounds& bounds) {
  MIPNERF_CHECK_CLOSE("weights", dev.weights, r.weights, from(bounds.weights));
  MIPNERF_CHECK_CLOSE("comp_rgb", dev.comp_rgb, r.comp_rgb, from(bounds.comp_rgb));
  MIPNERF_CHECK_CLOSE("acc", dev.acc, r.acc, from(bounds.acc));
  MIPNERF_CHECK_CLOSE("distance", dev.distance, r.distance, from(bounds.distance));
  MIPNERF_CHECK_CLOSE("d_rgb", dev.d_rgb, r.d_rgb, from(bounds.d_rgb));
  MIPNERF_CHECK_CLOSE("d_density", dev.d_density, r.d_density, from(bounds.d_density));
}

// The device's forward and backward against the reference bounds, every way of walking the samples.
void check_against_reference(const RenderOptions& options, const Batch& b, bool with_d_acc) {
  const auto r = run_ref(options, b, with_d_acc);
  const auto bounds = float_bounds(options, b, r, with_d_acc);
  for (const auto loop : kSampleLoops) {
    INFO(loop_name(loop));
    const auto dev = run_device(options, b, with_d_acc, false, {}, {}, loop);
    check_within_bounds(dev, r, bounds);
  }
}

const Background kBackgrounds[] = {Background::none, Background::black, Background::white};

// L = Σ_c d_comp_c·comp_rgb_c + d_acc·acc of one ray through the reference forward, with the ray's inputs in
// double (perturbed by the caller).
double ray_loss(const RenderOptions& options, const std::vector<double>& rgb, const std::vector<double>& density,
                const std::vector<double>& t_edges, const std::vector<double>& direction, const double* d_comp,
                const double* d_acc, size_t n_samples) {
  std::vector<double> comp, acc, distance, weights;
  ref::render_fwd(options, rgb, density, t_edges, direction, comp, acc, distance, weights, 1, n_samples);
  double loss = d_acc ? *d_acc * acc[0] : 0.0;
  for (int c = 0; c < 3; ++c) loss += d_comp[c] * comp[c];
  return loss;
}

// Central finite differences of ray_loss for every colour and density of every ray.
void finite_differences(const RenderOptions& options, const Batch& b, bool with_d_acc, std::vector<double>& fd_rgb,
                        std::vector<double>& fd_density) {
  const size_t n = b.n_samples;
  fd_rgb.assign(3 * b.n_rays * n, 0.0);
  fd_density.assign(b.n_rays * n, 0.0);
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    std::vector<double> rgb(b.rgb.begin() + 3 * ray * n, b.rgb.begin() + 3 * (ray + 1) * n);
    std::vector<double> density(b.density.begin() + ray * n, b.density.begin() + (ray + 1) * n);
    const std::vector<double> t(b.t_edges.begin() + ray * (n + 1), b.t_edges.begin() + (ray + 1) * (n + 1));
    const std::vector<double> dir(b.directions.begin() + 3 * ray, b.directions.begin() + 3 * ray + 3);
    const double d_comp[3] = {b.d_comp_rgb[3 * ray], b.d_comp_rgb[3 * ray + 1], b.d_comp_rgb[3 * ray + 2]};
    const double d_acc = b.d_acc[ray];
    const auto loss = [&] { return ray_loss(options, rgb, density, t, dir, d_comp, with_d_acc ? &d_acc : nullptr, n); };
    for (size_t i = 0; i < n; ++i) {
      const double sigma = density[i], h = 1e-6 * std::max(sigma, 1.0);
      density[i] = sigma + h;
      const double up = loss();
      density[i] = sigma - h;
      const double down = loss();
      density[i] = sigma;
      fd_density[ray * n + i] = (up - down) / (2 * h);
      for (int c = 0; c < 3; ++c) {
        const double x = rgb[3 * i + c], hc = 1e-6;
        rgb[3 * i + c] = x + hc;
        const double up_c = loss();
        rgb[3 * i + c] = x - hc;
        const double down_c = loss();
        rgb[3 * i + c] = x;
        fd_rgb[3 * (ray * n + i) + c] = (up_c - down_c) / (2 * hc);
      }
    }
  }
}

size_t count_outside(const std::vector<double>& a, const std::vector<double>& b,
                     const std::function<double(size_t)>& tol) {
  size_t failures = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!(std::abs(a[i] - b[i]) <= tol(i))) ++failures;
  }
  return failures;
}

}  // namespace

TEST_CASE("render: forward and backward match the CPU reference on 10,000 random rays, every background") {
  // (a tenth of them under the oclgrind simulator: test::batch_for_device)
  const Batch b = random_batch(test::batch_for_device(10000), 32, 101);
  for (auto background : kBackgrounds) {
    for (bool with_d_acc : {false, true}) {
      INFO("background " << static_cast<int>(background) << ", d_acc " << with_d_acc);
      check_against_reference({background}, b, with_d_acc);
    }
  }
}

TEST_CASE("render: an opaque background (mip-NeRF 360) - the last interval takes what is left, every sample walk") {
  // OPAQUE_BACKGROUND: s_{N-1} = ∞, so w_{N-1} = T_{N-1}, acc = 1 and the last density has no gradient. 32 samples put
  // the last in a vector of the per-vector walk, 23 in its scalar tail; every background (none of it shows).
  for (const size_t n_samples : {size_t(32), size_t(23)}) {
    Batch b = random_batch(test::batch_for_device(3000), n_samples, 111);
    for (size_t i = 0; i < n_samples; ++i) b.density[i] = 0.0f;  // ray 0 empty: all background without the option
    for (auto background : kBackgrounds) {
      INFO("samples " << n_samples << ", background " << static_cast<int>(background));
      const RenderOptions options{background, 0.0f, true};
      check_against_reference(options, b, true);
      const auto r = run_ref(options, b, true);
      const auto dev = run_device(options, b, true);
      for (size_t ray = 0; ray < b.n_rays; ++ray) {
        CHECK(std::abs(r.acc[ray] - 1.0) <= 1e-12);
        CHECK(r.d_density[ray * n_samples + n_samples - 1] == 0.0);
        CHECK(dev.d_density[ray * n_samples + n_samples - 1] == 0.0f);
      }
      // Without it the empty ray shows only background (and of the random rays, 53 of 3,000 with 32 samples and 191
      // with 23 keep more than 0.001 of it); with it the last interval takes the whole ray.
      const auto see_through = run_ref({background}, b, true);
      CHECK(see_through.acc[0] == 0.0);
      CHECK(dev.acc[0] == 1.0f);
      CHECK(dev.weights[n_samples - 1] == 1.0f);
    }
  }
  // The reference backward is the derivative of its forward with the last interval opaque.
  const Batch small = random_batch(200, 16, 112, 1e-2, 1e2);
  const RenderOptions options{Background::white, 0.0f, true};
  std::vector<double> fd_rgb, fd_density;
  finite_differences(options, small, true, fd_rgb, fd_density);
  const auto r = run_ref(options, small, true);
  const auto fd_tol = [](const std::vector<double>& fd) {
    return std::function<double(size_t)>([&fd](size_t i) { return 1e-8 + 1e-7 * std::abs(fd[i]); });
  };
  CHECK(count_outside(r.d_rgb, fd_rgb, fd_tol(fd_rgb)) == 0);
  CHECK(count_outside(r.d_density, fd_density, fd_tol(fd_density)) == 0);
}

TEST_CASE("render: the backward matches central finite differences of the reference forward") {
  // Densities 1e-2..1e2 over gaps up to 0.5: optical thicknesses around 1, where the gradient is informative.
  const Batch b = random_batch(300, 16, 202, 1e-2, 1e2);
  for (auto background : kBackgrounds) {
    for (bool with_d_acc : {false, true}) {
      INFO("background " << static_cast<int>(background) << ", d_acc " << with_d_acc);
      const RenderOptions options{background};
      std::vector<double> fd_rgb, fd_density;
      finite_differences(options, b, with_d_acc, fd_rgb, fd_density);
      const auto r = run_ref(options, b, with_d_acc);
      const auto dev = run_device(options, b, with_d_acc);
      const auto bounds = float_bounds(options, b, r, with_d_acc);
      // Finite-difference error with h = 1e-6·max(σ, 1): truncation h²/6 times the third derivative (each weight
      // is a product of exponentials of σ·δ, δ ≤ 1: |L'''| ≤ ~10) plus rounding 1e-16/h: below 1e-9 here. The
      // reference backward must agree to 1e-8 + 1e-7 relative; the device backward to its float32 bound plus that.
      const auto fd_tol = [](const std::vector<double>& fd) {
        return std::function<double(size_t)>([&fd](size_t i) { return 1e-8 + 1e-7 * std::abs(fd[i]); });
      };
      CHECK(count_outside(r.d_rgb, fd_rgb, fd_tol(fd_rgb)) == 0);
      CHECK(count_outside(r.d_density, fd_density, fd_tol(fd_density)) == 0);
      MIPNERF_CHECK_CLOSE("device d_rgb vs finite differences", dev.d_rgb, fd_rgb,
                          [&](size_t i) { return bounds.d_rgb[i] + fd_tol(fd_rgb)(i); });
      MIPNERF_CHECK_CLOSE("device d_density vs finite differences", dev.d_density, fd_density,
                          [&](size_t i) { return bounds.d_density[i] + fd_tol(fd_density)(i); });
    }
  }
}

TEST_CASE("render: hard cases stay finite - sigma 0, sigma 1e10, empty intervals, zero accumulation") {
  const size_t n_rays = 6, n = 8;
  Batch b = random_batch(n_rays, n, 303);
  // Ray 0: σ = 0 everywhere (acc = 0). Ray 1: σ = 1e10 everywhere. Ray 2: every interval empty (t constant) with
  // σ = 1e10. Ray 3: empty intervals with σ = +∞ (∞·0 must not make a NaN). Ray 4: clear, then one opaque sample.
  // Ray 5: densities of 1e-38, whose weights are denormal or zero.
  for (size_t i = 0; i < n; ++i) {
    b.density[0 * n + i] = 0.0f;
    b.density[1 * n + i] = 1e10f;
    b.density[2 * n + i] = 1e10f;
    b.density[3 * n + i] = INFINITY;
    b.density[4 * n + i] = i == 5 ? 1e10f : 0.0f;
    b.density[5 * n + i] = 1e-38f;
  }
  for (size_t ray : {size_t(2), size_t(3)}) {
    for (size_t k = 0; k <= n; ++k) b.t_edges[ray * (n + 1) + k] = 4.0f;
  }
  for (size_t k = 0; k <= n; ++k) b.t_edges[4 * (n + 1) + k] = 2.0f + 0.25f * k;  // no empty interval on ray 4
  for (auto background : kBackgrounds) {
    INFO("background " << static_cast<int>(background));
    const RenderOptions options{background};
    for (const auto loop : kSampleLoops) {
      INFO(loop_name(loop));
      const auto dev = run_device(options, b, true, false, {}, {}, loop);
      for (const auto* v : {&dev.comp_rgb, &dev.acc, &dev.distance, &dev.weights, &dev.d_rgb, &dev.d_density}) {
        CHECK(test::all_finite(*v));
      }
      const float bg = background == Background::white ? 1.0f : 0.0f;
      const auto t_at = [&](size_t ray, size_t k) { return b.t_edges[ray * (n + 1) + k]; };
      // σ = 0: nothing accumulates; the background shows; distance = t_0 (official nan_to_num + clip).
      CHECK(dev.acc[0] == 0.0f);
      for (int c = 0; c < 3; ++c) CHECK(dev.comp_rgb[c] == bg);
      CHECK(dev.distance[0] == t_at(0, 0));
      // σ = 1e10: the first non-empty sample takes all the weight.
      size_t first = 0;
      while (t_at(1, first + 1) == t_at(1, first)) ++first;
      CHECK(dev.weights[1 * n + first] == 1.0f);
      CHECK(dev.acc[1] == 1.0f);
      for (int c = 0; c < 3; ++c) CHECK(dev.comp_rgb[3 + c] == b.rgb[3 * (1 * n + first) + c]);
      CHECK(dev.distance[1] == doctest::Approx(0.5 * (t_at(1, first) + t_at(1, first + 1))).epsilon(1e-6));
      // Behind an opaque sample nothing changes the colour: the density gradients there are 0.
      for (size_t i = first + 1; i < n; ++i) CHECK(dev.d_density[1 * n + i] == 0.0f);
      // Empty intervals: no weight whatever σ (even ∞), distance = the common t, zero density gradients.
      for (size_t ray : {size_t(2), size_t(3)}) {
        CHECK(dev.acc[ray] == 0.0f);
        CHECK(dev.distance[ray] == 4.0f);
        for (size_t i = 0; i < n; ++i) CHECK(dev.d_density[ray * n + i] == 0.0f);
      }
      // One opaque sample behind clear space takes all the weight; behind it the gradients vanish.
      CHECK(dev.acc[4] == 1.0f);
      CHECK(dev.weights[4 * n + 5] == 1.0f);
      for (size_t i = 6; i < n; ++i) CHECK(dev.d_density[4 * n + i] == 0.0f);
    }
    // Everything but ray 3 (σ = ∞ is outside the reference's domain) also matches the reference bounds.
    Batch finite = b;
    for (size_t i = 0; i < n; ++i) finite.density[3 * n + i] = 1e10f;
    check_against_reference(options, finite, true);
  }
}

TEST_CASE("render: sigma times delta overflowing to +inf, and far distances around t = 1e4, forward and backward") {
  // Rays 0..199: edges shifted to t ≈ 1e4 (float32 spacing 1e-3 there, so the smallest gaps are a few ulps) with
  // densities 1e-5..10: the far distances. Rays 200..: σ = FLT_MAX on intervals of t-width 2.5 (δ ≥ 1.25 for
  // |d| ≥ 0.5), so s = σ·δ overflows to +∞ in float32 while the reference's double s is finite (~1e38..1e39): α = 1,
  // everything behind has T = 0. Placed first, after clear space, behind an opaque σ = 1e10 sample, and twice in a
  // row. The reference and the bounds of float_bounds apply unchanged: exp(−s) is 0 in both, and the weights,
  // sums and gradients behind such a sample are exactly 0 in both.
  const size_t n = 24, far_rays = 200, overflow_rays = 4 * 50;
  Batch b = random_batch(far_rays + overflow_rays, n, 606, 1e-5, 10.0);
  for (size_t ray = 0; ray < far_rays; ++ray) {
    for (size_t k = 0; k <= n; ++k) b.t_edges[ray * (n + 1) + k] += 1e4f;
  }
  constexpr float kHuge = std::numeric_limits<float>::max();
  for (size_t ray = far_rays; ray < b.n_rays; ++ray) {
    const size_t kind = (ray - far_rays) % 4;
    for (size_t k = 0; k <= n; ++k) b.t_edges[ray * (n + 1) + k] = 2.0f + 2.5f * k;  // δ = 2.5·|d| ≥ 1.25
    const size_t at = ray * n;
    const size_t hit = kind == 0 ? 0 : 7;
    for (size_t i = 0; i < n; ++i) b.density[at + i] = i < hit ? 0.0f : 0.5f;
    b.density[at + hit] = kHuge;
    if (kind == 2) b.density[at + hit - 2] = 1e10f;  // an opaque sample in front of the overflow
    if (kind == 3) b.density[at + hit + 1] = kHuge;  // two overflowing samples in a row
  }
  for (auto background : kBackgrounds) {
    for (bool with_d_acc : {false, true}) {
      INFO("background " << static_cast<int>(background) << ", d_acc " << with_d_acc);
      const RenderOptions options{background};
      const auto dev = run_device(options, b, with_d_acc);
      const auto r = run_ref(options, b, with_d_acc);
      for (size_t ray = far_rays; ray < b.n_rays; ++ray) {  // the reference's s is finite but beyond float32
        const size_t hit = (ray - far_rays) % 4 == 0 ? 0 : 7;
        const double delta = (double(b.t_edges[ray * (n + 1) + hit + 1]) - b.t_edges[ray * (n + 1) + hit]) *
                             std::sqrt(double(b.directions[3 * ray]) * b.directions[3 * ray] +
                                       double(b.directions[3 * ray + 1]) * b.directions[3 * ray + 1] +
                                       double(b.directions[3 * ray + 2]) * b.directions[3 * ray + 2]);
        REQUIRE(delta > 1.0);
        REQUIRE(std::isinf(kHuge * static_cast<float>(delta)));
      }
      check_against_reference(options, b, with_d_acc);
      // The overflowing sample takes all the weight that reaches it; behind it nothing moves the colour.
      for (size_t ray = far_rays; ray < b.n_rays; ++ray) {
        const size_t kind = (ray - far_rays) % 4, hit = kind == 0 ? 0 : 7;
        if (kind != 2) CHECK(dev.weights[ray * n + hit] == doctest::Approx(r.weights[ray * n + hit]).epsilon(1e-6));
        for (size_t i = hit + 1; i < n; ++i) {
          CHECK(dev.weights[ray * n + i] == 0.0f);
          CHECK(dev.d_density[ray * n + i] == 0.0f);
        }
        CHECK(dev.d_density[ray * n + hit] == 0.0f);  // δ·(g·T_{i+1} − Σ_{k>i} g_k·w_k) with T_{i+1} = 0, w_k = 0
      }
    }
  }
  // The fused kernels on raw values (what training runs): raw densities of FLT_MAX overflow s the same way and give
  // exactly the composition activations → render, finite.
  auto& ctx = test::test_context();
  Batch raw = b;
  for (auto& x : raw.density) x = x == kHuge ? kHuge : (x == 0.0f ? -30.0f : x);
  for (auto& x : raw.rgb) x = 8 * x - 4;
  const size_t rows = raw.n_rays * n;
  for (auto background : kBackgrounds) {
    INFO("fused, background " << static_cast<int>(background));
    const RenderOptions options{background};
    const auto fused = run_device(options, raw, true, true);
    for (const auto* v :
         {&fused.comp_rgb, &fused.acc, &fused.distance, &fused.weights, &fused.d_rgb, &fused.d_density}) {
      CHECK(test::all_finite(*v));
    }
    auto raw_density = test::upload(ctx, raw.density, "raw_density"), raw_rgb = test::upload(ctx, raw.rgb, "raw_rgb");
    ocl::DeviceArray<float> density(ctx, rows, "density"), rgb(ctx, 3 * rows, "rgb");
    ops::Activations(ctx, {}).fwd({raw_density, raw_rgb, rows}, {density, rgb});
    Batch activated = raw;
    activated.density = density.download(ctx);
    activated.rgb = rgb.download(ctx);
    const auto composed = run_device(options, activated, true);
    CHECK(fused.comp_rgb == composed.comp_rgb);
    CHECK(fused.weights == composed.weights);
    CHECK(fused.distance == composed.distance);
  }
}

TEST_CASE("render: black and none composite the same, white adds 1 - acc") {
  const Batch b = random_batch(test::batch_for_device(2000), 24, 404);
  const auto none = run_device({Background::none}, b, false);
  const auto black = run_device({Background::black}, b, false);
  const auto white = run_device({Background::white}, b, false);
  CHECK(none.comp_rgb == black.comp_rgb);
  CHECK(none.weights == black.weights);
  CHECK(white.acc == black.acc);
  // white = black + (1 − acc), one rounding each for 1 − acc and the sum: ≤ 2 roundoffs of values ≤ 2.
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    for (int c = 0; c < 3; ++c) {
      const double expected = double(black.comp_rgb[3 * ray + c]) + (1.0 - double(black.acc[ray]));
      CHECK(std::abs(white.comp_rgb[3 * ray + c] - expected) <= 4 * kUnitRoundoff * 2.0);
    }
  }
}

TEST_CASE("render: the fused activation and render kernels equal activations then render") {
  auto& ctx = test::test_context();
  Batch raw = random_batch(test::batch_for_device(3000), 24, 505);
  std::mt19937 rng(5);
  std::normal_distribution<float> normal(0.0f, 4.0f);
  for (auto& x : raw.density) x = normal(rng);
  for (auto& x : raw.rgb) x = normal(rng);
  ActivationOptions nerf;
  nerf.density = DensityActivation::relu;
  nerf.density_bias = 0.0f;
  nerf.rgb_padding = 0.0f;
  for (const auto& activation : {ActivationOptions{}, nerf}) {
    for (auto background : kBackgrounds) {
      INFO("density activation " << static_cast<int>(activation.density) << ", background "
                                 << static_cast<int>(background));
      const RenderOptions options{background};
      const auto fused = run_device(options, raw, true, true, activation);
      // The composition on the device: activations_fwd, render_fwd, render_bwd, activations_bwd.
      const size_t rows = raw.n_rays * raw.n_samples;
      auto raw_density = test::upload(ctx, raw.density, "raw_density");
      auto raw_rgb = test::upload(ctx, raw.rgb, "raw_rgb");
      ocl::DeviceArray<float> density(ctx, rows, "density"), rgb(ctx, 3 * rows, "rgb");
      ops::Activations act(ctx, activation);
      act.fwd({raw_density, raw_rgb, rows}, {density, rgb});
      Batch activated = raw;
      activated.density = density.download(ctx);
      activated.rgb = rgb.download(ctx);
      const auto composed = run_device(options, activated, true);
      auto d_density = test::upload(ctx, composed.d_density, "d_density");
      auto d_rgb = test::upload(ctx, composed.d_rgb, "d_rgb");
      ocl::DeviceArray<float> d_raw_density(ctx, rows, "d_raw_density"), d_raw_rgb(ctx, 3 * rows, "d_raw_rgb");
      act.bwd({raw_density, raw_rgb, rows}, {d_density, d_rgb}, {d_raw_density, d_raw_rgb});
      // The same inline functions in the same order: bit-identical results.
      CHECK(fused.comp_rgb == composed.comp_rgb);
      CHECK(fused.acc == composed.acc);
      CHECK(fused.distance == composed.distance);
      CHECK(fused.weights == composed.weights);
      CHECK(fused.d_density == d_raw_density.download(ctx));
      CHECK(fused.d_rgb == d_raw_rgb.download(ctx));
    }
  }
}

// ---- Density noise (DENSITY_NOISE): N(0, 1) draws added to the raw densities by the fused kernels while training ----

namespace {

// rng_normal4 on the device for items 0..n_items − 1 at one counter slot: [n_items][4].
std::vector<float> device_normal4(ocl::Context& ctx, const RngKey& key, uint32_t slot, size_t n_items) {
  ocl::DeviceArray<float> out(ctx, 4 * n_items, "normals [n][4]");
  auto& kernel = ctx.program({"common.cl", "util.cl"}).kernel("rng_normal4_fill");
  ocl::set_args(kernel, "rng_normal4_fill", cl_ulong{key.seed}, cl_uint{key.step}, cl_uint{slot},
                cl_uint{rng_stream_density_noise}, out, static_cast<cl_uint>(n_items));
  ocl::launch_1d(ctx, kernel, n_items, "rng_normal4_fill");
  return out.download(ctx);
}

// The device's noise draws of a launch [R][N], picked from rng_normal4_fill as render.cl picks them: sample i of ray r
// takes draw i % 4 of the counter (first_ray + r, step, level·2^24 + i/4).
std::vector<float> device_noise_draws(ocl::Context& ctx, const DensityNoiseKey& noise, size_t n_rays, size_t n) {
  std::vector<float> z(n_rays * n);
  for (size_t group = 0; 4 * group < n; ++group) {
    const auto draws = device_normal4(ctx, noise.rng, (noise.level << 24) + static_cast<uint32_t>(group),
                                      noise.rng.first_ray + n_rays);
    for (size_t ray = 0; ray < n_rays; ++ray) {
      for (size_t k = 0; k < 4 && 4 * group + k < n; ++k) {
        z[ray * n + 4 * group + k] = draws[4 * (noise.rng.first_ray + ray) + k];
      }
    }
  }
  return z;
}

// Raw network outputs: N(0, 4²) densities and colours (both signs, saturated tails), as the fused test above.
Batch raw_batch(size_t n_rays, size_t n_samples, unsigned seed) {
  Batch raw = random_batch(n_rays, n_samples, seed);
  std::mt19937 rng(seed + 1);
  std::normal_distribution<float> normal(0.0f, 4.0f);
  for (auto& x : raw.density) x = normal(rng);
  for (auto& x : raw.rgb) x = normal(rng);
  return raw;
}

// Rays first.. of a batch, as a launch of their own.
Batch tail_of(const Batch& b, size_t first) {
  Batch t = b;
  const size_t n = b.n_samples;
  t.n_rays = b.n_rays - first;
  t.rgb.assign(b.rgb.begin() + 3 * first * n, b.rgb.end());
  t.density.assign(b.density.begin() + first * n, b.density.end());
  t.t_edges.assign(b.t_edges.begin() + first * (n + 1), b.t_edges.end());
  t.directions.assign(b.directions.begin() + 3 * first, b.directions.end());
  t.d_comp_rgb.assign(b.d_comp_rgb.begin() + 3 * first, b.d_comp_rgb.end());
  t.d_acc.assign(b.d_acc.begin() + first, b.d_acc.end());
  return t;
}

std::vector<float> tail_of(const std::vector<float>& v, size_t first_element) {
  return std::vector<float>(v.begin() + first_element, v.end());
}

}  // namespace

TEST_CASE("render: the weights-only kernel writes the fused kernel's acc, distance and weights, and no composite") {
  // render_raw_weights_fwd serves levels whose colour nothing reads (the coarse level when rendering): the same
  // values as render_raw_fwd, bit for bit (the same inline code without the colour sum), with and without density
  // noise, on every background; the composite it must not write keeps a sentinel.
  auto& ctx = test::test_context();
  const Batch raw = raw_batch(test::batch_for_device(2000), 24, 515);
  const size_t rows = raw.n_rays * raw.n_samples;
  auto raw_density = test::upload(ctx, raw.density, "raw_density");
  auto t_edges = test::upload(ctx, raw.t_edges, "t_edges");
  ops::RayBundle rays(ctx, raw.n_rays);
  rays.directions.upload(ctx, raw.directions);
  for (const float noise_scale : {0.0f, 1.0f}) {
    for (auto background : kBackgrounds) {
      INFO("background " << static_cast<int>(background) << ", density noise " << noise_scale);
      const RenderOptions options{background, noise_scale};
      const DensityNoiseKey key{{77, 3, 100}, 1};
      const auto fused = run_device(options, raw, true, true, {}, key);
      ocl::DeviceArray<float> acc(ctx, raw.n_rays, "acc"), distance(ctx, raw.n_rays, "distance");
      ocl::DeviceArray<float> weights(ctx, rows, "weights");
      ops::Render render(ctx, options);
      render.raw_weights_fwd({raw_density, t_edges, rays, raw.n_rays, raw.n_samples}, {acc, distance, weights}, key);
      CHECK(acc.download(ctx) == fused.acc);
      CHECK(distance.download(ctx) == fused.distance);
      CHECK(weights.download(ctx) == fused.weights);
      // The reference mirror agrees with the fused reference (colours never reach these three).
      std::vector<double> ref_acc, ref_distance, ref_weights, comp, full_acc, full_distance, full_weights;
      const auto density = test::to_double(raw.density), t = test::to_double(raw.t_edges);
      const auto dirs = test::to_double(raw.directions);
      ref::render_raw_weights_fwd(options, {}, density, t, dirs, ref_acc, ref_distance, ref_weights, raw.n_rays,
                                  raw.n_samples, key);
      ref::render_raw_fwd(options, {}, test::to_double(raw.rgb), density, t, dirs, comp, full_acc, full_distance,
                          full_weights, raw.n_rays, raw.n_samples, key);
      CHECK(ref_weights == full_weights);
      CHECK(ref_acc == full_acc);
      CHECK(ref_distance == full_distance);
    }
  }
  // Sizes that do not fit are refused before the launch, naming the kernel.
  ocl::DeviceArray<float> small(ctx, 1, "small"), distance(ctx, raw.n_rays, "distance"), weights(ctx, rows, "weights");
  ops::Render render(ctx, RenderOptions{});
  CHECK_THROWS_WITH(
      render.raw_weights_fwd({raw_density, t_edges, rays, raw.n_rays, raw.n_samples}, {small, distance, weights}),
      doctest::Contains("render_raw_weights_fwd"));
}

TEST_CASE("render: samples in lockstep give the per-ray values bit for bit, with a partial last work-group") {
  // The same arithmetic in the same order per ray, only the order of the rays' steps differs; 1,000 rays (100 under
  // oclgrind) leave the last work-group partial, whose padding items run the last ray again and must store nothing.
  // The programs really differ: each loop asked for is the one built (else the equality below would be vacuous).
  auto& ctx = test::test_context();
  for (const auto loop : kSampleLoops) CHECK(ops::Render(ctx, RenderOptions{}, {}, loop).sample_loop() == loop);
  const Batch plain = random_batch(test::batch_for_device(1000), 24, 525);
  const Batch raw = raw_batch(test::batch_for_device(1000), 24, 526);
  for (auto background : kBackgrounds) {
    INFO("background " << static_cast<int>(background));
    const RenderOptions options{background};
    check_bit_equal(run_device(options, plain, true, false, {}, {}, ops::RenderSampleLoop::per_ray),
                    run_device(options, plain, true, false, {}, {}, ops::RenderSampleLoop::lockstep));
    for (const float noise_scale : {0.0f, 1.0f}) {
      INFO("fused, density noise " << noise_scale);
      const RenderOptions noisy{background, noise_scale};
      const DensityNoiseKey key{{91, 5, 40}, 1};
      check_bit_equal(run_device(noisy, raw, true, true, {}, key, ops::RenderSampleLoop::per_ray),
                      run_device(noisy, raw, true, true, {}, key, ops::RenderSampleLoop::lockstep));
    }
  }
}

TEST_CASE(
    "render: samples by vectors of 16 - against the reference with 8 samples after the vectors, and the "
    "backward is the per-ray loop's bit for bit given the same weights") {
  // 40 samples: two vectors, then 8 samples by the scalar loop, which carries on the vectors' sums. The forward's sums
  // run in another order (render.cl), so it is held to the reference's bounds; the backward, given the forward's
  // weights, runs the per-ray loop's operations in its order: its gradients must match the per-ray backward's
  // exactly when that backward reads the same weights.
  const Batch b = random_batch(test::batch_for_device(2000), 40, 527);
  for (auto background : kBackgrounds) {
    INFO("background " << static_cast<int>(background));
    const RenderOptions options{background};
    const auto r = run_ref(options, b, true);
    const auto bounds = float_bounds(options, b, r, true);
    const auto dev = run_device(options, b, true, false, {}, {}, ops::RenderSampleLoop::per_vector);
    check_within_bounds(dev, r, bounds);
    const auto per_ray = run_backward_on(options, b, dev.weights, ops::RenderSampleLoop::per_ray);
    CHECK(per_ray.d_rgb == dev.d_rgb);
    CHECK(per_ray.d_density == dev.d_density);
  }
}

TEST_CASE("render: one sample's weight is alpha = -expm1(-sigma delta) within 3 ulp, every binade, both loops") {
  // With t = [0, 1] and |d| = 1, δ = 1 exactly and the single weight is −expm1_nonpositive(−σ)·exp_nonpositive(0)
  // = −expm1_nonpositive(−σ) (kernels/common.cl; within 3 ulp by its derivation): σ over every binade from 2^-40
  // (where α ≈ σ must keep its relative accuracy: 1 − exp(−σ) would lose it all) to 2^6, 64 mantissas per binade (6
  // under oclgrind), and σ = 0; against double expm1, at 3 ulp ≤ 6u·|α|.
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> mantissa(1.0f, 2.0f);
  Batch b = random_batch(1, 1, 31);
  std::vector<float> sigmas{0.0f};
  const size_t per_binade = test::batch_for_device(64, 6);
  for (int exponent = -40; exponent <= 6; ++exponent) {
    for (size_t k = 0; k < per_binade; ++k) sigmas.push_back(std::ldexp(mantissa(rng), exponent));
  }
  const Batch one_ray = b;
  b = Batch{};
  b.n_rays = sigmas.size();
  b.n_samples = 1;
  for (const float sigma : sigmas) {
    b.density.push_back(sigma);
    b.t_edges.insert(b.t_edges.end(), {0.0f, 1.0f});
    b.directions.insert(b.directions.end(), {1.0f, 0.0f, 0.0f});
    b.rgb.insert(b.rgb.end(), one_ray.rgb.begin(), one_ray.rgb.end());
    b.d_comp_rgb.insert(b.d_comp_rgb.end(), one_ray.d_comp_rgb.begin(), one_ray.d_comp_rgb.end());
    b.d_acc.push_back(one_ray.d_acc[0]);
  }
  std::vector<double> alpha(sigmas.size());
  for (size_t i = 0; i < sigmas.size(); ++i) alpha[i] = -std::expm1(-static_cast<double>(sigmas[i]));
  for (const auto loop : kSampleLoops) {
    INFO(loop_name(loop));
    const auto dev = run_device({Background::black}, b, false, false, {}, {}, loop);
    MIPNERF_CHECK_CLOSE("weight of one sample", dev.weights, alpha,
                        [&](size_t i) { return 6 * kUnitRoundoff * std::abs(alpha[i]); });
    CHECK(dev.acc == dev.weights);
  }
}

TEST_CASE("render: density-noise draws - the kernel's normals are the host mirror's within float32 and are N(0, 1)") {
  auto& ctx = test::test_context();
  const size_t n = 20000;
  const RngKey key{0x5eed5eedULL, 11, 0};
  const uint32_t slot = (1u << 24) + 3;  // level 1, samples 12..15
  const auto device = device_normal4(ctx, key, slot, n);
  // Bound per draw z = r·cos(2πu), r = sqrt(−2·log(1 − u0)), 1 − u0 exact: log ≤ 3 ulp (6u relative), so r is within
  // 3u, and sqrt adds ≤ 3 ulp (6u); cospi/sinpi of the exact 2u ≤ 4 ulp (8u); the product 1u: 18u·|z|. Twice that;
  // the host's double evaluation is exact to ~1e-16.
  std::vector<double> host(4 * n);
  for (size_t i = 0; i < n; ++i) {
    const auto z = rng_normal4(key.seed, static_cast<uint32_t>(i), key.step, slot, rng_stream_density_noise);
    for (int k = 0; k < 4; ++k) host[4 * i + k] = z[k];
  }
  MIPNERF_CHECK_CLOSE("normal draws", device, host,
                      [&](size_t i) { return 2 * 18 * kUnitRoundoff * std::abs(host[i]); });
  // The host's draws are N(0, 1) (an oracle independent of the transform): 80,000 draws, so the mean's standard
  // deviation is 0.0035 (bound 0.02, > 5σ) and the variance's sqrt(2/n) = 0.005 (bound 0.03, 6σ); each decile of
  // Φ(z) expects 8,000 with sd ≈ 85 (bound ±500, > 5σ); |z| ≤ sqrt(−2·log 2^-24) ≈ 5.77 by construction.
  double sum = 0, sum_sq = 0, max_abs = 0;
  int deciles[10] = {};
  for (double z : host) {
    sum += z;
    sum_sq += z * z;
    max_abs = std::max(max_abs, std::abs(z));
    ++deciles[std::min(9, static_cast<int>(10 * 0.5 * std::erfc(-z / std::sqrt(2.0))))];
  }
  const double mean = sum / host.size(), variance = sum_sq / host.size() - mean * mean;
  CHECK(std::abs(mean) < 0.02);
  CHECK(std::abs(variance - 1.0) < 0.03);
  for (int d = 0; d < 10; ++d) CHECK(std::abs(deciles[d] - 8000) < 500);
  CHECK(max_abs <= std::sqrt(-2.0 * std::log(1.0 / 16777216.0)) + 1e-12);
  CHECK(max_abs > 3.5);  // the tails are there (P(|z| > 3.5) = 4.7e-4: ~37 expected)
}

TEST_CASE("render: density noise - the fused kernels add the kernel's own draws, the backward draws them again") {
  // With DENSITY_NOISE = σ (a power of two, so σ·z is exact and raw + σ·z one rounding, fused or not), the fused
  // kernels must equal the noiseless fused kernels run on raw + σ·z with the device's draws (rng_normal4_fill), bit for
  // bit: forward (which draws) and backward (which draws again, and must differentiate at the same noisy value).
  auto& ctx = test::test_context();
  // 23 samples: a last group of three draws (a tenth of the rays under the oclgrind simulator)
  const Batch raw = raw_batch(test::batch_for_device(1500), 23, 707);
  for (const float sigma : {1.0f, 0.5f}) {
    for (const uint32_t level : {0u, 1u}) {
      INFO("sigma " << sigma << ", level " << level);
      const DensityNoiseKey key{{20200823, 11, 0}, level};
      const auto noisy = run_device({Background::black, sigma}, raw, true, true, {}, key);
      const auto z = device_noise_draws(ctx, key, raw.n_rays, raw.n_samples);
      Batch shifted = raw;
      for (size_t k = 0; k < shifted.density.size(); ++k) shifted.density[k] = raw.density[k] + sigma * z[k];
      check_bit_equal(noisy, run_device({Background::black}, shifted, true, true));
      // And the noise is there: the same key without it gives other weights.
      CHECK(run_device({Background::black}, raw, true, true, {}, key).weights != noisy.weights);
    }
  }
  // Keyed by (seed, step, ray in the batch, level, sample): another level, step or seed draws other numbers; a launch
  // of the later rays with first_ray = their index (a chunk) gives exactly those rays' results of the whole launch.
  const RenderOptions noisy_options{Background::black, 1.0f};
  const auto whole = run_device(noisy_options, raw, true, true, {}, {{7, 3, 0}, 0});
  CHECK(run_device(noisy_options, raw, true, true, {}, {{7, 3, 0}, 1}).weights != whole.weights);
  CHECK(run_device(noisy_options, raw, true, true, {}, {{7, 4, 0}, 0}).weights != whole.weights);
  CHECK(run_device(noisy_options, raw, true, true, {}, {{8, 3, 0}, 0}).weights != whole.weights);
  const uint32_t first = static_cast<uint32_t>(raw.n_rays * 7 / 15);  // 700 of 1,500
  const size_t n = raw.n_samples;
  const auto chunk = run_device(noisy_options, tail_of(raw, first), true, true, {}, {{7, 3, first}, 0});
  CHECK(chunk.weights == tail_of(whole.weights, first * n));
  CHECK(chunk.comp_rgb == tail_of(whole.comp_rgb, 3 * first));
  CHECK(chunk.d_density == tail_of(whole.d_density, first * n));
  CHECK(chunk.d_rgb == tail_of(whole.d_rgb, 3 * first * n));
  // The plain kernels (activated inputs) never add noise, whatever the option.
  const Batch activated = random_batch(500, 16, 708);
  const auto plain_noisy = run_device(noisy_options, activated, true);
  const auto plain = run_device({Background::black}, activated, true);
  CHECK(plain_noisy.weights == plain.weights);
  CHECK(plain_noisy.d_density == plain.d_density);
}

TEST_CASE("render: density noise - the reference backward is the derivative of its noisy forward, draws held fixed") {
  // The reference's fused forward with noise σ = 1 (draws keyed, so a perturbed input keeps them), differenced
  // centrally in each raw density and colour: L = Σ_c d_comp_c·comp_c + d_acc·acc of each ray. Step
  // h = 1e-6·max(|x|, 1) on raw values of size ≤ ~15: truncation h²/6·|L'''| (softplus and sigmoid have bounded
  // derivatives; the weights as in the plain test) and rounding 1e-16/h, both below 1e-9; the reference backward
  // within 1e-8 + 1e-7 relative.
  const Batch b = raw_batch(200, 16, 909);
  const size_t n = b.n_samples;
  const RenderOptions options{Background::black, 1.0f};
  const ActivationOptions activation;
  const DensityNoiseKey key{{99, 5, 0}, 1};
  const auto rgb = test::to_double(b.rgb), density = test::to_double(b.density);
  const auto t_edges = test::to_double(b.t_edges), directions = test::to_double(b.directions);
  const auto d_comp = test::to_double(b.d_comp_rgb), d_acc = test::to_double(b.d_acc);
  std::vector<double> comp, acc, distance, weights, d_rgb, d_density;
  ref::render_raw_fwd(options, activation, rgb, density, t_edges, directions, comp, acc, distance, weights, b.n_rays, n,
                      key);
  ref::render_raw_bwd(options, activation, rgb, density, t_edges, directions, weights, d_comp, &d_acc, d_rgb, d_density,
                      b.n_rays, n, key);
  std::vector<double> fd_rgb(3 * b.n_rays * n), fd_density(b.n_rays * n);
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    std::vector<double> ray_rgb(rgb.begin() + 3 * ray * n, rgb.begin() + 3 * (ray + 1) * n);
    std::vector<double> ray_density(density.begin() + ray * n, density.begin() + (ray + 1) * n);
    const std::vector<double> ray_t(t_edges.begin() + ray * (n + 1), t_edges.begin() + (ray + 1) * (n + 1));
    const std::vector<double> ray_dir(directions.begin() + 3 * ray, directions.begin() + 3 * ray + 3);
    DensityNoiseKey ray_key = key;
    ray_key.rng.first_ray = static_cast<uint32_t>(ray);  // this ray's draws, as in the whole batch
    const auto loss = [&] {
      std::vector<double> c, a, dist, w;
      ref::render_raw_fwd(options, activation, ray_rgb, ray_density, ray_t, ray_dir, c, a, dist, w, 1, n, ray_key);
      return d_acc[ray] * a[0] + d_comp[3 * ray] * c[0] + d_comp[3 * ray + 1] * c[1] + d_comp[3 * ray + 2] * c[2];
    };
    for (size_t i = 0; i < n; ++i) {
      fd_density[ray * n + i] = central_difference(ray_density[i], loss);
      for (int c = 0; c < 3; ++c) fd_rgb[3 * (ray * n + i) + c] = central_difference(ray_rgb[3 * i + c], loss);
    }
  }
  const auto fd_tol = [](const std::vector<double>& fd) {
    return std::function<double(size_t)>([&fd](size_t i) { return 1e-8 + 1e-7 * std::abs(fd[i]); });
  };
  CHECK(count_outside(d_density, fd_density, fd_tol(fd_density)) == 0);
  CHECK(count_outside(d_rgb, fd_rgb, fd_tol(fd_rgb)) == 0);
  // The noise matters: the noiseless derivative is another one for most samples.
  std::vector<double> d_rgb_plain, d_density_plain;
  ref::render_raw_bwd({Background::black}, activation, rgb, density, t_edges, directions, weights, d_comp, &d_acc,
                      d_rgb_plain, d_density_plain, b.n_rays, n);
  CHECK(count_outside(d_density_plain, fd_density, fd_tol(fd_density)) > b.n_rays * n / 4);

  // The device's fused kernels with the same key, as the specialisation test holds every specialisation (its draws
  // within 36u·|z| of the reference's, then float32 rendering): 1e-4 of the array's largest magnitude. A backward that
  // missed the noise, or drew other numbers, is off by O(1) of the large gradients (above: most samples move).
  const auto dev = run_device(options, b, true, true, activation, key);
  const auto scaled = [](const std::vector<double>& reference) {
    double scale = 1e-30;
    for (double v : reference) scale = std::max(scale, std::abs(v));
    return std::function<double(size_t)>([scale](size_t) { return 1e-4 * scale; });
  };
  MIPNERF_CHECK_CLOSE("device d_raw_density with noise vs finite differences", dev.d_density, fd_density,
                      scaled(fd_density));
  MIPNERF_CHECK_CLOSE("device d_raw_rgb with noise vs finite differences", dev.d_rgb, fd_rgb, scaled(fd_rgb));
  MIPNERF_CHECK_CLOSE("device weights with noise vs the reference", dev.weights, weights, scaled(weights));
  MIPNERF_CHECK_CLOSE("device comp_rgb with noise vs the reference", dev.comp_rgb, comp, scaled(comp));
}

// ---- The weights' backward (render_raw_weights_bwd): ∂L/∂raw_density from ∂L/∂w, what a proposal level trains by ----

namespace {

// The three density activations the render program can be built with, as the stage list's (mip-NeRF softplus with
// bias −1, NeRF relu with bias 0) and the two with the other bias, so the bias is not only ever the default's.
std::vector<std::pair<const char*, ActivationOptions>> weights_bwd_activations() {
  ActivationOptions softplus_no_bias;
  softplus_no_bias.density_bias = 0.0f;
  ActivationOptions relu;
  relu.density = DensityActivation::relu;
  relu.density_bias = 0.0f;
  ActivationOptions relu_biased = relu;
  relu_biased.density_bias = -1.0f;
  return {{"softplus, bias -1", ActivationOptions{}},
          {"softplus, bias 0", softplus_no_bias},
          {"relu, bias 0", relu},
          {"relu, bias -1", relu_biased}};
}

// Random ∂L/∂w in [−1, 1] (the interlevel loss's gradient has either sign), [R][N].
std::vector<float> random_d_weights(size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> signed_unit(-1.0f, 1.0f);
  std::vector<float> d(count);
  for (auto& x : d) x = signed_unit(rng);
  return d;
}

struct WeightsRun {
  std::vector<float> weights, d_raw_density;
};

// render_raw_weights_fwd then render_raw_weights_bwd on the raw densities of `raw` with d_weights [R][N]; the
// backward reads `given_weights` instead of the forward's when not null.
WeightsRun run_weights_device(const RenderOptions& options, const ActivationOptions& activation, const Batch& raw,
                              const std::vector<float>& d_weights, const DensityNoiseKey& noise = {},
                              ops::RenderSampleLoop loop = ops::RenderSampleLoop::device_default,
                              const std::vector<float>* given_weights = nullptr) {
  auto& ctx = test::test_context();
  const size_t rows = raw.n_rays * raw.n_samples;
  auto raw_density = test::upload(ctx, raw.density, "raw_density"), t_edges = test::upload(ctx, raw.t_edges, "t");
  auto d_w = test::upload(ctx, d_weights, "d_weights");
  ops::RayBundle rays(ctx, raw.n_rays);  // only the directions are read
  rays.directions.upload(ctx, raw.directions);
  ocl::DeviceArray<float> acc(ctx, raw.n_rays, "acc"), distance(ctx, raw.n_rays, "distance");
  ocl::DeviceArray<float> weights(ctx, rows, "weights"), d_raw_density(ctx, rows, "d_raw_density");
  ops::Render render(ctx, options, activation, loop);
  const ops::RenderDensityInputs in{raw_density, t_edges, rays, raw.n_rays, raw.n_samples};
  render.raw_weights_fwd(in, {acc, distance, weights}, noise);
  if (given_weights) {
    auto given = test::upload(ctx, *given_weights, "given weights");
    render.raw_weights_bwd(in, given, d_w, d_raw_density, noise);
  } else {
    render.raw_weights_bwd(in, weights, d_w, d_raw_density, noise);
  }
  return {weights.download(ctx), d_raw_density.download(ctx)};
}

// The reference's weights and d_raw_density for the same inputs (its own double weights).
struct WeightsRef {
  std::vector<double> weights, d_raw_density;
};

WeightsRef run_weights_ref(const RenderOptions& options, const ActivationOptions& activation, const Batch& raw,
                           const std::vector<float>& d_weights, const DensityNoiseKey& noise = {}) {
  WeightsRef r;
  std::vector<double> acc, distance;
  const auto density = test::to_double(raw.density), t = test::to_double(raw.t_edges);
  const auto dirs = test::to_double(raw.directions);
  ref::render_raw_weights_fwd(options, activation, density, t, dirs, acc, distance, r.weights, raw.n_rays,
                              raw.n_samples, noise);
  ref::render_raw_weights_bwd(options, activation, density, t, dirs, r.weights, test::to_double(d_weights),
                              r.d_raw_density, raw.n_rays, raw.n_samples, noise);
  return r;
}

// Float32 bounds of the device's weights and d_raw_density against the reference (no density noise), per element:
// float_bounds' derivation with the density activation in front and g = d_weights exact (floats, read as they are).
//  - x = raw + bias is rounded once (|Δx| ≤ u·|x|); the activation adds ≤ 16u of σ (test_activations.cpp's bound):
//    |Δσ| ≤ 16u·σ + u·|x|·act'(x), act' = sigmoid (softplus) or 0/1 (relu, whose σ = 0 side is exact).
//  - s = σ·δ: relative error rel_s = 16u (δ and the product, as float_bounds) + |Δσ|/σ.
//  - S_i = Σ_{j<i} s_j in order: absolute error Σ_{j<i} (rel_s_j + N·u)·s_j; w_i = α_i·T_i relative
//    e_w,i = 30u + rel_s_i + that (α's condition number s·e^−s/α ≤ 1, exp and expm1 within 3 ulp, a product).
//  - the reverse sweep as float_bounds' with g exact: T_{i+1} = T_N + A_i, A_i = Σ_{k>i} w_k, B_i = Σ_{k>i} g_k·w_k,
//    ∂L/∂σ_i = δ_i·(g_i·T_{i+1} − B_i) with 16u of δ and the product.
//  - ∂L/∂raw_i = ∂L/∂σ_i·act'(x_i): act' within 16u of itself plus its slope under |Δx|, u·|x|·sigmoid'(x) (relu's is
//    exact), and one rounding.
// Every tolerance is twice the bound, plus a few float denormal ulps.
struct WeightsBounds {
  std::vector<double> weights, d_raw_density;
};

WeightsBounds weights_bwd_bounds(const ActivationOptions& activation, const Batch& raw,
                                 const std::vector<float>& d_weights, const WeightsRef& r) {
  const size_t n = raw.n_samples;
  const double u = kUnitRoundoff, tiny = 1e-43;
  const bool relu = activation.density == DensityActivation::relu;
  WeightsBounds out;
  out.weights.resize(raw.n_rays * n);
  out.d_raw_density.resize(raw.n_rays * n);
  std::vector<double> x(n), sigma(n), delta(n), s(n), rel_s(n), e_w(n);
  for (size_t ray = 0; ray < raw.n_rays; ++ray) {
    const float* dir = raw.directions.data() + 3 * ray;
    const double dir_norm = std::sqrt(double(dir[0]) * dir[0] + double(dir[1]) * dir[1] + double(dir[2]) * dir[2]);
    const float* t = raw.t_edges.data() + ray * (n + 1);
    double depth = 0.0, depth_err = 0.0;  // S_i and its bound
    for (size_t i = 0; i < n; ++i) {
      const size_t at = ray * n + i;
      x[i] = double(raw.density[at]) + activation.density_bias;
      sigma[i] = ref::density_activation(activation, raw.density[at]);
      const double slope = ref::density_activation_grad(activation, raw.density[at]);
      const double sigma_err = 16 * u * sigma[i] + u * std::abs(x[i]) * slope;
      delta[i] = (double(t[i + 1]) - t[i]) * dir_norm;
      s[i] = delta[i] > 0 ? sigma[i] * delta[i] : 0.0;
      rel_s[i] = 16 * u + (sigma[i] > 0 ? sigma_err / sigma[i] : 0.0);
      e_w[i] = 30 * u + rel_s[i] + depth_err;
      out.weights[at] = 2 * e_w[i] * r.weights[at] + tiny;
      depth += s[i];
      depth_err += (rel_s[i] + n * u) * s[i];
    }
    const double trans_last = std::exp(-depth);
    const double trans_last_err = (depth_err + 6 * u) * trans_last;
    double a = 0.0, a_err = 0.0, bsum = 0.0, b_err = 0.0;
    for (size_t rr = 0; rr < n; ++rr) {
      const size_t i = n - 1 - rr, at = ray * n + i;
      const double g = d_weights[at];
      const double trans_next = trans_last + a;
      const double trans_next_err = trans_last_err + a_err + n * u * a + u * trans_next;
      const double d_s = g * trans_next - bsum;
      const double d_s_err = std::abs(g) * trans_next_err + b_err + n * u * std::abs(bsum) +
                             u * (std::abs(g) * trans_next + std::abs(bsum));
      const double d_sigma = delta[i] > 0 ? delta[i] * d_s : 0.0;
      const double d_sigma_err = delta[i] > 0 ? delta[i] * d_s_err + 16 * u * std::abs(d_sigma) : 0.0;
      const double act_grad = ref::density_activation_grad(activation, raw.density[at]);
      const double act_grad_err = relu ? 0.0 : 16 * u * act_grad + u * std::abs(x[i]) * act_grad * (1 - act_grad);
      out.d_raw_density[at] =
          2 * (d_sigma_err * act_grad + std::abs(d_sigma) * act_grad_err + u * std::abs(d_sigma) * act_grad) + tiny;
      const double w = r.weights[at];
      a += w;
      a_err += e_w[i] * w;
      bsum += g * w;
      b_err += std::abs(g) * e_w[i] * w;
    }
  }
  return out;
}

// The device (each way of walking the samples) against the reference within weights_bwd_bounds; the backward also run
// on one set of weights (the per-ray forward's) for every walk, which must then agree bit for bit (render.cl: the
// backward keeps the per-ray loop's order in every walk).
void check_weights_bwd_against_reference(const RenderOptions& options, const ActivationOptions& activation,
                                         const Batch& raw, const std::vector<float>& d_weights) {
  const auto r = run_weights_ref(options, activation, raw, d_weights);
  const auto bounds = weights_bwd_bounds(activation, raw, d_weights, r);
  const auto per_ray = run_weights_device(options, activation, raw, d_weights, {}, ops::RenderSampleLoop::per_ray);
  for (const auto loop : kSampleLoops) {
    INFO(loop_name(loop));
    const auto dev = run_weights_device(options, activation, raw, d_weights, {}, loop);
    MIPNERF_CHECK_CLOSE("weights", dev.weights, r.weights, from(bounds.weights));
    MIPNERF_CHECK_CLOSE("d_raw_density", dev.d_raw_density, r.d_raw_density, from(bounds.d_raw_density));
    CHECK(test::all_finite(dev.d_raw_density));
    const auto on_same_weights = run_weights_device(options, activation, raw, d_weights, {}, loop, &per_ray.weights);
    CHECK(on_same_weights.d_raw_density == per_ray.d_raw_density);
  }
}

// L = Σ_i g_i·w_i(raw) over every ray through the reference forward, and its central differences in each raw density
// (draws held fixed by the key). Step h = 1e-6·max(|x|, 1): truncation h²/6·|L'''| and rounding 1e-16/h, both below
// 1e-9 for raw values of size ≤ ~20 (the activations' derivatives are bounded, the weights as in the plain test).
// Relu's kink at x = 0 is not differentiable: samples with |raw + bias| < 10h get NaN (skipped by the caller).
std::vector<double> weights_loss_differences(const RenderOptions& options, const ActivationOptions& activation,
                                             const Batch& raw, const std::vector<float>& d_weights,
                                             const DensityNoiseKey& noise) {
  const size_t n = raw.n_samples;
  std::vector<double> fd(raw.n_rays * n);
  for (size_t ray = 0; ray < raw.n_rays; ++ray) {
    std::vector<double> density(raw.density.begin() + ray * n, raw.density.begin() + (ray + 1) * n);
    const std::vector<double> t(raw.t_edges.begin() + ray * (n + 1), raw.t_edges.begin() + (ray + 1) * (n + 1));
    const std::vector<double> dir(raw.directions.begin() + 3 * ray, raw.directions.begin() + 3 * ray + 3);
    DensityNoiseKey ray_key = noise;
    ray_key.rng.first_ray = noise.rng.first_ray + static_cast<uint32_t>(ray);  // this ray's draws, as in the batch
    const auto loss = [&] {
      std::vector<double> acc, distance, w;
      ref::render_raw_weights_fwd(options, activation, density, t, dir, acc, distance, w, 1, n, ray_key);
      double sum = 0.0;
      for (size_t i = 0; i < n; ++i) sum += double(d_weights[ray * n + i]) * w[i];
      return sum;
    };
    for (size_t i = 0; i < n; ++i) {
      const bool at_kink = activation.density == DensityActivation::relu &&
                           std::abs(density[i] + activation.density_bias) < 10 * central_step(density[i]);
      fd[ray * n + i] = at_kink ? std::nan("") : central_difference(density[i], loss);
    }
  }
  return fd;
}

}  // namespace

TEST_CASE(
    "render: weights backward - the kernel matches the CPU reference within float32 bounds, every activation "
    "and bias, every sample walk") {
  // 40 samples: two vectors of 16 and 8 by the scalar loop in the per-vector walk. N(0, 4²) raw densities (opaque and
  // clear samples, both sides of relu's kink), 5 % empty intervals (random_batch). No background enters the weights:
  // every background's program must give the same gradients.
  const Batch raw = raw_batch(test::batch_for_device(2000), 40, 811);
  const auto d_weights = random_d_weights(raw.n_rays * raw.n_samples, 812);
  for (const auto& variant : weights_bwd_activations()) {
    const ActivationOptions& activation = variant.second;
    INFO(variant.first);
    check_weights_bwd_against_reference({Background::white}, activation, raw, d_weights);
    const auto white = run_weights_device({Background::white}, activation, raw, d_weights);
    for (const auto background : {Background::none, Background::black}) {
      CHECK(run_weights_device({background}, activation, raw, d_weights).d_raw_density == white.d_raw_density);
    }
  }
}

TEST_CASE("render: weights backward - the reference and the kernel match central finite differences of the forward") {
  const Batch raw = raw_batch(200, 16, 821);
  const auto d_weights = random_d_weights(raw.n_rays * raw.n_samples, 822);
  for (const auto& variant : weights_bwd_activations()) {
    const ActivationOptions& activation = variant.second;
    INFO(variant.first);
    const RenderOptions options{Background::black};
    const auto fd = weights_loss_differences(options, activation, raw, d_weights, {});
    const auto r = run_weights_ref(options, activation, raw, d_weights);
    const auto bounds = weights_bwd_bounds(activation, raw, d_weights, r);
    const auto dev = run_weights_device(options, activation, raw, d_weights);
    // The reference within 1e-8 + 1e-7 relative (the differences' error is below 1e-9, see weights_loss_differences);
    // the device within its float32 bound plus that. Samples at relu's kink (NaN differences) are skipped; there
    // are few (|raw| < 1e-5 of N(0, 4²)), and the count checks the skip does not hide the test.
    size_t compared = 0, outside_ref = 0, outside_dev = 0;
    for (size_t k = 0; k < fd.size(); ++k) {
      if (std::isnan(fd[k])) continue;
      ++compared;
      const double tol = 1e-8 + 1e-7 * std::abs(fd[k]);
      if (!(std::abs(r.d_raw_density[k] - fd[k]) <= tol)) ++outside_ref;
      if (!(std::abs(dev.d_raw_density[k] - fd[k]) <= tol + bounds.d_raw_density[k])) ++outside_dev;
    }
    CHECK(compared >= fd.size() - 2);
    CHECK(outside_ref == 0);
    CHECK(outside_dev == 0);
    // The gradients are not trivially small: most samples have one of size > 1e-3 (else the comparison says little).
    CHECK(std::count_if(fd.begin(), fd.end(), [](double v) { return std::abs(v) > 1e-3; }) > fd.size() / 4);
  }
}

TEST_CASE(
    "render: weights backward - hard cases: opaque samples, overflowing sigma delta, sigma near 0, empty "
    "intervals, far and wide intervals") {
  const size_t n = 20, kinds = 8;
  const size_t n_rays = kinds * 8;
  Batch raw = raw_batch(n_rays, n, 831);
  const auto d_weights = random_d_weights(n_rays * n, 832);
  constexpr float kHuge = std::numeric_limits<float>::max();
  // By kind (ray % 8), in raw values (softplus with bias −1, or the relu of the same raw values):
  //  0: raw = 1e10 everywhere: the first non-empty interval takes all the weight (one-hot).
  //  1: clear space (raw −30: σ ≈ 1e-13 under softplus, 0 under relu), then raw 1e10 at sample 7.
  //  2: raw = FLT_MAX at sample 7 (σ·δ overflows to +∞ for δ > 1: edges 2.5 apart), 0.5 elsewhere.
  //  3: raw −30 everywhere: σ → 0, T ≈ 1.
  //  4: every interval empty (t constant), raw N(0, 4²): no weight, zero gradients whatever σ.
  //  5: every interval empty with raw = FLT_MAX: σ·0 must not become NaN.
  //  6: far: t from 1e4 with gaps of 1e4 (δ = 1e4·|d|), raw −12 (σ ≈ 2.3e-6 under softplus): s ≈ 0.01..0.05 a
  //     sample, the ray's weights spread along it.
  //  7: far and wide with N(0, 4²) raw: s in the thousands, opaque at once.
  for (size_t ray = 0; ray < n_rays; ++ray) {
    float* density = raw.density.data() + ray * n;
    float* t = raw.t_edges.data() + ray * (n + 1);
    const size_t kind = ray % kinds;
    for (size_t i = 0; i < n; ++i) {
      if (kind == 0) density[i] = 1e10f;
      if (kind == 1) density[i] = i == 7 ? 1e10f : -30.0f;
      if (kind == 2) density[i] = i == 7 ? kHuge : 0.5f;
      if (kind == 3) density[i] = -30.0f;
      if (kind == 5) density[i] = kHuge;
      if (kind == 6) density[i] = -12.0f;
    }
    for (size_t k = 0; k <= n; ++k) {
      if (kind == 1 || kind == 2) t[k] = 2.0f + 2.5f * k;  // no empty interval; δ = 2.5·|d| ≥ 1.25
      if (kind == 4 || kind == 5) t[k] = 4.0f;
      if (kind == 6 || kind == 7) t[k] = 1e4f * (1 + k);
    }
  }
  const auto at = [&](size_t ray, size_t i) { return ray * n + i; };
  for (const auto& variant : weights_bwd_activations()) {
    const ActivationOptions& activation = variant.second;
    INFO(variant.first);
    const bool relu = activation.density == DensityActivation::relu;
    const RenderOptions options{Background::black};
    check_weights_bwd_against_reference(options, activation, raw, d_weights);
    for (const auto loop : kSampleLoops) {
      INFO(loop_name(loop));
      const auto dev = run_weights_device(options, activation, raw, d_weights, {}, loop);
      CHECK(test::all_finite(dev.weights));
      CHECK(test::all_finite(dev.d_raw_density));
      for (size_t ray = 0; ray < n_rays; ++ray) {
        const size_t kind = ray % kinds;
        const float* t = raw.t_edges.data() + ray * (n + 1);
        // The opaque sample: all the weight that reaches it; at it and behind it nothing moves any weight
        // (∂w_k/∂σ_k = δ·e^{−s}·T_k = 0 and T = 0 behind), so the gradients are exactly 0.
        if (kind == 0 || kind == 1 || kind == 2) {
          size_t hit = kind == 0 ? 0 : 7;
          while (kind == 0 && t[hit + 1] == t[hit]) ++hit;
          if (kind == 0) CHECK(dev.weights[at(ray, hit)] == 1.0f);
          if (kind == 1 && relu) CHECK(dev.weights[at(ray, hit)] == 1.0f);  // relu's clear space has σ = 0
          for (size_t i = hit; i < n; ++i) CHECK(dev.d_raw_density[at(ray, i)] == 0.0f);
          for (size_t i = hit + 1; i < n; ++i) CHECK(dev.weights[at(ray, i)] == 0.0f);
        }
        // Empty intervals: no weight and no gradient, whatever σ (even raw FLT_MAX).
        if (kind == 4 || kind == 5) {
          for (size_t i = 0; i < n; ++i) {
            CHECK(dev.weights[at(ray, i)] == 0.0f);
            CHECK(dev.d_raw_density[at(ray, i)] == 0.0f);
          }
        }
      }
    }
  }
  // σ → 0 (kind 3, softplus: σ = softplus(−31) ≈ 3.4e-14): T ≈ 1 and w ≈ 0, so ∂L/∂raw_k → δ_k·g_k·sigmoid(x_k).
  // The terms dropped, g_k·(T_{k+1} − 1) and −Σ_{i>k} g_i·w_i, are at most |g|·S_N and Σ w_i ≤ S_N (|g| ≤ 1, S_N the
  // ray's optical depth, ~1e-12): the reference must match the closed form within δ_k·sigmoid(x_k)·2·S_N, plus
  // 1e-14 relative for its double rounding (the device is held to the reference above).
  const ActivationOptions softplus;
  const auto r = run_weights_ref({Background::black}, softplus, raw, d_weights);
  const double sigma = ref::density_activation(softplus, -30.0), slope = ref::density_activation_grad(softplus, -30.0);
  for (size_t ray = 3; ray < n_rays; ray += kinds) {
    const float* dir = raw.directions.data() + 3 * ray;
    const double dir_norm = std::sqrt(double(dir[0]) * dir[0] + double(dir[1]) * dir[1] + double(dir[2]) * dir[2]);
    const auto delta = [&](size_t i) {
      return (double(raw.t_edges[ray * (n + 1) + i + 1]) - raw.t_edges[ray * (n + 1) + i]) * dir_norm;
    };
    double depth = 0.0;  // S_N
    for (size_t i = 0; i < n; ++i) depth += sigma * delta(i);
    REQUIRE(depth < 1e-11);
    for (size_t i = 0; i < n; ++i) {
      const double expected = delta(i) * d_weights[at(ray, i)] * slope;
      CHECK(std::abs(r.d_raw_density[at(ray, i)] - expected) <=
            delta(i) * slope * 2 * depth + 1e-14 * std::abs(expected));
    }
  }
}

TEST_CASE("render: weights backward - with d_weights = d_acc it is render_raw_bwd's density gradient, bit for bit") {
  // ∂acc/∂w_i = 1: render_raw_bwd with d_comp_rgb = 0 and d_acc = a (black background) has g_i = 0·c + a = a exactly,
  // so its d_raw_density must equal render_raw_weights_bwd's with d_weights = a on every sample of the ray: the same
  // sweep (render_ray_bwd) fed from either side. An independent check that the weights-only path reads g where the
  // composite's path computes it, in every walk.
  const Batch raw = raw_batch(test::batch_for_device(1000), 40, 841);
  Batch acc_only = raw;
  std::fill(acc_only.d_comp_rgb.begin(), acc_only.d_comp_rgb.end(), 0.0f);
  std::vector<float> d_weights(raw.n_rays * raw.n_samples);
  for (size_t k = 0; k < d_weights.size(); ++k) d_weights[k] = raw.d_acc[k / raw.n_samples];
  for (const auto loop : kSampleLoops) {
    INFO(loop_name(loop));
    const RenderOptions options{Background::black};
    const auto full = run_device(options, acc_only, true, true, {}, {}, loop);
    const auto weights_only = run_weights_device(options, {}, raw, d_weights, {}, loop, &full.weights);
    CHECK(weights_only.d_raw_density == full.d_density);
  }
}

TEST_CASE("render: weights backward - density noise: the forward's draws again, keyed by ray, step and level") {
  // As the fused kernels' noise test: with DENSITY_NOISE = σ a power of two, the noisy kernels equal the noiseless
  // ones on raw + σ·z (the device's draws), bit for bit, forward and backward; a chunk of rays keyed by its first ray
  // gives the whole launch's values; another key gives other gradients.
  auto& ctx = test::test_context();
  const Batch raw = raw_batch(test::batch_for_device(1500), 23, 851);  // 23: a last group of three draws
  const auto d_weights = random_d_weights(raw.n_rays * raw.n_samples, 852);
  for (const float sigma : {1.0f, 0.5f}) {
    INFO("sigma " << sigma);
    const DensityNoiseKey key{{20200823, 11, 0}, 1};
    const auto noisy = run_weights_device({Background::black, sigma}, {}, raw, d_weights, key);
    const auto z = device_noise_draws(ctx, key, raw.n_rays, raw.n_samples);
    Batch shifted = raw;
    for (size_t k = 0; k < shifted.density.size(); ++k) shifted.density[k] = raw.density[k] + sigma * z[k];
    const auto plain = run_weights_device({Background::black}, {}, shifted, d_weights);
    CHECK(noisy.weights == plain.weights);
    CHECK(noisy.d_raw_density == plain.d_raw_density);
    const auto other_level =
        run_weights_device({Background::black, sigma}, {}, raw, d_weights, {{20200823, 11, 0}, 0}, {}, &noisy.weights);
    CHECK(other_level.d_raw_density != noisy.d_raw_density);
  }
  const RenderOptions noisy_options{Background::black, 1.0f};
  const auto whole = run_weights_device(noisy_options, {}, raw, d_weights, {{7, 3, 0}, 0});
  const uint32_t first = static_cast<uint32_t>(raw.n_rays / 2);
  const size_t n = raw.n_samples;
  const auto chunk =
      run_weights_device(noisy_options, {}, tail_of(raw, first), tail_of(d_weights, first * n), {{7, 3, first}, 0});
  CHECK(chunk.weights == tail_of(whole.weights, first * n));
  CHECK(chunk.d_raw_density == tail_of(whole.d_raw_density, first * n));
}

TEST_CASE("render: weights backward - with density noise the reference is the derivative of its noisy forward") {
  // The reference's finite differences with the noise's draws held fixed by the key (step and tolerance as
  // weights_loss_differences says); the device with the same key within 1e-4 of the largest gradient, as the fused
  // kernels' noise test (its draws within 36u·|z| of the reference's, then float32 rendering). Without the noise the
  // derivative is another one for most samples, so a backward that missed it fails.
  const Batch raw = raw_batch(100, 16, 861);
  const auto d_weights = random_d_weights(raw.n_rays * raw.n_samples, 862);
  const RenderOptions options{Background::black, 1.0f};
  const DensityNoiseKey key{{99, 5, 0}, 1};
  const auto fd = weights_loss_differences(options, {}, raw, d_weights, key);
  const auto r = run_weights_ref(options, {}, raw, d_weights, key);
  const auto fd_tol = std::function<double(size_t)>([&fd](size_t i) { return 1e-8 + 1e-7 * std::abs(fd[i]); });
  CHECK(count_outside(r.d_raw_density, fd, fd_tol) == 0);
  const auto plain = run_weights_ref({Background::black}, {}, raw, d_weights);
  CHECK(count_outside(plain.d_raw_density, fd, fd_tol) > fd.size() / 4);
  const auto dev = run_weights_device(options, {}, raw, d_weights, key);
  double scale = 1e-30;
  for (double v : fd) scale = std::max(scale, std::abs(v));
  MIPNERF_CHECK_CLOSE("device d_raw_density with noise vs finite differences", dev.d_raw_density, fd,
                      [scale](size_t) { return 1e-4 * scale; });
}

TEST_CASE("render: weights backward - sizes that do not fit are refused before the launch, naming the kernel") {
  auto& ctx = test::test_context();
  const size_t n_rays = 4, n = 8, rows = n_rays * n;
  auto raw_density = test::filled(ctx, rows, 0.0f, "raw_density");
  auto t_edges = test::filled(ctx, n_rays * (n + 1), 1.0f, "t_edges");
  const auto rays = test::filled_rays(ctx, n_rays, 1.0f);
  auto weights = test::filled(ctx, rows, 0.0f, "weights"), d_weights = test::filled(ctx, rows, 0.0f, "d_weights");
  auto d_raw = test::filled(ctx, rows, 0.0f, "d_raw_density"), small = test::filled(ctx, rows - 1, 0.0f, "small");
  ops::Render render(ctx, RenderOptions{});
  const ops::RenderDensityInputs in{raw_density, t_edges, rays, n_rays, n};
  CHECK_THROWS_WITH(render.raw_weights_bwd(in, small, d_weights, d_raw), doctest::Contains("render_raw_weights_bwd"));
  CHECK_THROWS_WITH(render.raw_weights_bwd(in, weights, small, d_raw), doctest::Contains("render_raw_weights_bwd"));
  CHECK_THROWS_WITH(render.raw_weights_bwd(in, weights, d_weights, small), doctest::Contains("render_raw_weights_bwd"));
  CHECK_THROWS_WITH(render.raw_weights_bwd(in, weights, d_weights, d_raw, {{1, 2, 3}, 256}),
                    doctest::Contains("256 levels"));
  render.raw_weights_bwd(in, weights, d_weights, d_raw);  // the right sizes launch
  CHECK(test::all_finite(d_raw.download(ctx)));
}

// The fused backward with a loss on the weights as well (RenderGradients::d_weights: the distortion loss on the last
// level, added to the composite's ∂L/∂w): the reference is the derivative of L = Σ d_comp·comp + d_acc·acc + Σ d_w·w
// (central differences, as the noise test above), and the device, per ray and per vector (whose 16-sample blocks
// read d_weights their own way; 37 samples: two blocks and a tail), within 1e-4 of the largest gradient. Without
// d_weights, or with d_weights = 0, the kernel gives what it gave before, bit for bit.
TEST_CASE("render: the fused backward adds a loss on the weights (d_weights) to the composite's, both sample loops") {
  auto& ctx = test::test_context();
  const Batch b = raw_batch(150, 37, 1313);
  const size_t n = b.n_samples, rows = b.n_rays * n;
  const RenderOptions options{Background::white};
  const ActivationOptions activation;
  const auto d_weights = random_d_weights(rows, 1314);
  const auto rgb = test::to_double(b.rgb), density = test::to_double(b.density);
  const auto t_edges = test::to_double(b.t_edges), directions = test::to_double(b.directions);
  const auto d_comp = test::to_double(b.d_comp_rgb), d_acc = test::to_double(b.d_acc);
  const auto d_w = test::to_double(d_weights);
  std::vector<double> comp, acc, distance, weights, d_rgb, d_density;
  ref::render_raw_fwd(options, activation, rgb, density, t_edges, directions, comp, acc, distance, weights, b.n_rays, n);
  ref::render_raw_bwd(options, activation, rgb, density, t_edges, directions, weights, d_comp, &d_acc, d_rgb, d_density,
                      b.n_rays, n, {}, &d_w);
  std::vector<double> fd_density(rows);
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    const std::vector<double> ray_rgb(rgb.begin() + 3 * ray * n, rgb.begin() + 3 * (ray + 1) * n);
    std::vector<double> ray_density(density.begin() + ray * n, density.begin() + (ray + 1) * n);
    const std::vector<double> ray_t(t_edges.begin() + ray * (n + 1), t_edges.begin() + (ray + 1) * (n + 1));
    const std::vector<double> ray_dir(directions.begin() + 3 * ray, directions.begin() + 3 * ray + 3);
    const auto loss = [&] {
      std::vector<double> c, a, dist, w;
      ref::render_raw_fwd(options, activation, ray_rgb, ray_density, ray_t, ray_dir, c, a, dist, w, 1, n);
      double l = d_acc[ray] * a[0] + d_comp[3 * ray] * c[0] + d_comp[3 * ray + 1] * c[1] + d_comp[3 * ray + 2] * c[2];
      for (size_t i = 0; i < n; ++i) l += d_w[ray * n + i] * w[i];
      return l;
    };
    for (size_t i = 0; i < n; ++i) fd_density[ray * n + i] = central_difference(ray_density[i], loss);
  }
  size_t outside = 0;
  for (size_t k = 0; k < rows; ++k) outside += !(std::abs(d_density[k] - fd_density[k]) <= 1e-8 + 1e-7 * std::abs(fd_density[k]));
  CHECK(outside == 0);
  // The weights' loss matters: without it the reference is another derivative for most samples.
  std::vector<double> d_rgb_colour_only, d_density_colour_only;
  ref::render_raw_bwd(options, activation, rgb, density, t_edges, directions, weights, d_comp, &d_acc,
                      d_rgb_colour_only, d_density_colour_only, b.n_rays, n);
  size_t moved = 0;
  for (size_t k = 0; k < rows; ++k) moved += std::abs(d_density_colour_only[k] - fd_density[k]) > 1e-3;
  CHECK(moved > rows / 4);
  CHECK(d_rgb_colour_only == d_rgb);  // the colours' gradients do not involve ∂L/∂w

  double scale = 1e-30;
  for (double v : fd_density) scale = std::max(scale, std::abs(v));
  auto raw_rgb = test::upload(ctx, b.rgb, "raw_rgb"), raw_density = test::upload(ctx, b.density, "raw_density");
  auto t_dev = test::upload(ctx, b.t_edges, "t_edges");
  ops::RayBundle rays(ctx, b.n_rays);
  rays.directions.upload(ctx, b.directions);
  auto d_comp_dev = test::upload(ctx, b.d_comp_rgb, "d_comp_rgb"), d_acc_dev = test::upload(ctx, b.d_acc, "d_acc");
  auto d_w_dev = test::upload(ctx, d_weights, "d_weights");
  auto zero_d_w = test::upload(ctx, std::vector<float>(rows, 0.0f), "zero d_weights");
  for (const auto loop : {ops::RenderSampleLoop::per_ray, ops::RenderSampleLoop::per_vector}) {
    INFO("loop " << static_cast<int>(loop));
    ops::Render render(ctx, options, activation, loop);
    ocl::DeviceArray<float> comp_dev(ctx, 3 * b.n_rays, "comp"), acc_dev(ctx, b.n_rays, "acc");
    ocl::DeviceArray<float> distance_dev(ctx, b.n_rays, "distance"), weights_dev(ctx, rows, "weights");
    ocl::DeviceArray<float> d_rgb_dev(ctx, 3 * rows, "d_rgb"), d_density_dev(ctx, rows, "d_density");
    const ops::RenderInputs in{raw_rgb, raw_density, t_dev, rays, b.n_rays, n};
    render.raw_fwd(in, {comp_dev, acc_dev, distance_dev, weights_dev});
    const auto backward = [&](const ocl::DeviceArray<float>* with) {
      ops::RenderGradients grads{d_comp_dev, &d_acc_dev};
      grads.d_weights = with;
      render.raw_bwd(in, weights_dev, grads, {d_rgb_dev, d_density_dev});
      return std::make_pair(d_rgb_dev.download(ctx), d_density_dev.download(ctx));
    };
    const auto with_loss = backward(&d_w_dev);
    MIPNERF_CHECK_CLOSE("device d_raw_density with d_weights vs finite differences", with_loss.second, fd_density,
                        [scale](size_t) { return 1e-4 * scale; });
    const auto without = backward(nullptr);
    const auto with_zero = backward(&zero_d_w);
    CHECK(with_zero.first == without.first);
    CHECK(with_zero.second == without.second);
    CHECK(with_loss.first == without.first);
  }
}
