// bench_kernels: throughput of each ray-math stage (rays … activations) on one OpenCL device, beside the
// double-precision CPU reference (host/ref, single thread) on the same inputs, in one run.
//
//   bench_kernels [--device SELECTOR] [--rays R] [--samples N] [--reps K]
//
// SELECTOR is --device's rule (index or part of the name; MIPNERF_DEVICE is read when the flag is absent).
// Defaults are the paper's batch: R = 4096 rays, N = 128 samples per ray. Each stage is called once to warm up
// (the program was built before, timed separately as "first build"; PoCL's on-disk cache may serve it — run with
// POCL_KERNEL_CACHE=0 for a cold compile), then K timed calls, each followed by clFinish: wall time per call, so
// launch overhead is included as the host graph sees it. Throughput uses the best of the K calls (robust to other
// processes on a shared machine); the median is shown beside it. The CPU reference runs twice, best kept.
// Prints markdown.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
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

using namespace mipnerf;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

struct Args {
  std::string device;
  size_t rays = 4096, samples = 128, reps = 10;
};

Args parse(int argc, char** argv) {
  Args args;
  if (const char* env = std::getenv("MIPNERF_DEVICE")) args.device = env;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw Error("bench_kernels: " + flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--device") {
      args.device = value;
    } else if (flag == "--rays") {
      args.rays = std::stoul(value);
    } else if (flag == "--samples") {
      args.samples = std::stoul(value);
    } else if (flag == "--reps") {
      args.reps = std::max<size_t>(1, std::stoul(value));
    } else {
      throw Error("bench_kernels: unknown flag " + flag + " (use --device, --rays, --samples, --reps)");
    }
  }
  return args;
}

std::vector<double> download_double(ocl::Context& ctx, const ocl::DeviceArray<float>& array) {
  const auto values = array.download(ctx);
  return {values.begin(), values.end()};
}

struct Row {
  std::string stage, unit;
  size_t items;
  double device_best_s, device_median_s, ref_s;
};

}  // namespace

int main(int argc, char** argv) try {
  const Args args = parse(argc, argv);
  auto devices = ocl::list_devices();
  ocl::Context ctx(ocl::choose_device(devices, args.device));
  const size_t R = args.rays, N = args.samples, rows = R * N;

  // --- first builds (one program per stage and specialisation) ---
  std::vector<std::pair<std::string, double>> builds;
  const auto timed_build = [&](const std::string& name, auto make) {
    const auto start = Clock::now();
    auto stage = make();
    builds.push_back({name, seconds_since(start)});
    return stage;
  };
  const ops::RaysOptions rays_options;
  const ops::SampleOptions sample_options{false, true};
  const ops::ResampleOptions resample_options;  // paper: α = 0.01, blur, jittered
  const ops::GaussianOptions gaussian_options;
  const ops::RenderOptions render_options;  // white background (Blender)
  const ops::ActivationOptions activation_options;
  ops::EncodingOptions ipe_options;   // degrees 0..15: 96 features
  ops::EncodingOptions view_options;  // degrees 0..3 + identity: 27 features
  view_options.max_deg = 4;
  view_options.append_identity = true;
  auto rays = timed_build("rays.cl", [&] { return ops::Rays(ctx, rays_options); });
  auto sample = timed_build("sample.cl", [&] { return ops::Sample(ctx, sample_options); });
  auto resample = timed_build("resample.cl", [&] { return ops::Resample(ctx); });
  auto gaussian = timed_build("gaussian.cl", [&] { return ops::Gaussian(ctx, gaussian_options); });
  auto encode = timed_build("gaussian.cl + encode.cl", [&] { return ops::Encode(ctx, gaussian_options); });
  auto activations = timed_build("activations.cl", [&] { return ops::Activations(ctx, activation_options); });
  auto render =
      timed_build("activations.cl + render.cl", [&] { return ops::Render(ctx, render_options, activation_options); });

  // --- inputs: a 800×800 Blender-like camera, R random pixels, then the pipeline's own outputs ---
  std::mt19937 rng(1);
  data::Camera cam;
  cam.width_px = cam.height_px = 800;
  cam.focal_x_px = cam.focal_y_px = 1111.0;
  cam.center_x_px = cam.center_y_px = 400.0;
  cam.camera_to_world = {-0.9999, 0.0042, -0.0134, -0.0538, -0.0140, -0.2997,
                         0.9539,  3.8455, 0.0,     0.9540,  0.2997,  1.2081};
  const std::vector<float> cameras_host = data::pack_cameras({cam});
  std::vector<uint32_t> camera_ids(R, 0), pixel_ids(R);
  for (auto& p : pixel_ids) p = static_cast<uint32_t>(rng() % (800 * 800));
  ocl::DeviceArray<float> cameras(ctx, cameras_host.size(), "cameras");
  cameras.upload(ctx, cameras_host);
  ocl::DeviceArray<uint32_t> ids(ctx, R, "camera_ids"), pixels(ctx, R, "pixel_ids");
  ids.upload(ctx, camera_ids);
  pixels.upload(ctx, pixel_ids);
  ocl::DeviceArray<float> origins(ctx, 3 * R, "origins"), directions(ctx, 3 * R, "directions");
  ocl::DeviceArray<float> viewdirs(ctx, 3 * R, "viewdirs"), radii(ctx, R, "radii"), near(ctx, R, "near");
  ocl::DeviceArray<float> far(ctx, R, "far"), lossmult(ctx, R, "lossmult");
  ocl::DeviceArray<float> t_edges(ctx, R * (N + 1), "t_edges"), t_fine(ctx, R * (N + 1), "t_fine");
  ocl::DeviceArray<float> means(ctx, 3 * rows, "means"), covs(ctx, 3 * rows, "covs");
  ocl::DeviceArray<float> features(ctx, rows * ipe_options.ipe_width(), "ipe_features");
  ocl::DeviceArray<float> view_features(ctx, R * view_options.pe_width(), "view_encoding");
  ocl::DeviceArray<float> raw_density(ctx, rows, "raw_density"), raw_rgb(ctx, 3 * rows, "raw_rgb");
  ocl::DeviceArray<float> density(ctx, rows, "density"), rgb(ctx, 3 * rows, "rgb");
  ocl::DeviceArray<float> comp(ctx, 3 * R, "comp_rgb"), acc(ctx, R, "acc"), distance(ctx, R, "distance");
  ocl::DeviceArray<float> weights(ctx, rows, "weights"), d_comp(ctx, 3 * R, "d_comp_rgb");
  ocl::DeviceArray<float> d_rgb(ctx, 3 * rows, "d_rgb"), d_density(ctx, rows, "d_density");
  ocl::DeviceArray<float> d_raw_rgb(ctx, 3 * rows, "d_raw_rgb"), d_raw_density(ctx, rows, "d_raw_density");
  {
    std::normal_distribution<float> normal(0.0f, 2.0f);
    std::vector<float> host(3 * rows);
    for (auto& v : host) v = normal(rng);
    raw_rgb.upload(ctx, host);
    host.resize(rows);
    for (auto& v : host) v = normal(rng);
    raw_density.upload(ctx, host);
    host.resize(3 * R);
    for (auto& v : host) v = 0.1f * normal(rng);
    d_comp.upload(ctx, host);
  }
  const ops::RngKey key{20200823, 1, 0};
  const ops::RaysInputs rays_in{cameras, ids, pixels, R};
  const ops::RaysOutputs rays_out{origins, directions, viewdirs, radii, near, far, lossmult};
  const ops::GaussianInputs gaussian_in{origins, directions, radii, t_edges, R, N};
  const ops::ActivationInputs act_in{raw_density, raw_rgb, rows};
  const ops::RenderInputs render_in{rgb, density, t_edges, directions, R, N};
  const ops::RenderInputs render_raw_in{raw_rgb, raw_density, t_edges, directions, R, N};
  // One pass of the pipeline so every stage's inputs hold realistic values.
  rays.fwd(rays_in, rays_out, key);
  sample.stratified({near, far, R, N}, t_edges, key);
  activations.fwd(act_in, {density, rgb});
  render.fwd(render_in, {comp, acc, distance, weights});
  ctx.finish();

  // The reference's inputs, in double.
  const auto cameras_d = std::vector<double>(cameras_host.begin(), cameras_host.end());
  const auto origins_d = download_double(ctx, origins), directions_d = download_double(ctx, directions);
  const auto radii_d = download_double(ctx, radii), near_d = download_double(ctx, near);
  const auto far_d = download_double(ctx, far), viewdirs_d = download_double(ctx, viewdirs);
  const auto t_edges_d = download_double(ctx, t_edges), weights_d = download_double(ctx, weights);
  const auto raw_density_d = download_double(ctx, raw_density), raw_rgb_d = download_double(ctx, raw_rgb);
  const auto density_d = download_double(ctx, density), rgb_d = download_double(ctx, rgb);
  const auto d_comp_d = download_double(ctx, d_comp);
  gaussian.fwd(gaussian_in, {means, covs});
  const auto means_d = download_double(ctx, means), covs_d = download_double(ctx, covs);
  std::vector<double> o1, o2, o3, o4, o5, o6, o7, o8;  // reference outputs (discarded)

  struct Stage {
    std::string name, unit;
    size_t items;
    std::function<void()> device, reference;
  };
  const std::vector<Stage> stages = {
      {"rays_fwd (cone)", "rays", R, [&] { rays.fwd(rays_in, rays_out, key); },
       [&] { ref::rays_fwd(rays_options, cameras_d, camera_ids, pixel_ids, o1, o2, o3, o4, o5, o6, o7, R, 1, key); }},
      {"sample_stratified_fwd (jittered)", "edges", R * (N + 1),
       [&] {
         sample.stratified({near, far, R, N}, t_edges, key);
       },
       [&] { ref::sample_stratified_fwd(sample_options, near_d, far_d, o1, R, N, key); }},
      {"gaussian_fwd (cone)", "intervals", rows,
       [&] {
         gaussian.fwd(gaussian_in, {means, covs});
       },
       [&] { ref::gaussian_fwd(gaussian_options, origins_d, directions_d, radii_d, t_edges_d, o1, o2, R, N); }},
      {"ipe_fwd (L = 16, 96 features)", "intervals", rows,
       [&] {
         encode.ipe(ipe_options, {means, covs, rows}, features);
       },
       [&] { ref::ipe_fwd(ipe_options, means_d, covs_d, o1, rows); }},
      {"gaussian_ipe_fwd (fused)", "intervals", rows, [&] { encode.gaussian_ipe(ipe_options, gaussian_in, features); },
       [&] {
         ref::gaussian_ipe_fwd(gaussian_options, ipe_options, origins_d, directions_d, radii_d, t_edges_d, o1, R, N);
       }},
      {"pe_fwd (view directions, 27 features)", "rays", R,
       [&] {
         encode.pe(view_options, {viewdirs, R}, view_features);
       },
       [&] { ref::pe_fwd(view_options, viewdirs_d, o1, R); }},
      {"activations_fwd", "samples", rows,
       [&] {
         activations.fwd(act_in, {density, rgb});
       },
       [&] { ref::activations_fwd(activation_options, raw_density_d, raw_rgb_d, o1, o2, rows); }},
      {"activations_bwd", "samples", rows,
       [&] {
         activations.bwd(act_in, {density, rgb}, {d_raw_density, d_raw_rgb});
       },
       [&] { ref::activations_bwd(activation_options, raw_density_d, raw_rgb_d, density_d, rgb_d, o1, o2, rows); }},
      {"render_fwd (white)", "samples", rows,
       [&] {
         render.fwd(render_in, {comp, acc, distance, weights});
       },
       [&] { ref::render_fwd(render_options, rgb_d, density_d, t_edges_d, directions_d, o1, o2, o3, o4, R, N); }},
      {"render_bwd (white)", "samples", rows,
       [&] {
         render.bwd(render_in, weights, {d_comp, nullptr}, {d_rgb, d_density});
       },
       [&] {
         ref::render_bwd(render_options, rgb_d, density_d, t_edges_d, directions_d, weights_d, d_comp_d, nullptr, o1,
                         o2, R, N);
       }},
      {"render_raw_fwd (fused activations)", "samples", rows,
       [&] {
         render.raw_fwd(render_raw_in, {comp, acc, distance, weights});
       },
       [&] {
         ref::render_raw_fwd(render_options, activation_options, raw_rgb_d, raw_density_d, t_edges_d, directions_d, o1,
                             o2, o3, o4, R, N);
       }},
      {"render_raw_bwd (fused activations)", "samples", rows,
       [&] {
         render.raw_bwd(render_raw_in, weights, {d_comp, nullptr}, {d_raw_rgb, d_raw_density});
       },
       [&] {
         ref::render_raw_bwd(render_options, activation_options, raw_rgb_d, raw_density_d, t_edges_d, directions_d,
                             weights_d, d_comp_d, nullptr, o1, o2, R, N);
       }},
      {"resample_fwd (α = 0.01, jittered)", "edges", R * (N + 1),
       [&] {
         resample.fwd(resample_options, {t_edges, weights, R, N, N}, t_fine, key);
       },
       [&] { ref::resample_fwd(resample_options, t_edges_d, weights_d, o1, R, N, N, key); }},
  };

  std::vector<Row> table;
  for (const auto& stage : stages) {
    stage.device();  // warm-up: first launch, buffers touched
    ctx.finish();
    std::vector<double> times;
    for (size_t k = 0; k < args.reps; ++k) {
      const auto start = Clock::now();
      stage.device();
      ctx.finish();
      times.push_back(seconds_since(start));
    }
    std::sort(times.begin(), times.end());
    double ref_s = 1e30;
    for (int k = 0; k < 2; ++k) {
      const auto ref_start = Clock::now();
      stage.reference();
      ref_s = std::min(ref_s, seconds_since(ref_start));
    }
    table.push_back({stage.name, stage.unit, stage.items, times.front(), times[times.size() / 2], ref_s});
  }

  const auto& info = ctx.device_info();
  std::printf("## Ray-math kernels: %s\n\n", info.name.c_str());
  std::printf(
      "Device: %s (%s, %s), %u compute units. Batch: %zu rays x %zu samples. Device: best and median of %zu "
      "calls after a warm-up, wall time with clFinish; items/s from the best. CPU reference: host/ref in "
      "double, one thread, best of 2 calls.\n\n",
      info.name.c_str(), info.platform_name.c_str(), info.type_name().c_str(), info.compute_units, R, N, args.reps);
  std::printf(
      "| stage | items | device ms best (median) | device items/s | CPU ref ms | CPU ref items/s | "
      "device / ref |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& row : table) {
    std::printf("| %s | %zu %s | %.3f (%.3f) | %.3g | %.1f | %.3g | %.1fx |\n", row.stage.c_str(), row.items,
                row.unit.c_str(), 1e3 * row.device_best_s, 1e3 * row.device_median_s, row.items / row.device_best_s,
                1e3 * row.ref_s, row.items / row.ref_s, row.ref_s / row.device_best_s);
  }
  std::printf(
      "\nFirst build of each program: clBuildProgram, served from PoCL's on-disk cache when it holds the program "
      "(POCL_KERNEL_CACHE=0 for a cold compile); PoCL generates each kernel's work-group code at its first "
      "launch, which the warm-up call absorbs.\n\n");
  std::printf("| program | first build s |\n|---|---:|\n");
  for (const auto& [name, s] : builds) std::printf("| %s | %.2f |\n", name.c_str(), s);
  return 0;
} catch (const mipnerf::Error& e) {
  std::fprintf(stderr, "bench_kernels: %s\n", e.what());
  return 1;
}
