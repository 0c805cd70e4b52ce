// The ray-math stages timed on the device, and in a CPU implementation when one is given (see kernel_bench.hpp).
#include "bench/kernel_bench.hpp"

#include <algorithm>
#include <functional>
#include <optional>
#include <random>

#include "cl/buffer.hpp"
#include "core/camera.hpp"
#include "core/error.hpp"
#include "ops/activations.hpp"
#include "ops/encode.hpp"
#include "ops/gaussian.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/rays.hpp"
#include "ops/render.hpp"
#include "ops/resample.hpp"
#include "ops/sample.hpp"
#include "ops/stage_list.hpp"

namespace mipnerf::bench {
namespace {

// Every stage's host/ops object (each builds its program once), filled in the stage list's order.
struct Stages {
  std::optional<ops::Rays> rays;
  std::optional<ops::Sample> sample;
  std::optional<ops::Gaussian> gaussian;
  std::optional<ops::Encode> encode;
  std::optional<ops::Activations> activations;
  std::optional<ops::Render> render;
  std::optional<ops::Resample> resample;
};

using Options = ops::RayMathOptions;

// Builds one stage of ops::ray_math_stages() (a missing case is a compile error: -Werror=switch).
void build_stage(ops::StageId id, ocl::Context& ctx, const Options& o, Stages& s) {
  switch (id) {
    case ops::StageId::rays:
      s.rays.emplace(ctx, o.rays);
      return;
    case ops::StageId::sample:
      s.sample.emplace(ctx, o.sample);
      return;
    case ops::StageId::gaussian:
      s.gaussian.emplace(ctx, o.gaussian);
      return;
    case ops::StageId::encode:
      s.encode.emplace(ctx, o.gaussian);
      return;
    case ops::StageId::activations:
      s.activations.emplace(ctx, o.activation);
      return;
    case ops::StageId::render:
      s.render.emplace(ctx, o.render, o.activation);
      return;
    case ops::StageId::resample:
      s.resample.emplace(ctx);
      return;
  }
  throw Error("kernel benchmark: stage id " + std::to_string(static_cast<int>(id)) + " is not in the stage list");
}

// Builds every listed stage with the benchmark's options, each first build timed.
Stages build_stages(ocl::Context& ctx, const ops::RayMathOptions& o, std::vector<ProgramBuild>& builds) {
  Stages stages;
  for (const auto& stage : ops::ray_math_stages()) {
    const auto start = Clock::now();
    build_stage(stage.id, ctx, o, stages);
    builds.push_back({stage.program, seconds_since(start)});
  }
  return stages;
}

// The device buffers of one batch of R rays × N samples (layouts: docs/ARCHITECTURE.md, "Buffers and layouts").
struct DeviceBuffers {
  DeviceBuffers(ocl::Context& ctx, size_t R, size_t N, const ops::RayMathOptions& o)
      : cameras(ctx, camera_layout::stride, "cameras"),
        camera_ids(ctx, R, "camera_ids"),
        pixel_ids(ctx, R, "pixel_ids"),
        rays(ctx, R),
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
  ops::RayBundle rays;
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

using DeviceCall = std::function<void()>;

// One listed kernel on the device over the benchmark's buffers (R rays × N samples); a missing case is a compile
// error (-Werror=switch).
DeviceCall device_call(ops::KernelId id, Stages& s, DeviceBuffers& b, const ops::RayMathOptions& o, size_t R, size_t N,
                       const RngKey& key) {
  const size_t rows = R * N;
  const ops::RaysInputs rays_in{b.cameras, b.camera_ids, b.pixel_ids, R};
  const ops::GaussianInputs gaussian_in{b.rays, b.t_edges, R, N};
  const ops::ActivationInputs act_in{b.raw_density, b.raw_rgb, rows};
  const ops::RenderInputs render_in{b.rgb, b.density, b.t_edges, b.rays, R, N};
  const ops::RenderInputs render_raw_in{b.raw_rgb, b.raw_density, b.t_edges, b.rays, R, N};
  using K = ops::KernelId;
  switch (id) {
    case K::rays_fwd:
      return [&s, &b, rays_in, key] { s.rays->fwd(rays_in, b.rays, key); };
    case K::sample_stratified_fwd:
      return [&s, &b, R, N, key] { s.sample->stratified({b.rays, R, N}, b.t_edges, key); };
    case K::gaussian_fwd:
      return [&s, &b, gaussian_in] { s.gaussian->fwd(gaussian_in, {b.means, b.covs}); };
    case K::ipe_fwd:
      return [&s, &b, &o, rows] { s.encode->ipe(o.ipe, {b.means, b.covs, rows}, b.features); };
    case K::gaussian_ipe_fwd:
      return [&s, &b, &o, gaussian_in] { s.encode->gaussian_ipe(o.ipe, gaussian_in, b.features); };
    case K::pe_fwd:
      return [&s, &b, &o, R] { s.encode->pe(o.view, {b.rays.viewdirs, R}, b.view_features); };
    case K::activations_fwd:
      return [&s, &b, act_in] { s.activations->fwd(act_in, {b.density, b.rgb}); };
    case K::activations_bwd:
      return [&s, &b, act_in] { s.activations->bwd(act_in, {b.density, b.rgb}, {b.d_raw_density, b.d_raw_rgb}); };
    case K::render_fwd:
      return [&s, &b, render_in] { s.render->fwd(render_in, {b.comp, b.acc, b.distance, b.weights}); };
    case K::render_bwd:
      return [&s, &b, render_in] { s.render->bwd(render_in, b.weights, {b.d_comp, nullptr}, {b.d_rgb, b.d_density}); };
    case K::render_raw_fwd:
      return [&s, &b, render_raw_in] { s.render->raw_fwd(render_raw_in, {b.comp, b.acc, b.distance, b.weights}); };
    case K::render_raw_bwd:
      return [&s, &b, render_raw_in] {
        s.render->raw_bwd(render_raw_in, b.weights, {b.d_comp, nullptr}, {b.d_raw_rgb, b.d_raw_density});
      };
    case K::resample_fwd:
      return [&s, &b, &o, R, N, key] { s.resample->fwd(o.resample, {b.t_edges, b.weights, R, N, N}, b.t_fine, key); };
  }
  throw Error("kernel benchmark: kernel id " + std::to_string(static_cast<int>(id)) + " is not in the stage list");
}

// One row of the benchmark: a listed kernel and how to run it.
struct Row {
  const ops::StageKernel* kernel;
  DeviceCall device;
};

// The listed kernels in the list's order, each with its device call.
std::vector<Row> rows(Stages& s, DeviceBuffers& b, const ops::RayMathOptions& o, size_t R, size_t N,
                      const RngKey& key) {
  std::vector<Row> list;
  for (const auto& stage : ops::ray_math_stages()) {
    for (const auto& kernel : stage.kernels) list.push_back({&kernel, device_call(kernel.id, s, b, o, R, N, key)});
  }
  return list;
}

// Random pixels and network outputs, then one pass of the pipeline so every stage's inputs hold realistic values;
// returns the reference's copies of them.
KernelBenchInputs make_inputs(ocl::Context& ctx, Stages& s, DeviceBuffers& b, size_t R, size_t N, const RngKey& key) {
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

  s.rays->fwd({b.cameras, b.camera_ids, b.pixel_ids, R}, b.rays, key);
  s.sample->stratified({b.rays, R, N}, b.t_edges, key);
  s.activations->fwd({b.raw_density, b.raw_rgb, rows}, {b.density, b.rgb});
  s.render->fwd({b.rgb, b.density, b.t_edges, b.rays, R, N}, {b.comp, b.acc, b.distance, b.weights});
  s.gaussian->fwd({b.rays, b.t_edges, R, N}, {b.means, b.covs});
  ctx.finish();

  r.cameras.assign(cameras.begin(), cameras.end());
  r.origins = download_double(ctx, b.rays.origins);
  r.directions = download_double(ctx, b.rays.directions);
  r.radii = download_double(ctx, b.rays.radii);
  r.near = download_double(ctx, b.rays.near);
  r.far = download_double(ctx, b.rays.far);
  r.viewdirs = download_double(ctx, b.rays.viewdirs);
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

StageTiming time_stage(ocl::Context& ctx, const Row& row, const std::function<void()>& reference,
                       const KernelBenchOptions& options) {
  StageTiming t;
  t.stage = row.kernel->row();
  t.unit = ops::unit_name(row.kernel->unit);
  t.items = ops::items(row.kernel->unit, options.rays, options.samples);
  const auto on_device = [&] {
    row.device();
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
  const ops::RayMathOptions stage_options;  // the paper's Blender configuration
  Stages stages = build_stages(ctx, stage_options, result.builds);
  DeviceBuffers buffers(ctx, R, N, stage_options);
  const RngKey key{20200823, 1, 0};
  KernelBenchInputs inputs = make_inputs(ctx, stages, buffers, R, N, key);
  const std::vector<Row> list = rows(stages, buffers, stage_options, R, N, key);
  for (size_t i = 0; i < list.size(); ++i) {
    if (progress) progress(list[i].kernel->row(), i, list.size());
    const std::function<void()> on_cpu = reference && result.options.reference_reps > 0
                                             ? reference(list[i].kernel->id, stage_options, inputs, R, N, key)
                                             : std::function<void()>{};
    result.stages.push_back(time_stage(ctx, list[i], on_cpu, result.options));
  }
  if (progress) progress("done", list.size(), list.size());
  return result;
}

}  // namespace mipnerf::bench
