// host/bench on tiny sizes: every measurement returns positive, finite figures of the right shape (figures are
// measured, never compared with a speed), the time box and the step counts behave, bench.json carries what a record
// needs (device, driver, OpenCL C and CLBlast versions, date, settings), and `mipnerf-cl bench --quick` writes
// bench.json and bench.md through the real executable.
#include <doctest/doctest.h>

#include <clblast.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <unordered_map>

#include "bench/gemm_bench.hpp"
#include "bench/kernel_bench.hpp"
#include "bench/machine_probe.hpp"
#include "kernel_reference.hpp"
#include "bench/preset_bench.hpp"
#include "bench/report.hpp"
#include "eval/render_setup.hpp"
#include "eval/report.hpp"
#include "io/json.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/cpu_sgemm.hpp"
#include "gemm/gemm_backend.hpp"
#include "gemm/gemm_tuning.hpp"
#include "ops/stage_list.hpp"
#include "support/temp_scene.hpp"
#include "support/mlp_fixtures.hpp"
#include "bench/stage_report.hpp"
#include "graph/stage_traffic.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }

fs::path bench_temp(const std::string& name) { return test::temp_path("bench-" + name); }

// A 16×16 procedural scene with 4 training views: trains and renders in well under a second per step.
const std::string& tiny_scene() {
  static const std::string path = test::write_temp_scene("bench-scene", {16, 4, 1, 1, 2});
  return path;
}

bench::KernelBenchOptions tiny_kernel_options() {
  bench::KernelBenchOptions o;
  o.rays = 32;
  o.samples = 8;
  o.reps = 2;
  o.reference_reps = 1;
  return o;
}

bench::GemmBenchOptions tiny_gemm_options() {
  bench::GemmBenchOptions o;
  o.widths = {8, 16};
  o.rows = 64;
  o.reps = 2;
  o.rounds = 2;
  return o;
}

// A "tuned" set that exercises installing and switching without a new CLBlast compile: CLBlast's own value of the
// direct/indirect switch (every product here is small enough for the direct kernel, already built by the defaults).
gemm::GemmTuning same_as_defaults_tuning() {
  auto& ctx = test::test_context();
  std::unordered_map<std::string, size_t> values;
  gemm::check_clblast(clblast::RetrieveParameters(ctx.raw_device(), "GemmRoutine", clblast::Precision::kSingle, values),
                     "RetrieveParameters");
  gemm::GemmTuning t;
  t.device_name = ctx.device_info().name;
  t.driver_version = ctx.device_info().driver_version;
  t.clblast_version = gemm::clblast_version();
  t.common["GemmRoutine"] = {values.begin(), values.end()};
  return t;
}

bench::PresetBenchOptions tiny_preset_options(const std::string& name) {
  bench::PresetBenchOptions o;
  o.preset = "tiny";
  o.settings = {{"batch_size", "32"}};
  o.data_path = tiny_scene();
  o.work_dir = bench_temp(name).string();
  fs::remove_all(o.work_dir);
  o.warm_steps = 2;
  o.render_width = 8;
  o.render_height = 6;
  o.render_reps = 2;
  return o;
}

// Results shared by the tests that need a measurement (each made once per process).
const bench::KernelBenchResult& kernel_result() {
  static const auto r =
      bench::run_kernel_bench(test::test_context(), tiny_kernel_options(), {}, bench::reference_stages());
  return r;
}

const bench::GemmBenchResult& gemm_result() {
  static const auto r = [] {
    auto configs = bench::clblast_configs(same_as_defaults_tuning());
    // A host configuration, as bench_gemm adds OpenBLAS: a plain loop on the host copies.
    configs.push_back({"host loop", std::nullopt, [](const bench::GemmProduct& p, bench::GemmOperands& o) {
                         return bench::time_call([&] {
                           for (size_t i = 0; i < p.shape.m * p.shape.n; ++i) o.c[i] = 0.5f * o.a[i % o.a.size()];
                         });
                       }});
    return bench::run_gemm_bench(test::test_context(), tiny_gemm_options(), configs);
  }();
  return r;
}

const bench::PresetBenchResult& preset_result() {
  static const auto r = [] {
    gemm::clear_gemm_tuning(test::test_context());
    const auto options = tiny_preset_options("preset");
    auto result = bench::run_preset_bench(test::test_context(), options);
    fs::remove_all(options.work_dir);
    return result;
  }();
  return r;
}

}  // namespace

TEST_CASE("bench timings: best, upper median and mean, zero when empty, and the peak RSS") {
  bench::Timings t;
  CHECK(t.best() == 0.0);
  CHECK(t.median() == 0.0);
  for (double s : {0.3, 0.1, 0.4, 0.2}) t.add(s);
  CHECK(t.best() == doctest::Approx(0.1));
  CHECK(t.median() == doctest::Approx(0.3));  // sorted[n/2] of 0.1 0.2 0.3 0.4
  CHECK(t.mean() == doctest::Approx(0.25));
  CHECK(bench::peak_rss_bytes() > 0);
}

TEST_CASE("bench kernels: every ray-math stage gives positive finite timings beside the reference") {
  const auto& r = kernel_result();
  // One program per stage file and specialisation, one row per kernel variant (13, as in bench/results).
  REQUIRE(r.builds.size() == 7);
  REQUIRE(r.stages.size() == 13);
  std::set<std::string> names;
  for (const auto& b : r.builds) CHECK(positive_finite(b.seconds));
  for (const auto& s : r.stages) {
    INFO(s.stage);
    names.insert(s.stage);
    CHECK(s.items >= 32);
    CHECK(s.device.count() == 2);
    CHECK(positive_finite(s.first_call_seconds));
    CHECK(positive_finite(s.device.best()));
    CHECK(s.device.median() >= s.device.best());
    CHECK(positive_finite(s.items_per_second()));
    CHECK(positive_finite(s.reference_items_per_second()));
  }
  CHECK(names.size() == r.stages.size());
  for (const char* kernel : {"rays_fwd", "sample_stratified_fwd", "resample_fwd", "gaussian_fwd", "ipe_fwd", "pe_fwd",
                             "gaussian_ipe_fwd", "activations_fwd", "activations_bwd", "render_fwd", "render_bwd",
                             "render_raw_fwd", "render_raw_bwd"}) {
    bool found = false;
    for (const auto& n : names) found = found || n.rfind(std::string(kernel) + " ", 0) == 0 || n == kernel;
    CHECK_MESSAGE(found, kernel);
  }
}

TEST_CASE("bench kernels: builds and rows are the stage list's, and the reference knows exactly its kernels") {
  const auto& r = kernel_result();
  const auto o = tiny_kernel_options();
  std::vector<std::string> programs, kernels;
  std::vector<const ops::StageKernel*> listed;
  for (const auto& stage : ops::ray_math_stages()) {
    programs.push_back(stage.program);
    for (const auto& kernel : stage.kernels) {
      listed.push_back(&kernel);
      kernels.push_back(kernel.kernel);
    }
  }
  REQUIRE(r.builds.size() == programs.size());
  for (size_t i = 0; i < programs.size(); ++i) CHECK(r.builds[i].program == programs[i]);
  REQUIRE(r.stages.size() == listed.size());
  for (size_t i = 0; i < listed.size(); ++i) {
    INFO(listed[i]->row());
    CHECK(r.stages[i].stage == listed[i]->row());
    CHECK(r.stages[i].unit == ops::unit_name(listed[i]->unit));
    CHECK(r.stages[i].items == ops::items(listed[i]->unit, o.rays, o.samples));
  }
  // The rows of bench/results, in their order: the list reproduces them.
  const std::vector<std::string> committed = {
      "rays_fwd (cone)", "sample_stratified_fwd (jittered)", "gaussian_fwd (cone)", "ipe_fwd (L = 16, 96 features)",
      "gaussian_ipe_fwd (fused)", "pe_fwd (view directions, 27 features)", "activations_fwd", "activations_bwd",
      "render_fwd (white)", "render_bwd (white)", "render_raw_fwd (fused activations)",
      "render_raw_bwd (fused activations)", "resample_fwd (α = 0.01, jittered)"};
  for (size_t i = 0; i < committed.size() && i < r.stages.size(); ++i) CHECK(r.stages[i].stage == committed[i]);
  // The CPU reference has a call for every listed kernel (its switch over KernelId is complete: -Werror=switch), and
  // refuses an id outside the list.
  bench::KernelBenchInputs inputs;
  for (const auto* kernel : listed) CHECK(bench::reference_stages()(kernel->id, ops::RayMathOptions{}, inputs, 1, 1, RngKey{}));
  CHECK_THROWS_WITH_AS(bench::reference_stages()(static_cast<ops::KernelId>(999), ops::RayMathOptions{}, inputs, 1, 1,
                                                 RngKey{}),
                       doctest::Contains("not in the stage list"), Error);
}

TEST_CASE("bench gemm: forward, backward data and backward weights per width, every configuration, defaults after") {
  const auto& r = gemm_result();
  REQUIRE(r.products.size() == 6);
  CHECK(r.products[0].kind == "forward");
  CHECK(r.products[0].shape.m == 64);
  CHECK(r.products[0].shape.n == 8);
  CHECK(r.products[1].shape.transpose_b);
  CHECK(r.products[2].shape.transpose_a);
  CHECK(r.products[2].shape.k == 64);  // the weight gradient sums over the rows
  CHECK(r.products[5].shape.m == 16);
  REQUIRE(r.series.size() == 3);
  CHECK(r.series[0].name == "CLBlast default");
  CHECK(r.series[1].name == "CLBlast tuned");
  for (const auto& s : r.series) {
    INFO(s.name);
    REQUIRE(s.first_call_seconds.size() == r.products.size());
    for (size_t i = 0; i < r.products.size(); ++i) {
      CHECK(s.calls[i].count() == 4);  // rounds × reps
      CHECK(positive_finite(s.first_call_seconds[i]));
      CHECK(positive_finite(s.gflops_best(r.products[i], i)));
      CHECK(s.gflops_best(r.products[i], i) >= s.gflops_median(r.products[i], i));
    }
  }
  CHECK_FALSE(gemm::gemm_tuning_installed(test::test_context()));
}

TEST_CASE("bench gemm: zero rows or reps are refused") {
  auto o = tiny_gemm_options();
  o.rows = 0;
  CHECK_THROWS_WITH_AS(bench::run_gemm_bench(test::test_context(), o, bench::clblast_configs(std::nullopt)),
                       doctest::Contains("at least 1"), Error);
  o = tiny_gemm_options();
  o.reps = 0;
  CHECK_THROWS_AS(bench::run_gemm_bench(test::test_context(), o, bench::clblast_configs(std::nullopt)), Error);
}

TEST_CASE("bench gemm: the whole network on one chunk") {
  const auto net_owner = mlp::make_network(test::test_context(), test::small_mlp_config(), gemm::GemmBackend::automatic);
  mlp::Network& net = *net_owner;
  const auto t = bench::time_mlp_chunk(test::test_context(), net, 4, 8, 1);
  CHECK(t.rows == 32);
  CHECK(positive_finite(t.forward));
  CHECK(positive_finite(t.backward));
  CHECK(positive_finite(t.inference));
  CHECK(positive_finite(t.training_rows_per_second()));
}

TEST_CASE("bench preset: a few training steps and a render of the tiny preset") {
  const auto& r = preset_result();
  CHECK(r.preset == "tiny");
  CHECK(r.config.steps == 3);           // the first step and 2 warm ones
  CHECK(r.config.batch_size == 32);     // the settings apply over the preset
  CHECK(r.config.num_samples == 16);    // the preset's own
  const auto& t = r.train;
  CHECK(t.batch_rays == 32);
  CHECK(t.parameters > 0);
  CHECK(t.chunk_rays > 0);
  CHECK(t.chunk_rays <= 32);
  CHECK(t.planned_device_bytes > 0);
  CHECK(t.planned_device_bytes <= t.memory_budget_bytes);
  CHECK(t.peak_rss_bytes > 0);
  CHECK_FALSE(t.gemm_tuned);
  CHECK(positive_finite(t.setup_seconds));
  CHECK(positive_finite(t.first_step_seconds));
  CHECK(t.warm_steps.count() == 2);
  CHECK_FALSE(t.time_boxed);
  CHECK(positive_finite(t.warm_steps.best()));
  CHECK(positive_finite(t.rays_per_second()));
  REQUIRE(r.render.has_value());
  CHECK(r.render->width == 8);
  CHECK(r.render->height == 6);
  CHECK(r.render->renders.count() == 2);
  CHECK(positive_finite(r.render->warm_up_seconds));
  CHECK(positive_finite(r.render->seconds_per_megapixel()));
}

TEST_CASE("bench preset: the time box stops the warm steps after the first one, and no render when size is 0") {
  auto options = tiny_preset_options("timebox");
  options.warm_steps = 50;
  options.time_box_seconds = 1e-9;  // spent by any step: exactly one warm step runs
  options.render_width = 0;
  const auto r = bench::run_preset_bench(test::test_context(), options);
  fs::remove_all(options.work_dir);
  CHECK(r.train.warm_steps.count() == 1);
  CHECK(r.train.time_boxed);
  CHECK_FALSE(r.render.has_value());
}

TEST_CASE("bench preset: profiled steps follow the timed ones, by stage, also after the time box") {
  ocl::Context ctx(test::test_context().device_info(), true);
  for (const double time_box : {0.0, 1e-9}) {
    INFO("time box " << time_box);
    auto options = tiny_preset_options("profile");
    options.warm_steps = time_box > 0 ? 50 : 2;
    options.time_box_seconds = time_box;
    options.profile_steps = 2;
    options.render_width = 0;
    const auto r = bench::run_preset_bench(ctx, options);
    fs::remove_all(options.work_dir);
    CHECK(ctx.profiler() == nullptr);  // detached when done
    CHECK(r.train.warm_steps.count() == (time_box > 0 ? 1u : 2u));  // the profiled steps are not timed
    CHECK(r.train.time_boxed == (time_box > 0));
    REQUIRE(r.train.profile.has_value());
    const ocl::StageProfile& p = *r.train.profile;
    CHECK(p.steps == 2);
    for (const char* stage : {"batch", "rays", "sampling", "resampling", "encoding", "gemm forward",
                              "gemm backward_data", "gemm backward_weights", "render", "render backward", "loss",
                              "adam"}) {
      CAPTURE(stage);
      const ocl::StageTime* s = p.find(stage);
      REQUIRE(s != nullptr);
      CHECK(s->seconds > 0.0);
      const bool product = std::string(stage).rfind("gemm", 0) == 0;
      CHECK((s->bytes > 0.0) == !product);  // every ray stage declares its least traffic
    }
    // The render's least traffic per step: both levels' batch at the tiny preset's 16 samples a level, over 2 steps.
    CHECK(p.find("render")->bytes / 2 == doctest::Approx(2 * graph::traffic::render_forward(r.train.batch_rays, 16)));
    CHECK(p.stage_seconds() <= p.wall_seconds);
    const bench::GemmLimit g = bench::gemm_limit(p, r.train.batch_rays);
    CHECK(g.fraction() > 0.0);
    CHECK(g.fraction() < 1.0);
    CHECK(g.limit_rays_per_second > g.rays_per_second);
  }
  {
    // With a render: one more render profiled by stage, its products and encoding among them, the profiler detached.
    auto options = tiny_preset_options("profile-render");
    options.profile_steps = 1;
    const auto r = bench::run_preset_bench(ctx, options);
    fs::remove_all(options.work_dir);
    CHECK(ctx.profiler() == nullptr);
    REQUIRE(r.render.has_value());
    CHECK(r.render->renders.count() == 2);  // the profiled render is not one of the timed ones
    REQUIRE(r.render->profile.has_value());
    const ocl::StageProfile& p = *r.render->profile;
    CHECK(p.steps == 1);
    for (const char* stage : {"rays", "sampling", "encoding", "gemm forward", "render"}) {
      CAPTURE(stage);
      const ocl::StageTime* s = p.find(stage);
      REQUIRE(s != nullptr);
      CHECK(s->seconds > 0.0);
      // The ray stages declare their least traffic, the products their FLOPs.
      const bool product = std::string(stage).rfind("gemm", 0) == 0;
      CHECK((s->bytes > 0.0) == !product);
      CHECK((s->flops > 0.0) == product);
    }
    CHECK(p.find("gemm backward_data") == nullptr);  // inference: no backward
    CHECK(p.stage_seconds() <= p.wall_seconds);
    const std::string md = bench::stage_profile_markdown(p, 48, io::Json::object(), "image");
    CHECK(md.find("| stage | ms/image | share of image |") != std::string::npos);
  }
  auto options = tiny_preset_options("profile-refused");
  options.profile_steps = 1;
  CHECK_THROWS_WITH_AS(bench::run_preset_bench(test::test_context(), options),
                       doctest::Contains("context made with profiling on"), Error);
}

TEST_CASE("bench stage report: per-step figures, largest stage first, and the GEMM-bound limit") {
  ocl::StageProfile p;
  p.steps = 2;
  p.wall_seconds = 2.0;  // 1 s per step
  p.stages = {{"encoding", 0.2, 4, 0.0, 4e9}, {"gemm forward", 0.6, 10, 60e9},
              {"gemm backward_weights", 0.4, 10, 40e9}, {"adam", 0.1, 2, 0.0}};
  const bench::GemmLimit g = bench::gemm_limit(p, 1000);
  CHECK(g.step_seconds == doctest::Approx(1.0));
  CHECK(g.gemm_seconds == doctest::Approx(0.5));
  CHECK(g.gemm_gflops == doctest::Approx(100.0));  // 100e9 FLOPs in 1 s
  CHECK(g.rays_per_second == doctest::Approx(1000.0));
  CHECK(g.limit_rays_per_second == doctest::Approx(2000.0));
  CHECK(g.fraction() == doctest::Approx(0.5));
  const std::string md = bench::stage_profile_markdown(p, 1000);
  CHECK(md.find("| gemm forward | 300.00 | 30.0 % | 5 | 100.0 |") != std::string::npos);
  CHECK(md.find("gemm forward") < md.find("gemm backward_weights"));
  CHECK(md.find("gemm backward_weights") < md.find("| encoding"));
  CHECK(md.find("| (host time between commands: launches, waits) | 350.00 | 35.0 %") != std::string::npos);
  CHECK(md.find("GEMM-bound limit: 2000 rays/s") != std::string::npos);
  CHECK(md.find("= 50 % of it") != std::string::npos);
  // The encoding's 4e9 bytes in 0.2 s: 20 GB/s; no machine probe, so no fraction of the triad.
  CHECK(md.find("| encoding | 100.00 | 10.0 % | 2 | – | 20.00 | – |") != std::string::npos);
  CHECK(md.find("| adam | 50.00 | 5.0 % | 1 | – | – | – |") != std::string::npos);
  io::Json machine;
  machine["triad_gbs"]["all_threads"]["best"] = 25.0;
  const std::string with_triad = bench::stage_profile_markdown(p, 1000, machine);
  CHECK(with_triad.find("| encoding | 100.00 | 10.0 % | 2 | – | 20.00 | 80 % |") != std::string::npos);
  CHECK(with_triad.find("STREAM triad (25.0 GB/s, probed in this run)") != std::string::npos);
  const auto j = bench::stage_profile_json(p, 1000);
  CHECK(j["gemm_limit_fraction"].get<double>() == doctest::Approx(0.5));
  CHECK(j["stages"].size() == 4);
  CHECK(j["stages"][0]["least_bytes_per_step"].get<double>() == doctest::Approx(2e9));
}

TEST_CASE("stage traffic: each stage's least bytes, counted by hand for small sizes") {
  // 2 rays, 3 intervals, 96 features: per ray 7 ray floats + 4 edges in, 3 × 96 features out.
  CHECK(graph::traffic::encoding(2, 3, 96) == 4.0 * 2 * (7 + 4 + 3 * 96));
  // Per ray 2 ids copied (read + write) and read again, 13 ray floats written (10 without the view direction).
  CHECK(graph::traffic::rays(5, true) == 4.0 * 5 * (4 + 2 + 13));
  CHECK(graph::traffic::rays(5, false) == 4.0 * 5 * (4 + 2 + 10));
  CHECK(graph::traffic::stratified_sampling(2, 3) == 4.0 * 2 * (2 + 4));
  // Resampling 3 → 5 intervals: 4 edges + 3 weights in, 6 edges out; the union reads both again and writes 10.
  CHECK(graph::traffic::resampling(1, 3, 5, false) == 4.0 * (4 + 3 + 6));
  CHECK(graph::traffic::resampling(1, 3, 5, true) == 4.0 * (4 + 3 + 6 + 4 + 6 + 10));
  // Render: per sample raw colour 3, density, edge in, weight out; per ray last edge, direction in, 5 outputs.
  CHECK(graph::traffic::render_forward(2, 3) == 4.0 * 2 * (3 * 6 + 1 + 3 + 5));
  CHECK(graph::traffic::render_forward(2, 3, false) == 4.0 * 2 * (3 * 3 + 1 + 3 + 2));  // weights only: no colours
  CHECK(graph::traffic::render_backward(2, 3) == 4.0 * 2 * (3 * 10 + 1 + 3 + 3));
  CHECK(graph::traffic::loss(3) == 4.0 * 3 * 10);
  CHECK(graph::traffic::view_encoding(2, 27) == 4.0 * 2 * 30);
  CHECK(graph::traffic::adam(10) == 4.0 * 10 * 9);
  CHECK(graph::traffic::batch(2) == 4.0 * 2 * 9);
}

TEST_CASE("bench preset: an unknown preset or zero warm steps are refused") {
  auto options = tiny_preset_options("bad");
  options.preset = "nosuch";
  CHECK_THROWS_WITH_AS(bench::run_preset_bench(test::test_context(), options), doctest::Contains("unknown preset"),
                       Error);
  options = tiny_preset_options("bad");
  options.warm_steps = 0;
  CHECK_THROWS_WITH_AS(bench::run_preset_bench(test::test_context(), options),
                       doctest::Contains("at least one warm step"), Error);
}

TEST_CASE("bench report: bench.json names the device, driver, OpenCL C and CLBlast versions, date and settings") {
  auto& ctx = test::test_context();
  bench::BenchRun run;
  run.version = MIPNERF_VERSION;
  run.date = eval::utc_timestamp();
  run.command = "mipnerf-cl bench (test)";
  run.host = bench::host_record();
  run.presets.scene = "tiny scene";
  run.presets.warm_steps = 2;
  bench::DeviceBench d;
  d.device = eval::device_record(ctx.device_info());
  d.clblast_version = gemm::clblast_version();
  d.tuning_file = "/nowhere/gemm.json";
  d.gemm = gemm_result();
  d.kernels = kernel_result();
  d.presets.push_back(preset_result());
  d.errors.push_back({"train paper", "did not fit"});
  run.devices.push_back(d);
  run.complete = true;

  const auto j = io::parse_json(bench::bench_json(run).dump(), "bench.json");
  CHECK(j.at("tool") == "mipnerf-cl bench");
  CHECK(std::regex_match(j.at("date").get<std::string>(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
  CHECK(j.at("host").at("hardware_threads").get<int>() > 0);
  REQUIRE(j.at("devices").size() == 1);
  const auto& dj = j.at("devices")[0];
  CHECK(dj.at("device").at("name") == ctx.device_info().name);
  CHECK(dj.at("device").at("platform") == ctx.device_info().platform_name);
  CHECK(dj.at("device").at("driver_version") == ctx.device_info().driver_version);
  CHECK(dj.at("device").at("opencl_c_version") == ctx.device_info().opencl_c_version);
  CHECK_FALSE(dj.at("clblast_version").get<std::string>().empty());
  CHECK(dj.at("gemm").at("tuned") == false);
  CHECK(dj.at("gemm").at("note").get<std::string>().find("mipnerf-cl tune") != std::string::npos);
  CHECK(dj.at("gemm").at("settings").at("rows") == 64);
  REQUIRE(dj.at("gemm").at("products").size() == 6);
  CHECK(dj.at("gemm").at("products")[0].at("CLBlast default").at("gflops_best").get<double>() > 0);
  CHECK(dj.at("kernels").at("stages").size() == 13);
  CHECK(dj.at("kernels").at("settings").at("rays") == 32);
  const auto& tj = dj.at("training").at(0);
  CHECK(tj.at("preset") == "tiny");
  CHECK(tj.at("rays_per_second").get<double>() > 0);
  CHECK(tj.at("first_step_seconds").get<double>() > 0);
  CHECK(tj.at("planned_device_bytes").get<double>() > 0);
  CHECK(tj.at("peak_rss_bytes").get<double>() > 0);
  CHECK(tj.at("config").at("batch_size") == 32);
  CHECK(dj.at("render").at(0).at("seconds_per_megapixel").get<double>() > 0);
  CHECK(dj.at("errors").at(0).at("section") == "train paper");

  const std::string md = bench::bench_markdown(run);
  for (const std::string& expected : {ctx.device_info().name, ctx.device_info().driver_version,
                                      ctx.device_info().opencl_c_version, "CLBlast | " + gemm::clblast_version(),
                                      run.date, std::string("No tuning file"), std::string("### Training steps"),
                                      std::string("| tiny | 32 × 16 × 2 |"), std::string("train paper: did not fit")}) {
    CHECK_MESSAGE(md.find(expected) != std::string::npos, expected);
  }
}

#ifdef MIPNERF_CLI_PATH
// Points XDG_CACHE_HOME at `folder` for the scope (where tuning files are looked up), then restores it.
class CacheHome {
 public:
  explicit CacheHome(const fs::path& folder) {
    const char* old = std::getenv("XDG_CACHE_HOME");
    had_old_ = old != nullptr;
    if (old) old_ = old;
    ::setenv("XDG_CACHE_HOME", folder.c_str(), 1);
  }
  ~CacheHome() {
    if (had_old_) {
      ::setenv("XDG_CACHE_HOME", old_.c_str(), 1);
    } else {
      ::unsetenv("XDG_CACHE_HOME");
    }
  }

 private:
  std::string old_;
  bool had_old_ = false;
};

TEST_CASE("bench CLI: mipnerf-cl bench --quick on tiny sizes writes bench.json and bench.md, tuned where a file is") {
  const auto out = bench_temp("cli");
  const auto cache = bench_temp("cli-cache");
  fs::remove_all(out);
  fs::remove_all(cache);
  // A tuning file for this device in a cache folder of the test's own (never the user's): the bench finds it and
  // adds the tuned column; its one set equals CLBlast's default, so nothing new is compiled.
  CacheHome cache_home(cache);
  gemm::save_tuning(gemm::tuning_file_path(test::test_context().device_info()), same_as_defaults_tuning());
  // gemm_backend=clblast: the training preset must show the file reaching CLBlast (auto takes the host BLAS on CPUs).
  const std::string log = (bench_temp("cli-log")).string();
  const std::string command = "XDG_CACHE_HOME=\"" + cache.string() + "\" \"" + MIPNERF_CLI_PATH + "\" --device " +
                              std::to_string(test::test_context().device_info().index) + " bench --quick --out \"" +
                              out.string() +
                              "\" --presets tiny --set batch_size=32 --set gemm_backend=clblast --steps 1 --gemm-rows 64 --gemm-widths 8 "
                              "--kernel-rays 16 --kernel-samples 4 --render-size 8x8 --scene-size 16 --scene-views 3 "
                              ">\"" + log + ".out\" 2>\"" + log + ".err\"";
  const int status = std::system(command.c_str());
  std::ifstream err(log + ".err");
  std::stringstream err_text;
  err_text << err.rdbuf();
  INFO(err_text.str());
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);

  const auto j = io::read_json((out / "bench.json").string());
  CHECK(j.at("complete") == true);
  CHECK(j.at("quick") == true);
  CHECK(j.at("command").get<std::string>().find("--quick") != std::string::npos);
  REQUIRE(j.at("devices").size() == 1);
  const auto& d = j.at("devices")[0];
  CHECK(d.at("device").at("name") == test::test_context().device_info().name);
  CHECK_FALSE(d.at("device").at("driver_version").get<std::string>().empty());
  CHECK_FALSE(d.at("clblast_version").get<std::string>().empty());
  CHECK(d.at("errors").empty());
  CHECK(d.at("gemm").at("tuned") == true);
  REQUIRE(d.at("gemm").at("products").size() == 3);
  CHECK(d.at("gemm").at("products")[2].at("CLBlast tuned").at("gflops_best").get<double>() > 0);
  // The host GEMM backend stands beside CLBlast wherever the device can run it.
  const bool host_backend = test::test_context().device_info().host_unified_memory && gemm::host_blas_available();
  CHECK(d.at("gemm").at("products")[2].contains("host BLAS (mapped)") == host_backend);
  CHECK(d.at("kernels").at("stages").size() == 13);
  REQUIRE(d.at("training").size() == 1);
  CHECK(d.at("training")[0].at("warm_steps") == 1);
  CHECK(d.at("training")[0].at("gemm_parameters") == "tuned");  // gemm_backend=clblast, with the tuned file
  CHECK(d.at("render")[0].at("width") == 8);

  std::ifstream md_file(out / "bench.md");
  std::stringstream md;
  md << md_file.rdbuf();
  CHECK(md.str().find("# mipnerf-cl bench") != std::string::npos);
  CHECK(md.str().find(test::test_context().device_info().name) != std::string::npos);
  CHECK(md.str().find("### Rendering") != std::string::npos);
  fs::remove_all(out);
  fs::remove_all(cache);
  fs::remove(log + ".out");
  fs::remove(log + ".err");
}
#endif

TEST_CASE("bench: the machine probe measures the FMA peak, the triad and a large sgemm, and sums them up in a line") {
  bench::MachineProbeSettings settings;
  settings.threads = 2, settings.rounds = 1, settings.batch_seconds = 0.001, settings.triad_floats = 1 << 16;
  const io::Json probe = bench::probe_machine(settings);
  CHECK(probe.value("threads", 0) == 2);
  const auto positive = [](const io::Json& figure) {
    return figure.contains("skipped") || (figure.value("best", 0.0) > 0 && figure.value("median", 0.0) > 0 &&
                                          figure.value("best", 0.0) >= figure.value("median", 0.0));
  };
  for (const char* part : {"fma_peak_gflops", "triad_gbs"}) {
    INFO(part);
    REQUIRE(probe.contains(part));
    if (probe[part].contains("skipped")) continue;
    CHECK(positive(probe[part]["one_thread"]));
    CHECK(positive(probe[part]["all_threads"]));
  }
  CHECK(positive(probe["large_sgemm_gflops"]));
  // The peak is the fastest vector width timed (16 floats where the CPU has AVX-512), the large sgemm the fastest
  // library built in, each named: a slower denominator would put well-run products above "the limit".
  const auto fastest_of = [](const io::Json& options, const std::string& chosen, const char* rate_key) {
    double best = 0.0;
    std::string name;
    for (const auto& [key, value] : options.items()) {
      const io::Json& rate = rate_key ? value[rate_key] : value;
      if (rate.value("best", 0.0) > best) best = rate.value("best", 0.0), name = key;
    }
    return name == chosen;
  };
  const io::Json& fma = probe["fma_peak_gflops"];
  if (!fma.contains("skipped")) {
    REQUIRE(fma.contains("by_vector"));
    CHECK(fma["by_vector"].contains("avx2_8_floats"));
#if defined(__x86_64__)
    CHECK(fma["by_vector"].contains("avx512_16_floats") == static_cast<bool>(__builtin_cpu_supports("avx512f")));
#endif
    CHECK(fastest_of(fma["by_vector"], fma.value("vector", ""), "all_threads"));
    CHECK(fma["all_threads"] == fma["by_vector"][fma.value("vector", "")]["all_threads"]);
  }
  const io::Json& sgemm = probe["large_sgemm_gflops"];
  if (!sgemm.contains("skipped")) {
    REQUIRE(sgemm.contains("by_library"));
    CHECK(sgemm["by_library"].size() == gemm::cpu_sgemm_libraries().size());
    CHECK(fastest_of(sgemm["by_library"], sgemm.value("library", ""), nullptr));
    CHECK(sgemm.value("best", 0.0) == sgemm["by_library"][sgemm.value("library", "")].value("best", -1.0));
  }
  const std::string line = bench::machine_summary(probe);
  CHECK(line.find("FMA peak ") == 0);
  CHECK(line.find("(2 threads, " + fma.value("vector", std::string("not probed")) + "), triad ") != std::string::npos);
  CHECK(line.find("GFLOP/s (" + sgemm.value("library", std::string("none")) + ")") != std::string::npos);
  CHECK(bench::machine_summary(io::Json::object()).empty());
}
