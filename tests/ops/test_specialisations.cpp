// Every compile-time specialisation of the ray-math kernels is built and run against the reference: ray shape
// (cone/cylinder), background (none/black/white), view dependence (on/off), sub-pixel jitter, disparity sampling,
// and the density activations. The list below is the registry: a new option value must be added here.
#include <doctest/doctest.h>

#include <functional>

#include "core/camera.hpp"
#include "kernel_checks.hpp"
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
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

// The precise float32 bounds are the business of each stage's own tests; here a specialisation that builds but
// computes the wrong thing must fail: 1e-4 of the array's largest magnitude (a wrong branch is off by O(1)).
void check_matches(const char* what, const std::vector<float>& device, const std::vector<double>& reference) {
  double scale = 1e-30;
  for (double v : reference) scale = std::max(scale, std::abs(v));
  MIPNERF_CHECK_CLOSE(what, device, reference, [scale](size_t) { return 1e-4 * scale; });
}

// A small forward-facing scene (valid for both ray shapes): 3 cameras, 256 rays.
struct SmallScene {
  std::vector<float> cameras;
  std::vector<uint32_t> camera_ids, pixel_ids;
  SmallScene() {
    std::vector<Camera> cams(3);
    for (size_t c = 0; c < cams.size(); ++c) {
      cams[c].width_px = 40 + 10 * c;
      cams[c].height_px = 30;
      cams[c].focal_x_px = cams[c].focal_y_px = 50;
      cams[c].center_x_px = cams[c].width_px / 2.0;
      cams[c].center_y_px = 15;
      cams[c].camera_to_world[3] = 0.1 * c;
      cams[c].camera_to_world[11] = -0.2 * c;
    }
    cameras = pack_cameras(cams);
    for (uint32_t i = 0; i < 256; ++i) {
      camera_ids.push_back(i % 3);
      pixel_ids.push_back((i * 37) % (30 * 40));
    }
  }
};

void run_rays(const RaysOptions& options) {
  auto& ctx = test::test_context();
  const SmallScene s;
  const size_t n = s.camera_ids.size();
  auto cameras = test::upload(ctx, s.cameras, "cameras");
  auto ids = test::upload(ctx, s.camera_ids, "camera_ids"), pixels = test::upload(ctx, s.pixel_ids, "pixel_ids");
  auto o = test::filled(ctx, 3 * n, 7.0f, "origins"), d = test::filled(ctx, 3 * n, 7.0f, "directions");
  auto v = test::filled(ctx, 3 * n, 7.0f, "viewdirs"), r = test::filled(ctx, n, 7.0f, "radii");
  auto near = test::filled(ctx, n, 7.0f, "near"), far = test::filled(ctx, n, 7.0f, "far");
  auto lossmult = test::filled(ctx, n, 7.0f, "lossmult");
  const RngKey key{3, 4, 5};
  ops::Rays(ctx, options).fwd({cameras, ids, pixels, n}, {o, d, v, r, near, far, lossmult}, key);
  std::vector<double> ro, rd, rv, rr, rn, rf, rl;
  ref::rays_fwd(options, test::to_double(s.cameras), s.camera_ids, s.pixel_ids, ro, rd, rv, rr, rn, rf, rl, n, 3, key);
  check_matches("origins", o.download(ctx), ro);
  check_matches("directions", d.download(ctx), rd);
  check_matches("radii", r.download(ctx), rr);
  if (options.view_dependence) {
    check_matches("viewdirs", v.download(ctx), rv);
  } else {
    for (float x : v.download(ctx)) REQUIRE(x == 7.0f);
  }
}

// Rays of 64 samples over [2, 6] with a simple density profile, for the sampling/Gaussian/render stages.
struct SmallRays {
  size_t n_rays = 64, n = 32;
  std::vector<float> origins, directions, radii, near, far, t_edges, density, rgb, weights, d_comp, d_acc;
  SmallRays() {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (size_t ray = 0; ray < n_rays; ++ray) {
      for (int a = 0; a < 3; ++a) {
        origins.push_back(unit(rng) - 0.5f);
        directions.push_back(a == 2 ? -1.0f : 0.5f * (unit(rng) - 0.5f));
        d_comp.push_back(unit(rng) - 0.5f);
      }
      radii.push_back(1e-3f);
      near.push_back(2.0f);
      far.push_back(6.0f);
      d_acc.push_back(unit(rng) - 0.5f);
      for (size_t k = 0; k <= n; ++k) t_edges.push_back(2.0f + 4.0f * k / n + 0.01f * unit(rng));
      for (size_t i = 0; i < n; ++i) {
        density.push_back(4.0f * unit(rng) - 1.0f);  // raw values: both signs, for relu and softplus
        weights.push_back(unit(rng) < 0.3f ? unit(rng) : 0.0f);
        for (int c = 0; c < 3; ++c) rgb.push_back(4.0f * unit(rng) - 2.0f);
      }
    }
  }
};

void run_sample(const SampleOptions& options) {
  auto& ctx = test::test_context();
  const SmallRays s;
  auto near = test::upload(ctx, s.near, "near"), far = test::upload(ctx, s.far, "far");
  ocl::DeviceArray<float> t(ctx, s.n_rays * (s.n + 1), "t_edges");
  const RngKey key{1, 2, 3};
  ops::Sample(ctx, options).stratified({near, far, s.n_rays, s.n}, t, key);
  std::vector<double> expected;
  ref::sample_stratified_fwd(options, test::to_double(s.near), test::to_double(s.far), expected, s.n_rays, s.n, key);
  check_matches("t_edges", t.download(ctx), expected);
}

void run_resample(const ResampleOptions& options) {
  auto& ctx = test::test_context();
  const SmallRays s;
  auto t = test::upload(ctx, s.t_edges, "t_edges"), w = test::upload(ctx, s.weights, "weights");
  ocl::DeviceArray<float> out(ctx, s.n_rays * (s.n + 1), "t_new");
  const RngKey key{1, 2, 3};
  ops::Resample(ctx).fwd(options, {t, w, s.n_rays, s.n, s.n}, out, key);
  std::vector<double> expected;
  ref::resample_fwd(options, test::to_double(s.t_edges), test::to_double(s.weights), expected, s.n_rays, s.n, s.n, key);
  check_matches("t_new", out.download(ctx), expected);
}

void run_gaussian_and_encode(const GaussianOptions& options) {
  auto& ctx = test::test_context();
  const SmallRays s;
  auto o = test::upload(ctx, s.origins, "origins"), d = test::upload(ctx, s.directions, "directions");
  auto r = test::upload(ctx, s.radii, "radii"), t = test::upload(ctx, s.t_edges, "t_edges");
  const size_t rows = s.n_rays * s.n;
  ocl::DeviceArray<float> means(ctx, 3 * rows, "means"), covs(ctx, 3 * rows, "covs");
  const ops::GaussianInputs in{o, d, r, t, s.n_rays, s.n};
  ops::Gaussian(ctx, options).fwd(in, {means, covs});
  std::vector<double> rm, rc;
  ref::gaussian_fwd(options, test::to_double(s.origins), test::to_double(s.directions), test::to_double(s.radii),
                    test::to_double(s.t_edges), rm, rc, s.n_rays, s.n);
  check_matches("means", means.download(ctx), rm);
  check_matches("covs", covs.download(ctx), rc);
  EncodingOptions encoding;
  encoding.max_deg = 8;  // low degrees: the 1e-4 check stays meaningful for features of these means
  ocl::DeviceArray<float> features(ctx, rows * encoding.ipe_width(), "features");
  ops::Encode(ctx, options).gaussian_ipe(encoding, in, features);
  std::vector<double> rf;
  ref::gaussian_ipe_fwd(options, encoding, test::to_double(s.origins), test::to_double(s.directions),
                        test::to_double(s.radii), test::to_double(s.t_edges), rf, s.n_rays, s.n);
  check_matches("gaussian_ipe features", features.download(ctx), rf);
}

void run_render(const RenderOptions& options, const ActivationOptions& activation) {
  auto& ctx = test::test_context();
  const SmallRays s;
  const size_t rows = s.n_rays * s.n;
  auto raw_rgb = test::upload(ctx, s.rgb, "raw_rgb"), raw_density = test::upload(ctx, s.density, "raw_density");
  auto t = test::upload(ctx, s.t_edges, "t_edges"), d = test::upload(ctx, s.directions, "directions");
  auto d_comp = test::upload(ctx, s.d_comp, "d_comp_rgb"), d_acc = test::upload(ctx, s.d_acc, "d_acc");
  ocl::DeviceArray<float> comp(ctx, 3 * s.n_rays, "comp_rgb"), acc(ctx, s.n_rays, "acc");
  ocl::DeviceArray<float> distance(ctx, s.n_rays, "distance"), weights(ctx, rows, "weights");
  ocl::DeviceArray<float> d_raw_rgb(ctx, 3 * rows, "d_raw_rgb"), d_raw_density(ctx, rows, "d_raw_density");
  // The activations stage on its own, then the fused render on raw values (which exercises both sets of options).
  ocl::DeviceArray<float> density(ctx, rows, "density"), rgb(ctx, 3 * rows, "rgb");
  ops::Activations(ctx, activation).fwd({raw_density, raw_rgb, rows}, {density, rgb});
  std::vector<double> ref_density, ref_rgb;
  ref::activations_fwd(activation, test::to_double(s.density), test::to_double(s.rgb), ref_density, ref_rgb, rows);
  check_matches("density", density.download(ctx), ref_density);
  check_matches("rgb", rgb.download(ctx), ref_rgb);
  ops::Render render(ctx, options, activation);
  const ops::RenderInputs in{raw_rgb, raw_density, t, d, s.n_rays, s.n};
  render.raw_fwd(in, {comp, acc, distance, weights});
  render.raw_bwd(in, weights, {d_comp, &d_acc}, {d_raw_rgb, d_raw_density});
  std::vector<double> rc, ra, rd, rw, rgr, rgd;
  const auto d_acc_ref = test::to_double(s.d_acc);
  ref::render_raw_fwd(options, activation, test::to_double(s.rgb), test::to_double(s.density),
                      test::to_double(s.t_edges), test::to_double(s.directions), rc, ra, rd, rw, s.n_rays, s.n);
  ref::render_raw_bwd(options, activation, test::to_double(s.rgb), test::to_double(s.density),
                      test::to_double(s.t_edges), test::to_double(s.directions), rw, test::to_double(s.d_comp),
                      &d_acc_ref, rgr, rgd, s.n_rays, s.n);
  check_matches("comp_rgb", comp.download(ctx), rc);
  check_matches("acc", acc.download(ctx), ra);
  check_matches("distance", distance.download(ctx), rd);
  check_matches("d_raw_rgb", d_raw_rgb.download(ctx), rgr);
  check_matches("d_raw_density", d_raw_density.download(ctx), rgd);
}

struct Specialisation {
  std::string name;
  std::function<void()> run;
};

std::vector<Specialisation> all_specialisations() {
  std::vector<Specialisation> list;
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    const std::string shape_name = shape == RayShape::cone ? "cone" : "cylinder";
    for (bool view : {true, false}) {
      for (bool jitter : {false, true}) {
        RaysOptions options;
        options.ray_shape = shape;
        options.view_dependence = view;
        options.jitter_subpixel = jitter;
        list.push_back({"rays " + shape_name + (view ? " view" : " no-view") + (jitter ? " jitter" : ""),
                        [options] { run_rays(options); }});
      }
    }
    list.push_back({"gaussian+encode " + shape_name, [shape] { run_gaussian_and_encode({shape}); }});
  }
  for (bool lindisp : {false, true}) {
    for (bool randomized : {false, true}) {
      list.push_back({std::string("sample") + (lindisp ? " lindisp" : "") + (randomized ? " jitter" : ""), [=] {
                        run_sample({lindisp, randomized});
                      }});
    }
  }
  for (bool blur : {true, false}) {
    list.push_back({std::string("resample") + (blur ? " mipnerf" : " nerf"), [blur] {
                      run_resample({blur ? 0.01f : 0.0f, blur, true});
                    }});
  }
  ActivationOptions nerf;
  nerf.density = DensityActivation::relu;
  nerf.density_bias = 0.0f;
  nerf.rgb_padding = 0.0f;
  for (auto background : {Background::none, Background::black, Background::white}) {
    for (const auto& activation : {ActivationOptions{}, nerf}) {
      list.push_back({"render background " + std::to_string(static_cast<int>(background)) +
                          (activation.density == DensityActivation::relu ? " relu" : " softplus"),
                      [=] { run_render({background}, activation); }});
    }
  }
  return list;
}

}  // namespace

TEST_CASE("specialisations: every ray shape, background, view dependence and activation builds and runs") {
  const auto list = all_specialisations();
  CHECK(list.size() == 8 + 2 + 4 + 2 + 6);
  for (const auto& s : list) {
    INFO("specialisation: " << s.name);
    s.run();
  }
}
