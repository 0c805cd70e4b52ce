// The ray-math stages timed on the device and in the CPU reference (see kernel_bench.hpp).
#include "bench/kernel_bench.hpp"

#include <algorithm>
#include <functional>
#include <random>

#include "cl/buffer.hpp"
#include "cl/error.hpp"
#include "data/camera.hpp"
#include "ops/activations.hpp"
#include "ops/encode.hpp"
#include "ops/gaussian.hpp"
#include "ops/rays.hpp"
#include "ops/render.hpp"
#include "ops/resample.hpp"
#include "ops/sample.hpp"
#include "ref/activations.hpp"
#include "ref/encode.hpp"
#include "ref/gaussian.hpp"
#include "ref/rays.hpp"
#include "ref/render.hpp"
#include "ref/resample.hpp"
#include "ref/sample.hpp"

namespace mipnerf::bench {
namespace {

// Every stage's options, as the paper's Blender configuration has them.
struct StageOptions {
  ops::RaysOptions rays;
  ops::SampleOptions sample{false, true};  // depth-linear, jittered
  ops::ResampleOptions resample;           // α = 0.01, blur, jittered
  ops::GaussianOptions gaussian;           // cone
  ops::RenderOptions render;               // white background
  ops::ActivationOptions activation;
  ops::EncodingOptions ipe;   // degrees 0..15: 96 features
  ops::EncodingOptions view;  // degrees 0..3 + identity: 27 features
  StageOptions() {
    view.max_deg = 4;
    view.append_identity = true;
  }
};

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

Stages build_stages(ocl::Context& ctx, const StageOptions& o, std::vector<ProgramBuild>& builds) {
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
  DeviceBuffers(ocl::Context& ctx, size_t R, size_t N, const StageOptions& o)
      : cameras(ctx, data::camera_layout::stride, "cameras"),
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
data::Camera blender_camera() {
  data::Camera cam;
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

// The CPU reference's inputs: the device's, in double; the reference's outputs are scratch.
struct ReferenceInputs {
  std::vector<double> cameras, origins, directions, radii, near, far, viewdirs, t_edges, weights;
  std::vector<double> raw_density, raw_rgb, density, rgb, d_comp, means, covs;
  std::vector<uint32_t> camera_ids, pixel_ids;
  std::vector<double> o1, o2, o3, o4, o5, o6, o7;  // outputs, discarded
};

struct Stage {
  std::string name, unit;
  size_t items;
  std::function<void()> device, reference;
};

std::vector<Stage> stage_list(Stages& s, DeviceBuffers& b, ReferenceInputs& r, const StageOptions& o, size_t R,
                              size_t N, const ops::RngKey& key) {
  const size_t rows = R * N;
  const ops::RaysInputs rays_in{b.cameras, b.camera_ids, b.pixel_ids, R};
  const ops::RaysOutputs rays_out{b.origins, b.directions, b.viewdirs, b.radii, b.near, b.far, b.lossmult};
  const ops::GaussianInputs gaussian_in{b.origins, b.directions, b.radii, b.t_edges, R, N};
  const ops::ActivationInputs act_in{b.raw_density, b.raw_rgb, rows};
  const ops::RenderInputs render_in{b.rgb, b.density, b.t_edges, b.directions, R, N};
  const ops::RenderInputs render_raw_in{b.raw_rgb, b.raw_density, b.t_edges, b.directions, R, N};
  return {
      {"rays_fwd (cone)", "rays", R, [&s, rays_in, rays_out, key] { s.rays.fwd(rays_in, rays_out, key); },
       [&r, &o, R, key] {
         ref::rays_fwd(o.rays, r.cameras, r.camera_ids, r.pixel_ids, r.o1, r.o2, r.o3, r.o4, r.o5, r.o6, r.o7, R, 1,
                       key);
       }},
      {"sample_stratified_fwd (jittered)", "edges", R * (N + 1),
       [&s, &b, R, N, key] { s.sample.stratified({b.near, b.far, R, N}, b.t_edges, key); },
       [&r, &o, R, N, key] { ref::sample_stratified_fwd(o.sample, r.near, r.far, r.o1, R, N, key); }},
      {"gaussian_fwd (cone)", "intervals", rows, [&s, &b, gaussian_in] { s.gaussian.fwd(gaussian_in, {b.means, b.covs}); },
       [&r, &o, R, N] { ref::gaussian_fwd(o.gaussian, r.origins, r.directions, r.radii, r.t_edges, r.o1, r.o2, R, N); }},
      {"ipe_fwd (L = 16, 96 features)", "intervals", rows,
       [&s, &b, &o, rows] { s.encode.ipe(o.ipe, {b.means, b.covs, rows}, b.features); },
       [&r, &o, rows] { ref::ipe_fwd(o.ipe, r.means, r.covs, r.o1, rows); }},
      {"gaussian_ipe_fwd (fused)", "intervals", rows,
       [&s, &b, &o, gaussian_in] { s.encode.gaussian_ipe(o.ipe, gaussian_in, b.features); },
       [&r, &o, R, N] {
         ref::gaussian_ipe_fwd(o.gaussian, o.ipe, r.origins, r.directions, r.radii, r.t_edges, r.o1, R, N);
       }},
      {"pe_fwd (view directions, 27 features)", "rays", R,
       [&s, &b, &o, R] { s.encode.pe(o.view, {b.viewdirs, R}, b.view_features); },
       [&r, &o, R] { ref::pe_fwd(o.view, r.viewdirs, r.o1, R); }},
      {"activations_fwd", "samples", rows, [&s, &b, act_in] { s.activations.fwd(act_in, {b.density, b.rgb}); },
       [&r, &o, rows] { ref::activations_fwd(o.activation, r.raw_density, r.raw_rgb, r.o1, r.o2, rows); }},
      {"activations_bwd", "samples", rows,
       [&s, &b, act_in] { s.activations.bwd(act_in, {b.density, b.rgb}, {b.d_raw_density, b.d_raw_rgb}); },
       [&r, &o, rows] {
         ref::activations_bwd(o.activation, r.raw_density, r.raw_rgb, r.density, r.rgb, r.o1, r.o2, rows);
       }},
      {"render_fwd (white)", "samples", rows,
       [&s, &b, render_in] { s.render.fwd(render_in, {b.comp, b.acc, b.distance, b.weights}); },
       [&r, &o, R, N] {
         ref::render_fwd(o.render, r.rgb, r.density, r.t_edges, r.directions, r.o1, r.o2, r.o3, r.o4, R, N);
       }},
      {"render_bwd (white)", "samples", rows,
       [&s, &b, render_in] { s.render.bwd(render_in, b.weights, {b.d_comp, nullptr}, {b.d_rgb, b.d_density}); },
       [&r, &o, R, N] {
         ref::render_bwd(o.render, r.rgb, r.density, r.t_edges, r.directions, r.weights, r.d_comp, nullptr, r.o1,
                         r.o2, R, N);
       }},
      {"render_raw_fwd (fused activations)", "samples", rows,
       [&s, &b, render_raw_in] { s.render.raw_fwd(render_raw_in, {b.comp, b.acc, b.distance, b.weights}); },
       [&r, &o, R, N] {
         ref::render_raw_fwd(o.render, o.activation, r.raw_rgb, r.raw_density, r.t_edges, r.directions, r.o1, r.o2,
                             r.o3, r.o4, R, N);
       }},
      {"render_raw_bwd (fused activations)", "samples", rows,
       [&s, &b, render_raw_in] {
         s.render.raw_bwd(render_raw_in, b.weights, {b.d_comp, nullptr}, {b.d_raw_rgb, b.d_raw_density});
       },
       [&r, &o, R, N] {
         ref::render_raw_bwd(o.render, o.activation, r.raw_rgb, r.raw_density, r.t_edges, r.directions, r.weights,
                             r.d_comp, nullptr, r.o1, r.o2, R, N);
       }},
      {"resample_fwd (α = 0.01, jittered)", "edges", R * (N + 1),
       [&s, &b, &o, R, N, key] { s.resample.fwd(o.resample, {b.t_edges, b.weights, R, N, N}, b.t_fine, key); },
       [&r, &o, R, N, key] { ref::resample_fwd(o.resample, r.t_edges, r.weights, r.o1, R, N, N, key); }},
  };
}

// Random pixels and network outputs, then one pass of the pipeline so every stage's inputs hold realistic values;
// returns the reference's copies of them.
ReferenceInputs make_inputs(ocl::Context& ctx, Stages& s, DeviceBuffers& b, const StageOptions& o, size_t R, size_t N,
                            const ops::RngKey& key) {
  const size_t rows = R * N;
  std::mt19937 rng(1);
  const data::Camera cam = blender_camera();
  const std::vector<float> cameras = data::pack_cameras({cam});
  ReferenceInputs r;
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

StageTiming time_stage(ocl::Context& ctx, const Stage& stage, const KernelBenchOptions& options) {
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
  if (options.reference_reps > 0) {
    t.reference_seconds = 1e300;
    for (size_t k = 0; k < options.reference_reps; ++k) {
      t.reference_seconds = std::min(t.reference_seconds, time_call(stage.reference));
    }
  }
  return t;
}

}  // namespace

KernelBenchResult run_kernel_bench(ocl::Context& ctx, const KernelBenchOptions& options, const ProgressFn& progress) {
  if (options.rays == 0 || options.samples == 0 || options.reps == 0) {
    throw Error("kernel benchmark: rays, samples and reps must be at least 1");
  }
  const size_t R = options.rays, N = options.samples;
  KernelBenchResult result;
  result.options = options;
  const StageOptions stage_options;
  Stages stages = build_stages(ctx, stage_options, result.builds);
  DeviceBuffers buffers(ctx, R, N, stage_options);
  const ops::RngKey key{20200823, 1, 0};
  ReferenceInputs reference = make_inputs(ctx, stages, buffers, stage_options, R, N, key);
  const std::vector<Stage> list = stage_list(stages, buffers, reference, stage_options, R, N, key);
  for (size_t i = 0; i < list.size(); ++i) {
    if (progress) progress(list[i].name, i, list.size());
    result.stages.push_back(time_stage(ctx, list[i], options));
  }
  if (progress) progress("done", list.size(), list.size());
  return result;
}

}  // namespace mipnerf::bench
