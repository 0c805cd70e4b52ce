// The ray-math stages timed on the device, and in a CPU implementation when one is given (see kernel_bench.hpp).
#include "bench/kernel_bench.hpp"

#include <algorithm>
#include <functional>
#include <random>

#include "cl/buffer.hpp"
#include "core/error.hpp"
#include "core/camera.hpp"
#include "ops/activations.hpp"
#include "ops/encode.hpp"
#include "ops/gaussian.hpp"
#include "ops/rays.hpp"
#include "ops/render.hpp"
#include "ops/resample.hpp"
#include "ops/sample.hpp"

namespace mipnerf::bench {
namespace {

// One program per stage and specialisation, each first build timed.
struct Stages {
  ops::Rays rays;
  ops::Sample sample;
  ops::Resample resample;
  ops::Gaussian gaussian;
  ops::Encode encode;
  ops::Activations activations;
  ops::Render render;
};

template <typename Make>
auto timed_build(std::vector<ProgramBuild>& builds, const std::string& name, Make make) {
  const auto start = Clock::now();
  auto stage = make();
  builds.push_back({name, seconds_since(start)});
  return stage;
}

Stages build_stages(ocl::Context& ctx, const KernelStageOptions& o, std::vector<ProgramBuild>& builds) {
  return Stages{
      timed_build(builds, "rays.cl", [&] { return ops::Rays(ctx, o.rays); }),
      timed_build(builds, "sample.cl", [&] { return ops::Sample(ctx, o.sample); }),
      timed_build(builds, "resample.cl", [&] { return ops::Resample(ctx); }),
      timed_build(builds, "gaussian.cl", [&] { return ops::Gaussian(ctx, o.gaussian); }),
      timed_build(builds, "gaussian.cl + encode.cl", [&] { return ops::Encode(ctx, o.gaussian); }),
      timed_build(builds, "activations.cl", [&] { return ops::Activations(ctx, o.activation); }),
      timed_build(builds, "activations.cl + render.cl", [&] { return ops::Render(ctx, o.render, o.activation); }),
  };
}

// The device buffers of one batch of R rays × N samples (layouts: docs/ARCHITECTURE.md, "Buffers and layouts").
struct DeviceBuffers {
  DeviceBuffers(ocl::Context& ctx, size_t R, size_t N, const KernelStageOptions& o)
      : cameras(ctx, camera_layout::stride, "cameras"),
        camera_ids(ctx, R, "camera_ids"),
        pixel_ids(ctx, R, "pixel_ids"),
        origins(ctx, 3 * R, "origins"),
        directions(ctx, 3 * R, "directions"),
        viewdirs(ctx, 3 * R, "viewdirs"),
        radii(ctx, R, "radii"),
        near(ctx, R, "near"),
        far(ctx, R, "far"),
        lossmult(ctx, R, "lossmult"),
        t_edges(ctx, R * (N + 1), "t_edges"),
        t_fine(ctx, R * (N + 1), "t_fine"),
        means(ctx, 3 * R * N, "means"),
        covs(ctx, 3 * R * N, "covs"),
        features(ctx, R * N * o.ipe.ipe_width(), "ipe_features"),
        view_features(ctx, R * o.view.pe_width(), "view_encoding"),
        raw_density(ctx, R * N, "raw_density"),
        raw_rgb(ctx, 3 * R * N, "raw_rgb"),
        density(ctx, R * N, "density"),
        rgb(ctx, 3 * R * N, "rgb"),
        comp(ctx, 3 * R, "comp_rgb"),
        acc(ctx, R, "acc"),
        distance(ctx, R, "distance"),
        weights(ctx, R * N, "weights"),
        d_comp(ctx, 3 * R, "d_comp_rgb"),
        d_rgb(ctx, 3 * R * N, "d_rgb"),
        d_density(ctx, R * N, "d_density"),
        d_raw_rgb(ctx, 3 * R * N, "d_raw_rgb"),
        d_raw_density(ctx, R * N, "d_raw_density") {}
  ocl::DeviceArray<float> cameras;
  ocl::DeviceArray<uint32_t> camera_ids, pixel_ids;
  ocl::DeviceArray<float> origins, directions, viewdirs, radii, near, far, lossmult;
  ocl::DeviceArray<float> t_edges, t_fine, means, covs, features, view_features;
  ocl::DeviceArray<float> raw_density, raw_rgb, density, rgb, comp, acc, distance, weights;
  ocl::DeviceArray<float> d_comp, d_rgb, d_density, d_raw_rgb, d_raw_density;
};

// A 800×800 Blender-like camera (lego's first training view, rounded).
Camera blender_camera() {
  Camera cam;
  cam.width_px = cam.height_px = 800;
  cam.focal_x_px = cam.focal_y_px = 1111.0;
  cam.center_x_px = cam.center_y_px = 400.0;
  cam.camera_to_world = {-0.9999, 0.0042, -0.0134, -0.0538, -0.0140, -0.2997,
                         0.9539,  3.8455, 0.0,     0.9540,  0.2997,  1.2081};
  return cam;
}

std::vector<double> download_double(ocl::Context& ctx, const ocl::DeviceArray<float>& array) {
  const auto values = array.download(ctx);
  return {values.begin(), values.end()};
}

struct Stage {
  std::string name, unit;
  size_t items;
  std::function<void()> device;
};

std::vector<Stage> stage_list(Stages& s, DeviceBuffers& b, const KernelStageOptions& o, size_t R, size_t N,
                              const RngKey& key) {
  const size_t rows = R * N;
  const ops::RaysInputs rays_in{b.cameras, b.camera_ids, b.pixel_ids, R};
  const ops::RaysOutputs rays_out{b.origins, b.directions, b.viewdirs, b.radii, b.near, b.far, b.lossmult};
  const ops::GaussianInputs gaussian_in{b.origins, b.directions, b.radii, b.t_edges, R, N};
  const ops::ActivationInputs act_in{b.raw_density, b.raw_rgb, rows};
  const ops::RenderInputs render_in{b.rgb, b.density, b.t_edges, b.directions, R, N};
  const ops::RenderInputs render_raw_in{b.raw_rgb, b.raw_density, b.t_edges, b.directions, R, N};
  return {
      {"rays_fwd (cone)", "rays", R, [&s, rays_in, rays_out, key] { s.rays.fwd(rays_in, rays_out, key); }},
      {"sample_stratified_fwd (jittered)", "edges", R * (N + 1),
       [&s, &b, R, N, key] { s.sample.stratified({b.near, b.far, R, N}, b.t_edges, key); }},
      {"gaussian_fwd (cone)", "intervals", rows, [&s, &b, gaussian_in] { s.gaussian.fwd(gaussian_in, {b.means, b.covs}); }},
      {"ipe_fwd (L = 16, 96 features)", "intervals", rows,
       [&s, &b, &o, rows] { s.encode.ipe(o.ipe, {b.means, b.covs, rows}, b.features); }},
      {"gaussian_ipe_fwd (fused)", "intervals", rows,
       [&s, &b, &o, gaussian_in] { s.encode.gaussian_ipe(o.ipe, gaussian_in, b.features); }},
      {"pe_fwd (view directions, 27 features)", "rays", R,
       [&s, &b, &o, R] { s.encode.pe(o.view, {b.viewdirs, R}, b.view_features); }},
      {"activations_fwd", "samples", rows, [&s, &b, act_in] { s.activations.fwd(act_in, {b.density, b.rgb}); }},
      {"activations_bwd", "samples", rows,
       [&s, &b, act_in] { s.activations.bwd(act_in, {b.density, b.rgb}, {b.d_raw_density, b.d_raw_rgb}); }},
      {"render_fwd (white)", "samples", rows,
       [&s, &b, render_in] { s.render.fwd(render_in, {b.comp, b.acc, b.distance, b.weights}); }},
      {"render_bwd (white)", "samples", rows,
       [&s, &b, render_in] { s.render.bwd(render_in, b.weights, {b.d_comp, nullptr}, {b.d_rgb, b.d_density}); }},
      {"render_raw_fwd (fused activations)", "samples", rows,
       [&s, &b, render_raw_in] { s.render.raw_fwd(render_raw_in, {b.comp, b.acc, b.distance, b.weights}); }},
      {"render_raw_bwd (fused activations)", "samples", rows,
       [&s, &b, render_raw_in] {
         s.render.raw_bwd(render_raw_in, b.weights, {b.d_comp, nullptr}, {b.d_raw_rgb, b.d_raw_density});
       }},
      {"resample_fwd (α = 0.01, jittered)", "edges", R * (N + 1),
       [&s, &b, &o, R, N, key] { s.resample.fwd(o.resample, {b.t_edges, b.weights, R, N, N}, b.t_fine, key); }},
  };
}

// Random pixels and network outputs, then one pass of the pipeline so every stage's inputs hold realistic values;
// returns the reference's copies of them.
KernelBenchInputs make_inputs(ocl::Context& ctx, Stages& s, DeviceBuffers& b, const KernelStageOptions& o, size_t R, size_t N,
                            const RngKey& key) {
  const size_t rows = R * N;
  std::mt19937 rng(1);
  const Camera cam = blender_camera();
  const std::vector<float> cameras = pack_cameras({cam});
  KernelBenchInputs r;
  r.camera_ids.assign(R, 0);
  r.pixel_ids.resize(R);
  for (auto& p : r.pixel_ids) p = static_cast<uint32_t>(rng() % (cam.width_px * cam.height_px));
  b.cameras.upload(ctx, cameras);
  b.camera_ids.upload(ctx, r.camera_ids);
  b.pixel_ids.upload(ctx, r.pixel_ids);
  std::normal_distribution<float> normal(0.0f, 2.0f);
  std::vector<float> host(3 * rows);
  for (auto& v : host) v = normal(rng);
  b.raw_rgb.upload(ctx, host);
  host.resize(rows);
  for (auto& v : host) v = normal(rng);
  b.raw_density.upload(ctx, host);
  host.resize(3 * R);
  for (auto& v : host) v = 0.1f * normal(rng);
  b.d_comp.upload(ctx, host);

  s.rays.fwd({b.cameras, b.camera_ids, b.pixel_ids, R},
             {b.origins, b.directions, b.viewdirs, b.radii, b.near, b.far, b.lossmult}, key);
  s.sample.stratified({b.near, b.far, R, N}, b.t_edges, key);
  s.activations.fwd({b.raw_density, b.raw_rgb, rows}, {b.density, b.rgb});
  s.render.fwd({b.rgb, b.density, b.t_edges, b.directions, R, N}, {b.comp, b.acc, b.distance, b.weights});
  s.gaussian.fwd({b.origins, b.directions, b.radii, b.t_edges, R, N}, {b.means, b.covs});
  ctx.finish();

  r.cameras.assign(cameras.begin(), cameras.end());
  r.origins = download_double(ctx, b.origins);
  r.directions = download_double(ctx, b.directions);
  r.radii = download_double(ctx, b.radii);
  r.near = download_double(ctx, b.near);
  r.far = download_double(ctx, b.far);
  r.viewdirs = download_double(ctx, b.viewdirs);
  r.t_edges = download_double(ctx, b.t_edges);
  r.weights = download_double(ctx, b.weights);
  r.raw_density = download_double(ctx, b.raw_density);
  r.raw_rgb = download_double(ctx, b.raw_rgb);
  r.density = download_double(ctx, b.density);
  r.rgb = download_double(ctx, b.rgb);
  r.d_comp = download_double(ctx, b.d_comp);
  r.means = download_double(ctx, b.means);
  r.covs = download_double(ctx, b.covs);
  return r;
}

StageTiming time_stage(ocl::Context& ctx, const Stage& stage, const std::function<void()>& reference,
                       const KernelBenchOptions& options) {
  StageTiming t;
  t.stage = stage.name;
  t.unit = stage.unit;
  t.items = stage.items;
  const auto on_device = [&] {
    stage.device();
    ctx.finish();
  };
  t.first_call_seconds = time_call(on_device);  // first launch: buffers touched, work-group code generated
  for (size_t k = 0; k < options.reps; ++k) t.device.add(time_call(on_device));
  if (reference && options.reference_reps > 0) {
    t.reference_seconds = 1e300;
    for (size_t k = 0; k < options.reference_reps; ++k) {
      t.reference_seconds = std::min(t.reference_seconds, time_call(reference));
    }
  }
  return t;
}

}  // namespace

KernelBenchResult run_kernel_bench(ocl::Context& ctx, const KernelBenchOptions& options, const ProgressFn& progress,
                                   const ReferenceStages& reference) {
  if (options.rays == 0 || options.samples == 0 || options.reps == 0) {
    throw Error("kernel benchmark: rays, samples and reps must be at least 1");
  }
  const size_t R = options.rays, N = options.samples;
  KernelBenchResult result;
  result.options = options;
  if (!reference) result.options.reference_reps = 0;
  const KernelStageOptions stage_options;
  Stages stages = build_stages(ctx, stage_options, result.builds);
  DeviceBuffers buffers(ctx, R, N, stage_options);
  const RngKey key{20200823, 1, 0};
  KernelBenchInputs inputs = make_inputs(ctx, stages, buffers, stage_options, R, N, key);
  const std::vector<Stage> list = stage_list(stages, buffers, stage_options, R, N, key);
  for (size_t i = 0; i < list.size(); ++i) {
    if (progress) progress(list[i].name, i, list.size());
    const std::function<void()> on_cpu =
        reference && result.options.reference_reps > 0 ? reference(list[i].name, stage_options, inputs, R, N, key)
                                                       : std::function<void()>{};
    result.stages.push_back(time_stage(ctx, list[i], on_cpu, result.options));
  }
  if (progress) progress("done", list.size(), list.size());
  return result;
}

}  // namespace mipnerf::bench
