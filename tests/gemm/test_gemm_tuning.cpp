// The per-device GEMM tuning store: its file name and format, installing parameter sets through
// clblast::OverrideParameters (per product kind), the CLI's load step, and that products stay correct.
#include <doctest/doctest.h>

#include <clblast.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <unordered_map>

#include "core/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/gemm.hpp"
#include "gemm/gemm_tuning.hpp"
#include "mlp/network.hpp"
#include "mlp/mlp_checks.hpp"
#include "ref/gemm_ref.hpp"
#include "support/mlp_fixtures.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

// Points XDG_CACHE_HOME at a fresh folder for the test and restores the environment and CLBlast afterwards.
class ScratchCache {
 public:
  ScratchCache() {
    char pattern[] = "/tmp/mipnerf-tuning-test-XXXXXX";
    REQUIRE(::mkdtemp(pattern) != nullptr);
    folder_ = pattern;
    const char* old = std::getenv("XDG_CACHE_HOME");
    had_old_ = old != nullptr;
    if (old) old_ = old;
    ::setenv("XDG_CACHE_HOME", folder_.c_str(), 1);
  }
  ~ScratchCache() {
    gemm::clear_gemm_tuning(test::test_context());
    if (had_old_) {
      ::setenv("XDG_CACHE_HOME", old_.c_str(), 1);
    } else {
      ::unsetenv("XDG_CACHE_HOME");
    }
    std::error_code error;
    std::filesystem::remove_all(folder_, error);
    CHECK_MESSAGE(!error, "could not remove " << folder_ << ": " << error.message());
  }
  const std::string& folder() const { return folder_; }

 private:
  std::string folder_, old_;
  bool had_old_ = false;
};

gemm::KernelParameters current(const std::string& kernel) {
  std::unordered_map<std::string, size_t> values;
  gemm::check_clblast(clblast::RetrieveParameters(test::test_context().raw_device(), kernel,
                                                 clblast::Precision::kSingle, values),
                     "RetrieveParameters");
  return {values.begin(), values.end()};
}

// A GEMMK = 0 Xgemm set unlike CLBlast's PoCL defaults (which use 32×32 tiles), valid for any device.
gemm::KernelParameters xgemm_set(size_t mwg) {
  return {{"GEMMK", 0}, {"KREG", 1}, {"MWG", mwg}, {"NWG", 64},  {"KWG", 16},  {"MDIMC", 8}, {"NDIMC", 8}, {"MDIMA", 8},
          {"NDIMB", 8}, {"KWI", 2},  {"VWM", 2},   {"VWN", 4},   {"STRM", 0},  {"STRN", 0},  {"SA", 0},    {"SB", 0}};
}

gemm::GemmTuning tuning_for_this_device() {
  const auto& device = test::test_context().device_info();
  gemm::GemmTuning t;
  t.device_name = device.name;
  t.driver_version = device.driver_version;
  t.clblast_version = gemm::clblast_version();
  t.common["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", 8}};  // the indirect kernel for every product below
  t.per_kind[gemm::GemmKind::forward]["Xgemm"] = xgemm_set(64);
  t.per_kind[gemm::GemmKind::backward_weights]["Xgemm"] = xgemm_set(16);
  return t;
}

// C = op(A)·op(B) on the device with whatever is installed, against the double loop (bound as in test_gemm).
void check_product(bool transpose_a, bool transpose_b) {
  auto& ctx = test::test_context();
  std::mt19937 rng(3);
  gemm::GemmShape s;
  s.m = 100;
  s.n = 70;
  s.k = 45;
  s.transpose_a = transpose_a;
  s.transpose_b = transpose_b;
  const size_t lda = transpose_a ? s.m : s.k, ldb = transpose_b ? s.k : s.n;
  const auto a = test::random_floats(s.m * s.k, rng), b = test::random_floats(s.k * s.n, rng);
  auto a_dev = test::device_copy(ctx, a, "A"), b_dev = test::device_copy(ctx, b, "B");
  ocl::DeviceArray<float> c_dev(ctx, s.m * s.n, "C");
  gemm::sgemm(ctx, gemm::GemmBackend::clblast, s, 1.0f, ocl::view(a_dev, lda), ocl::view(b_dev, ldb), 0.0f,
              ocl::view(c_dev, s.n), "tuned");
  const auto ad = test::as_double(a), bd = test::as_double(b);
  std::vector<double> c(s.m * s.n);
  ref::gemm<double>(s, 1.0, ad.data(), lda, bd.data(), ldb, 0.0, c.data(), s.n);
  // A k-term float dot product of values in [−1, 1] errs by at most k·u·k; 4·k·u bounds it (test_gemm).
  test::check_close(c_dev.download(ctx), c, 0, c.size(), 0.0, 4.0 * s.k * 6e-8 + 1e-6, "tuned product");
}

}  // namespace

TEST_CASE("gemm tuning: the file is keyed by device, driver and CLBlast version, under XDG_CACHE_HOME") {
  ScratchCache cache;
  ocl::DeviceInfo device;
  device.name = "pthread-haswell AMD EPYC 7B13";
  device.driver_version = "3.1+debian";
  const std::string path = gemm::tuning_file_path(device);
  CHECK(path.rfind(cache.folder() + "/mipnerf-cl/", 0) == 0);
  CHECK(path.find("pthread-haswell_AMD_EPYC_7B13") != std::string::npos);
  CHECK(path.find("3.1+debian") != std::string::npos);
  CHECK(path.find("clblast-" + gemm::clblast_version()) != std::string::npos);
  device.driver_version = "3.2";
  CHECK(gemm::tuning_file_path(device) != path);
}

TEST_CASE("gemm tuning: the file round-trips, and a malformed one is refused with its name") {
  ScratchCache cache;
  auto tuning = tuning_for_this_device();
  tuning.report_json = R"({"note": "measured"})";
  const std::string path = cache.folder() + "/sub/dir/tuning.json";
  gemm::save_tuning(path, tuning);
  const auto back = gemm::read_tuning(path);
  REQUIRE(back.has_value());
  CHECK(back->device_name == tuning.device_name);
  CHECK(back->common == tuning.common);
  CHECK(back->per_kind == tuning.per_kind);
  CHECK(back->report_json.find("measured") != std::string::npos);
  CHECK_FALSE(gemm::read_tuning(cache.folder() + "/absent.json").has_value());
  std::ofstream(cache.folder() + "/bad.json") << "{not json";
  CHECK_THROWS_WITH_AS(gemm::read_tuning(cache.folder() + "/bad.json"), doctest::Contains("bad.json"), Error);
  std::ofstream(cache.folder() + "/kind.json")
      << R"({"format": "mipnerf-cl gemm tuning 1", "per_kind": {"sideways": {}}})";
  CHECK_THROWS_WITH_AS(gemm::read_tuning(cache.folder() + "/kind.json"), doctest::Contains("sideways"), Error);
}

TEST_CASE("gemm tuning: installed sets reach CLBlast per product kind, products stay correct, clear restores") {
  ScratchCache cache;
  auto& ctx = test::test_context();
  const auto default_xgemm = current("Xgemm");
  const auto default_routine = current("GemmRoutine");
  gemm::install_gemm_tuning(ctx, tuning_for_this_device());
  CHECK(gemm::gemm_tuning_installed(ctx));
  CHECK(current("GemmRoutine").at("XGEMM_MIN_INDIRECT_SIZE") == 8);

  gemm::select_gemm_kind(ctx, gemm::GemmKind::forward);
  CHECK(current("Xgemm") == xgemm_set(64));
  check_product(false, false);
  gemm::select_gemm_kind(ctx, gemm::GemmKind::backward_weights);
  CHECK(current("Xgemm") == xgemm_set(16));
  check_product(true, false);
  // A kind without its own set runs CLBlast's defaults for that kernel.
  gemm::select_gemm_kind(ctx, gemm::GemmKind::backward_data);
  CHECK(current("Xgemm") == default_xgemm);
  check_product(false, true);

  gemm::clear_gemm_tuning(ctx);
  CHECK_FALSE(gemm::gemm_tuning_installed(ctx));
  CHECK(current("Xgemm") == default_xgemm);
  CHECK(current("GemmRoutine") == default_routine);
}

TEST_CASE("gemm tuning: a set CLBlast refuses is not installed at all") {
  ScratchCache cache;
  auto& ctx = test::test_context();
  const auto default_routine = current("GemmRoutine");
  auto tuning = tuning_for_this_device();
  tuning.per_kind[gemm::GemmKind::forward]["Xgemm"].erase("KWI");  // incomplete: CLBlast needs every parameter
  CHECK_THROWS_WITH_AS(gemm::install_gemm_tuning(ctx, tuning), doctest::Contains("Xgemm"), Error);
  CHECK_FALSE(gemm::gemm_tuning_installed(ctx));
  CHECK(current("GemmRoutine") == default_routine);
  tuning = tuning_for_this_device();
  tuning.common["NoSuchKernel"] = {{"X", 1}};
  CHECK_THROWS_AS(gemm::install_gemm_tuning(ctx, tuning), Error);
  CHECK_FALSE(gemm::gemm_tuning_installed(ctx));
}

TEST_CASE("gemm tuning: the CLI's load step uses the device's file, and says once when there is none") {
  ScratchCache cache;
  auto& ctx = test::test_context();
  std::vector<std::pair<LogLevel, std::string>> messages;
  ctx.set_log([&](LogLevel level, const std::string& message) { messages.emplace_back(level, message); });

  // No file: defaults, and a hint, once per device and process (only this test case loads).
  CHECK_FALSE(gemm::load_gemm_tuning(ctx));
  CHECK_FALSE(gemm::gemm_tuning_installed(ctx));
  REQUIRE(messages.size() == 1);
  CHECK(messages[0].second.find("mipnerf-cl tune") != std::string::npos);
  CHECK_FALSE(gemm::load_gemm_tuning(ctx));
  CHECK(messages.size() == 1);

  // A file for this device is installed.
  gemm::save_tuning(gemm::tuning_file_path(ctx.device_info()), tuning_for_this_device());
  messages.clear();
  CHECK(gemm::load_gemm_tuning(ctx));
  CHECK(gemm::gemm_tuning_installed(ctx));
  REQUIRE(messages.size() == 1);
  CHECK(messages[0].second.find("loaded from") != std::string::npos);
  gemm::clear_gemm_tuning(ctx);

  // A file written for another driver is ignored, with a warning.
  auto other = tuning_for_this_device();
  other.driver_version += "-other";
  gemm::save_tuning(gemm::tuning_file_path(ctx.device_info()), other);
  messages.clear();
  CHECK_FALSE(gemm::load_gemm_tuning(ctx));
  CHECK_FALSE(gemm::gemm_tuning_installed(ctx));
  REQUIRE_FALSE(messages.empty());
  CHECK(messages[0].first == LogLevel::warning);
  CHECK(messages[0].second.find("another device, driver or CLBlast version") != std::string::npos);
  ctx.set_log(nullptr);
}

TEST_CASE("gemm tuning: a network on CLBlast loads the device's file itself, and keeps parameters already installed") {
  ScratchCache cache;
  auto& ctx = test::test_context();
  const auto config = test::small_mlp_config(true);
  gemm::clear_gemm_tuning(ctx);
  // No file: CLBlast's defaults stay.
  mlp::make_network(ctx, config, gemm::GemmBackend::clblast);
  CHECK_FALSE(gemm::gemm_tuning_installed(ctx));

  // The device's file: the network's preparation installs it (no caller loads it).
  gemm::save_tuning(gemm::tuning_file_path(ctx.device_info()), tuning_for_this_device());
  mlp::make_network(ctx, config, gemm::GemmBackend::clblast);
  CHECK(gemm::gemm_tuning_installed(ctx));
  CHECK(current("GemmRoutine").at("XGEMM_MIN_INDIRECT_SIZE") == 8);
  gemm::clear_gemm_tuning(ctx);

  // Parameters installed by the caller (tune's own file, a benchmark's set) are not replaced by the device's file.
  auto own = tuning_for_this_device();
  own.per_kind[gemm::GemmKind::forward]["Xgemm"] = xgemm_set(16);
  gemm::install_gemm_tuning(ctx, own);
  mlp::make_network(ctx, config, gemm::GemmBackend::clblast);
  gemm::select_gemm_kind(ctx, gemm::GemmKind::forward);
  CHECK(current("Xgemm").at("MWG") == 16);
}

TEST_CASE("gemm tuning: auto_backend round-trips, and gemm_backend=auto follows tune's measurement for its device") {
  ScratchCache cache;
  auto& ctx = test::test_context();
  auto tuning = tuning_for_this_device();
  const std::string path = gemm::tuning_file_path(ctx.device_info());
  CHECK_FALSE(gemm::measured_auto_backend(ctx.device_info(), {}).has_value());  // no file: the rule

  tuning.auto_backend = gemm::GemmBackend::clblast;
  tuning.backend_measurement_json = R"({"seconds": {"clblast": 1.0, "host": 2.0}})";
  gemm::save_tuning(path, tuning);
  const auto back = gemm::read_tuning(path);
  REQUIRE(back.has_value());
  CHECK(back->auto_backend == gemm::GemmBackend::clblast);
  CHECK(back->backend_measurement_json.find("\"host\":2.0") != std::string::npos);
  // On the CPU test device the rule would take host (when it can); the measurement wins.
  CHECK(gemm::choose_gemm_backend(ctx, gemm::GemmBackend::automatic) == gemm::GemmBackend::clblast);
  CHECK(mlp::make_network(ctx, test::small_mlp_config(true), gemm::GemmBackend::automatic)->backend() ==
        gemm::GemmBackend::clblast);
  // An explicit choice is never overridden.
  if (gemm::host_blas_available() && ctx.device_info().host_unified_memory) {
    CHECK(gemm::choose_gemm_backend(ctx, gemm::GemmBackend::host) == gemm::GemmBackend::host);
  }
  // A file of another driver version is not this device's measurement.
  tuning.driver_version = "another";
  gemm::save_tuning(path, tuning);
  CHECK_FALSE(gemm::measured_auto_backend(ctx.device_info(), {}).has_value());
  // A malformed choice is refused by the reader, and auto falls back to its rule with a warning.
  std::ofstream(path) << R"({"format": "mipnerf-cl gemm tuning 1", "auto_backend": "fastest"})";
  CHECK_THROWS_WITH_AS(gemm::read_tuning(path), doctest::Contains("auto_backend 'fastest' is not clblast or host"),
                       Error);
  std::string warning;
  CHECK_FALSE(gemm::measured_auto_backend(ctx.device_info(), [&](LogLevel, const std::string& m) { warning = m; })
                  .has_value());
  CHECK(warning.find("follows its rule") != std::string::npos);
}

TEST_CASE("gemm tuning: the host MLP's library per product round-trips, and a library this build lacks is dropped") {
  ScratchCache cache;
  auto tuning = tuning_for_this_device();
  tuning.host_libraries = {{"forward 256x128x128", "openblas"}, {"backward_data 256x128x128", "nosuchlib"}};
  tuning.host_libraries_measurement_json = R"({"threads": 2})";
  const ocl::DeviceInfo& device = test::test_context().device_info();
  gemm::save_tuning(gemm::tuning_file_path(device), tuning);
  const auto back = gemm::read_tuning(gemm::tuning_file_path(device));
  REQUIRE(back.has_value());
  CHECK(back->host_libraries == tuning.host_libraries);
  CHECK(back->host_libraries_measurement_json.find("threads") != std::string::npos);
  // What a run takes from it: the choices it can run, never one naming a library it was not built with.
  const gemm::HostProductLibraries choice = gemm::host_product_libraries_for(device);
  CHECK(choice.by_product.size() == 1);
  CHECK(choice.by_product.count("forward 256x128x128") == 1);
  CHECK(choice.fallback == "openblas");
  std::ofstream(cache.folder() + "/host.json")
      << R"({"format": "mipnerf-cl gemm tuning 1", "host_libraries": {"forward 1x1x1": 3}})";
  CHECK_THROWS_WITH_AS(gemm::read_tuning(cache.folder() + "/host.json"), doctest::Contains("forward 1x1x1"), Error);
}
