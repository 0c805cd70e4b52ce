// Our render backward (kernels/render.cl render_bwd through ops::Render) against the official gradient:
// jax.vjp of mip.volumetric_rendering with respect to its colours and densities (tests/official/fixtures/
// render_grad.json, written by make_vectors.py from google/mipnerf in float64) for given cotangents of the composite
// and the accumulation, on render.json's inputs (thin, empty, opaque and nearly transparent rays, a zero-length
// interval), white and black backgrounds. The bound of each element is derived beside its assertion; ignoring the
// accumulation's cotangent or the background must not match.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "official_fixtures.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/render.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using official::flat;
using official::kU;

namespace {

struct RenderGradCase {
  size_t R = 0, N = 0;
  std::vector<double> rgb, density, t, dirs, d_comp, d_acc;
  io::Json outputs;
};

RenderGradCase load_case() {
  RenderGradCase c;
  const auto fx = official::fixture("render_grad.json");
  const auto render = official::fixture("render.json");
  const auto& in = render.at("inputs");
  c.R = in.at("density").size();
  c.N = in.at("density").at(0).size();
  c.rgb = flat(in.at("rgb"), {c.R, c.N, 3});
  c.density = flat(in.at("density"), {c.R, c.N});
  c.t = flat(in.at("t_vals"), {c.R, c.N + 1});
  c.dirs = flat(in.at("dirs"), {c.R, 3});
  c.d_comp = flat(fx.at("cotangents").at("d_comp_rgb"), {c.R, 3});
  c.d_acc = flat(fx.at("cotangents").at("d_acc"), {c.R});
  c.outputs = fx.at("outputs");
  return c;
}

struct Gradients {
  std::vector<float> d_rgb, d_density;
};

// Our forward (for the weights the backward reads, as the graph keeps them) then render_bwd.
Gradients run_bwd(const RenderGradCase& c, Background background, bool with_d_acc) {
  auto& ctx = test::test_context();
  ops::RayBundle rays(ctx, c.R);
  rays.directions.upload(ctx, official::as_float(c.dirs));
  auto rgb = official::upload(ctx, official::as_float(c.rgb), "rgb [R][N][3]");
  auto density = official::upload(ctx, official::as_float(c.density), "density [R][N]");
  auto t = official::upload(ctx, official::as_float(c.t), "t_edges [R][N+1]");
  auto d_comp = official::upload(ctx, official::as_float(c.d_comp), "d_comp_rgb [R][3]");
  auto d_acc = official::upload(ctx, official::as_float(c.d_acc), "d_acc [R]");
  ocl::DeviceArray<float> comp(ctx, 3 * c.R, "comp_rgb [R][3]"), acc(ctx, c.R, "acc [R]"),
      distance(ctx, c.R, "distance [R]"), weights(ctx, c.R * c.N, "weights [R][N]");
  ocl::DeviceArray<float> d_rgb(ctx, 3 * c.R * c.N, "d_rgb [R][N][3]"), d_density(ctx, c.R * c.N, "d_density [R][N]");
  RenderOptions options;
  options.background = background;
  ops::Render render(ctx, options);
  const ops::RenderInputs in{rgb, density, t, rays, c.R, c.N};
  render.fwd(in, {comp, acc, distance, weights});
  render.bwd(in, weights, {d_comp, with_d_acc ? &d_acc : nullptr}, {d_rgb, d_density});
  return {d_rgb.download(ctx), d_density.download(ctx)};
}

const double kFloor = std::ldexp(1.0, -126);  // FLT_MIN

// The bounds of d_rgb and d_density, from render.json's forward bound and the backward's own roundings.
struct GradientBounds {
  std::vector<double> d_rgb, d_density;
};

// With s_i = σ_i·δ_i, τ_i = Σ_{k≤i} s_k, w_i = (1 − e^{−s_i})·T_i, T_{i+1} = e^{−τ_i}, c_i the colours and
// g_k = d_comp·c_k + a (a = d_acc − Σ_c d_comp_c on a white background: comp holds 1 − acc; d_acc on black):
//   ∂L/∂c_i = d_comp·w_i,   ∂L/∂σ_i = δ_i·(g_i·T_{i+1} − Σ_{k>i} g_k·w_k).
// Our kernel evaluates them from the forward's float32 weights, each within wb_k = (N + 16)u·(1 + τ_k)·w_k of the
// official (render.json's bound), and T_{i+1} as T_N + Σ_{k>i} w_k, T_N = exp(−Σ s) within ((N + 4)u·τ_N + 2u)·T_N
// (the forward's running sum and exp), the suffix sums within N·u of their magnitudes. So:
//   |δ ∂L/∂c_i| ≤ |d_comp|·(wb_i + u·w_i);
//   |δ ∂L/∂σ_i| ≤ δ_i·[ |g_i|·(|δT_N| + Σ_{k>i} wb_k + N·u·T_{i+1}) + Σ_{k>i} (|g_k|·wb_k + 4u·G_k·w_k)
//                       + 4u·G_i·T_{i+1} + (N + 6)·u·(|g_i|·T_{i+1} + Σ_{k>i} |g_k|·w_k) ]
// with G_k = Σ_c |d_comp_c·c_k| + |d_acc| + Σ_c |d_comp_c| bounding g_k's terms (its float error ≤ 4u·G_k) and the
// interval δ_i = Δt·|d| within 4u (Δt exact for neighbouring edges, |d| 2u, the product u; the last term's 6u).
// Behind the opaque ray's surface the official weights and transmittances fall below float32's range (1e-50): every
// float32 value is also within 2^-126 of its exact value (FLT_MIN: a device may flush subnormals), so each gradient
// gets that floor times the magnitudes it multiplies: |d_comp|, and δ_i·(N + 2)·(G_i + Σ_{k>i} G_k).
GradientBounds gradient_bounds(const RenderGradCase& c, bool white) {
  GradientBounds b;
  b.d_rgb.resize(3 * c.R * c.N);
  b.d_density.resize(c.R * c.N);
  const size_t N = c.N;
  for (size_t r = 0; r < c.R; ++r) {
    const double* d = &c.dirs[3 * r];
    const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    std::vector<double> s(N), w(N), wb(N), g(N), G(N), T_after(N);
    double tau = 0;
    const double dc[3] = {c.d_comp[3 * r], c.d_comp[3 * r + 1], c.d_comp[3 * r + 2]};
    const double a = c.d_acc[r] - (white ? dc[0] + dc[1] + dc[2] : 0.0);
    const double dc1 = std::abs(dc[0]) + std::abs(dc[1]) + std::abs(dc[2]);
    for (size_t i = 0; i < N; ++i) {
      s[i] = c.density[r * N + i] * (c.t[r * (N + 1) + i + 1] - c.t[r * (N + 1) + i]) * norm;
      const double T = std::exp(-tau);
      tau += s[i];
      w[i] = -std::expm1(-s[i]) * T;
      T_after[i] = std::exp(-tau);
      wb[i] = (static_cast<double>(N) + 16) * kU * (1 + tau) * w[i];
      g[i] = a;
      G[i] = std::abs(c.d_acc[r]) + dc1;
      for (int ch = 0; ch < 3; ++ch) {
        g[i] += dc[ch] * c.rgb[3 * (r * N + i) + ch];
        G[i] += std::abs(dc[ch] * c.rgb[3 * (r * N + i) + ch]);
        b.d_rgb[3 * (r * N + i) + ch] = std::abs(dc[ch]) * (wb[i] + kU * w[i] + kFloor) + kFloor;
      }
    }
    const double dT_N = ((static_cast<double>(N) + 4) * kU * tau + 2 * kU) * T_after[N - 1];
    double wb_after = 0, gwb_after = 0, gw_after = 0, gGw_after = 0, G_after = 0;  // suffix sums over k > i
    for (size_t k = N; k-- > 0;) {
      const double delta = (c.t[r * (N + 1) + k + 1] - c.t[r * (N + 1) + k]) * norm;
      const double T = T_after[k];
      b.d_density[r * N + k] =
          delta *
              (std::abs(g[k]) * (dT_N + wb_after + N * kU * T) + gwb_after + 4 * kU * gGw_after + 4 * kU * G[k] * T +
               (N + 6) * kU * (std::abs(g[k]) * T + gw_after) + (N + 2) * kFloor * (G[k] + G_after)) +
          kFloor;
      wb_after += wb[k];
      gwb_after += std::abs(g[k]) * wb[k];
      gw_after += std::abs(g[k]) * w[k];
      gGw_after += G[k] * w[k];
      G_after += G[k];
    }
  }
  return b;
}

}  // namespace

TEST_CASE("volumetric_rendering gradient: our render backward is the official jax.vjp for colours and densities") {
  const auto c = load_case();
  for (const bool white : {true, false}) {
    CAPTURE(white);
    const auto& out = c.outputs.at(white ? "white" : "black");
    const auto d_rgb = flat(out.at("d_rgb"), {c.R, c.N, 3}), d_density = flat(out.at("d_density"), {c.R, c.N});
    const auto ours = run_bwd(c, white ? Background::white : Background::black, true);
    const auto bounds = gradient_bounds(c, white);
    OFFICIAL_CHECK_AGREES("d_rgb", ours.d_rgb, d_rgb, [&](size_t i) { return bounds.d_rgb[i]; });
    OFFICIAL_CHECK_AGREES("d_density", ours.d_density, d_density, [&](size_t i) { return bounds.d_density[i]; });
  }
}

TEST_CASE("volumetric_rendering gradient: without the acc cotangent, or with the other background, not the official") {
  const auto c = load_case();
  const auto& out = c.outputs.at("white");
  const auto d_density = flat(out.at("d_density"), {c.R, c.N});
  const auto bounds = gradient_bounds(c, true);
  const auto bound = [&](size_t i) { return bounds.d_density[i]; };
  // d_acc ~ N(0, 1) dropped from every g_k: the densities' gradients move by O(δ·T).
  OFFICIAL_CHECK_DISAGREES("d_density without d_acc", run_bwd(c, Background::white, false).d_density, d_density, 100.0,
                           bound);
  // A black background leaves Σ_c d_comp_c out of every g_k.
  OFFICIAL_CHECK_DISAGREES("d_density on black", run_bwd(c, Background::black, true).d_density, d_density, 100.0,
                           bound);
}
