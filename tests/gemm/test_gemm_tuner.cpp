// The GEMM tune's search (mlp/gemm_tuner.hpp) without a device: its rules (starting sets, the GEMMK = 1
// MWG = NWG rule, the direct/indirect switch), and whole searches whose steps an in-process runner answers with
// made-up measurements, so the winners are known in advance.
#include <clblast.h>
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/json.hpp"
#include "gemm/gemm_tuner.hpp"
#include "gemm/gemm_tuning.hpp"
#include "mlp/mlp_products.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

gemm::ParameterSet xgemm(size_t gemmk, size_t mwg, size_t nwg) {
  return {{"Xgemm", {{"GEMMK", gemmk}, {"MWG", mwg}, {"NWG", nwg}}}};
}

// A folder of its own under the system's temporary folder, removed afterwards.
class ScratchFolder {
 public:
  ScratchFolder() {
    char pattern[] = "/tmp/mipnerf-tuner-test-XXXXXX";
    REQUIRE(::mkdtemp(pattern) != nullptr);
    folder_ = pattern;
  }
  ~ScratchFolder() {
    std::error_code error;
    std::filesystem::remove_all(folder_, error);
    CHECK_FALSE(error);
  }
  std::string file(const std::string& name) const { return folder_ + "/" + name; }

 private:
  std::string folder_;
};

// Made-up step results, by candidate name ("evaluate <name>", the second round's "<name> (again)" alike):
// seconds per product kind, candidates whose results are wrong, candidates whose step crashes. Kernel tuners
// always crash, so only CLBlast's defaults and the starting sets compete.
struct FakeDevice {
  std::map<std::string, std::map<gemm::GemmKind, double>> seconds;  // candidate → kind → seconds per product
  std::map<std::string, double> error_ratio;                       // candidate → its error ratio (else 0.01)
  std::vector<std::string> crashes;                                // candidates whose step crashes
  std::vector<std::string> steps;                                  // names of the steps run, in order

  static std::string candidate_of(const std::string& step) {
    std::string name = step.substr(std::string("evaluate ").size());
    const auto again = name.find(" (again)");
    return again == std::string::npos ? name : name.substr(0, again);
  }

  gemm::TuneStepOutcome run(const std::string& step, const io::Json& spec) {
    steps.push_back(step);
    const std::string type = spec.at("type");
    if (type == "tuner") return {false, "crashed (signal 11)", 1.0, {}};
    if (type == "crossover") {
      // Indirect loses below 2048 rows, wins from there on.
      io::Json indirect = io::Json::array(), direct = io::Json::array();
      for (const auto& rows : spec.at("rows")) {
        indirect.push_back(rows.get<size_t>() < 2048 ? 2.0 : 1.0);
        direct.push_back(1.5);
      }
      return {true, "ok", 1.0, {{"indirect", indirect}, {"direct", direct}}};
    }
    const std::string candidate = candidate_of(step);
    if (std::find(crashes.begin(), crashes.end(), candidate) != crashes.end()) {
      return {false, "crashed (signal 11)", 1.0, {}};
    }
    io::Json times = io::Json::array(), errors = io::Json::array();
    for (const auto& p : spec.at("problems")) {
      gemm::GemmShape s;
      s.transpose_a = p.at("ta");
      s.transpose_b = p.at("tb");
      times.push_back(seconds.at(candidate).at(gemm::gemm_kind(s)));
      errors.push_back(error_ratio.count(candidate) ? error_ratio.at(candidate) : 0.01);
    }
    return {true, "ok", 1.0, {{"seconds", times}, {"error_ratio", errors}, {"probe_error_ratio", 0.01}}};
  }
};

// The network tuned for: the presets' layout at width 128.
mlp::MlpConfig tuned_network() {
  mlp::MlpConfig config;
  config.width = 128;
  config.bottleneck_width = 128;
  return config;
}

gemm::GemmTuneSettings small_settings() {
  gemm::GemmTuneSettings settings;
  settings.minutes = 30.0;  // the fake steps take no time: every step of the plan fits
  settings.rows = 1024;
  settings.kernel_rows = 128;
  settings.width = 128;
  settings.problems = mlp::mlp_gemm_problems(tuned_network(), settings.rows);
  return settings;
}

ocl::DeviceInfo fake_device() {
  ocl::DeviceInfo device;
  device.name = "fake device";
  device.driver_version = "0.1";
  return device;
}

// Seconds per training step of `kind` when each of its products takes `seconds_each`.
double per_step(const gemm::GemmTuneSettings& settings, gemm::GemmKind kind, double seconds_each) {
  double total = 0.0;
  for (const auto& p : settings.problems) {
    if (p.kind() == kind) total += seconds_each * static_cast<double>(p.count);
  }
  return total;
}

}  // namespace

TEST_CASE("gemm tuner: the starting sets are complete Xgemm sets that CLBlast accepts and the GEMMK = 1 rule keeps") {
  auto& ctx = test::test_context();
  const auto seeds = gemm::gemm_seed_sets();
  REQUIRE(seeds.size() == 4);
  for (const auto& seed : seeds) {
    const auto& name = seed.first;  // INFO cannot capture a structured binding (C++17)
    const auto& parameters = seed.second;
    INFO(name);
    CHECK(parameters.size() == 16);
    CHECK(gemm::gemmk1_usable({{"Xgemm", parameters}}, 1, 5));
    gemm::GemmTuning tuning;
    tuning.common["Xgemm"] = parameters;
    CHECK_NOTHROW(gemm::install_gemm_tuning(ctx, tuning));  // CLBlast checks names and completeness
    gemm::clear_gemm_tuning(ctx);
  }
}

TEST_CASE("gemm tuner: GEMMK = 1 with MWG != NWG is not timed before CLBlast 1.6") {
  CHECK_FALSE(gemm::gemmk1_usable(xgemm(1, 64, 128), 1, 5));
  CHECK(gemm::gemmk1_usable(xgemm(1, 64, 128), 1, 6));
  CHECK(gemm::gemmk1_usable(xgemm(1, 64, 128), 2, 0));
  CHECK(gemm::gemmk1_usable(xgemm(1, 64, 64), 1, 5));
  CHECK(gemm::gemmk1_usable(xgemm(0, 64, 128), 1, 5));
  CHECK(gemm::gemmk1_usable({}, 1, 5));
  CHECK(gemm::gemmk1_usable({{"XgemmDirect", {{"WGD", 32}}}}, 1, 5));
  // The one-argument form asks about the CLBlast this was built against.
  CHECK(gemm::gemmk1_usable(xgemm(1, 64, 128)) ==
        gemm::gemmk1_usable(xgemm(1, 64, 128), CLBLAST_VERSION_MAJOR, CLBLAST_VERSION_MINOR));
}

TEST_CASE("gemm tuner: the direct switch starts where the indirect kernel never loses again") {
  const std::vector<size_t> rows = {512, 1024, 2048, 4096};
  // Indirect wins at 1024, loses at 2048, wins from 4096: the switch is at 4096 rows, cbrt(4096·128·128) = 406.
  auto chosen = gemm::direct_switch_from(rows, {2.0, 1.0, 3.0, 1.0}, {1.0, 2.0, 2.0, 2.0}, 128);
  REQUIRE(chosen.from_rows.has_value());
  CHECK(*chosen.from_rows == 4096);
  CHECK(chosen.min_indirect_size == 406);
  // A tie counts for the indirect kernel.
  chosen = gemm::direct_switch_from(rows, {1.0, 1.0, 1.0, 1.0}, {1.0, 1.0, 1.0, 1.0}, 128);
  CHECK(chosen.from_rows == std::optional<size_t>(512));
  chosen = gemm::direct_switch_from(rows, {2.0, 2.0, 2.0, 2.0}, {1.0, 1.0, 1.0, 1.0}, 128);
  CHECK_FALSE(chosen.from_rows.has_value());
  CHECK(chosen.min_indirect_size == size_t{1} << 20);
  CHECK_THROWS_AS(gemm::direct_switch_from(rows, {1.0}, {1.0, 1.0, 1.0, 1.0}, 128), Error);
}

TEST_CASE("gemm tuner: each kind keeps its fastest correct candidate, wrong and crashed ones never win") {
  ScratchFolder scratch;
  const auto settings = small_settings();
  using K = gemm::GemmKind;
  const auto seeds = gemm::gemm_seed_sets();
  REQUIRE(seeds.size() == 4);
  FakeDevice fake;
  fake.seconds["CLBlast defaults"] = {{K::forward, 1.0}, {K::backward_data, 1.0}, {K::backward_weights, 1.0}};
  fake.seconds[seeds[0].first] = {{K::forward, 0.5}, {K::backward_data, 0.6}, {K::backward_weights, 2.0}};
  fake.seconds[seeds[1].first] = {{K::forward, 0.1}, {K::backward_data, 0.1}, {K::backward_weights, 0.1}};
  fake.error_ratio[seeds[1].first] = 5.0;  // the fastest everywhere, but wrong
  fake.seconds[seeds[2].first] = {{K::forward, 3.0}, {K::backward_data, 3.0}, {K::backward_weights, 0.4}};
  fake.crashes.push_back(seeds[3].first);
  std::vector<std::string> notes;
  gemm::GemmTuner tuner(
      settings, fake_device(), scratch.file("tuning.json"),
      [&](const std::string& name, const io::Json& spec, double) { return fake.run(name, spec); },
      [&](LogLevel, const std::string& message) { notes.push_back(message); });
  tuner.run();

  std::map<K, gemm::GemmTuneWinner> by_kind;
  for (const auto& w : tuner.winners()) by_kind[w.kind] = w;
  REQUIRE(by_kind.size() == 3);
  CHECK(by_kind[K::forward].candidate == seeds[0].first);
  CHECK(by_kind[K::backward_data].candidate == seeds[0].first);
  CHECK(by_kind[K::backward_weights].candidate == seeds[2].first);
  CHECK(by_kind[K::forward].seconds == doctest::Approx(per_step(settings, K::forward, 0.5)));
  REQUIRE(by_kind[K::backward_weights].default_seconds.has_value());
  CHECK(*by_kind[K::backward_weights].default_seconds == doctest::Approx(per_step(settings, K::backward_weights, 1.0)));
  bool told_wrong = false;
  for (const auto& n : notes)
    told_wrong = told_wrong || n.rfind(seeds[1].first + " (WRONG RESULTS, discarded)", 0) == 0;
  CHECK(told_wrong);
  // The correct candidates were timed a second time; the crashed and the wrong one were not.
  const auto ran = [&](const std::string& step) {
    return std::find(fake.steps.begin(), fake.steps.end(), step) != fake.steps.end();
  };
  CHECK(ran("evaluate " + seeds[0].first + " (again)"));
  CHECK(ran("evaluate CLBlast defaults (again)"));
  CHECK_FALSE(ran("evaluate " + seeds[1].first + " (again)"));
  CHECK_FALSE(ran("evaluate " + seeds[3].first + " (again)"));

  // The file: per-kind winners, with the switch of the crossover (indirect from 2048 rows: cbrt(2048·128²)).
  const auto saved = gemm::read_tuning(scratch.file("tuning.json"));
  REQUIRE(saved.has_value());
  CHECK(saved->device_name == "fake device");
  CHECK(saved->per_kind.at(K::forward).at("Xgemm") == seeds[0].second);
  CHECK(saved->per_kind.at(K::backward_weights).at("Xgemm") == seeds[2].second);
  CHECK(saved->per_kind.at(K::forward).at("GemmRoutine").at("XGEMM_MIN_INDIRECT_SIZE") == 322);
  const auto report = io::Json::parse(saved->report_json);
  CHECK(report.at("chosen").at("backward_weights").at("candidate") == seeds[2].first);
  CHECK(report.at("direct_switch").at("XGEMM_MIN_INDIRECT_SIZE") == 322);
  std::map<std::string, std::string> status;
  for (const auto& c : report.at("candidates")) {
    status[c.at("name")] = c.value("correct", true) ? c.at("status").get<std::string>() : "wrong";
  }
  CHECK(status[seeds[1].first] == "wrong");
  CHECK(status[seeds[3].first] == "crashed (signal 11)");
}

TEST_CASE("gemm tuner: once asked to stop, no further step starts and the best so far is kept") {
  ScratchFolder scratch;
  using K = gemm::GemmKind;
  FakeDevice fake;
  fake.seconds["CLBlast defaults"] = {{K::forward, 1.0}, {K::backward_data, 1.0}, {K::backward_weights, 1.0}};
  gemm::GemmTuner tuner(
      small_settings(), fake_device(), scratch.file("tuning.json"),
      [&](const std::string& name, const io::Json& spec, double) { return fake.run(name, spec); }, {},
      [&] { return !fake.steps.empty(); });
  tuner.run();
  CHECK(fake.steps == std::vector<std::string>{"evaluate CLBlast defaults"});
  const auto saved = gemm::read_tuning(scratch.file("tuning.json"));
  REQUIRE(saved.has_value());
  CHECK(io::Json::parse(saved->report_json).at("chosen").at("forward").at("candidate") == "CLBlast defaults");
}

TEST_CASE("gemm tuner: the parameter sets' JSON round-trips, and describes itself for people") {
  const gemm::ParameterSet set = {{"Xgemm", {{"GEMMK", 1}, {"MWG", 64}}}, {"Copy", {{"COPY_DIMX", 8}}}};
  CHECK(gemm::parameter_set_from_json(gemm::parameter_set_json(set)) == set);
  CHECK(gemm::describe_parameter_set(set) == "Copy: COPY_DIMX=8; Xgemm: GEMMK=1 MWG=64");
  CHECK(gemm::describe_parameter_set({}) == "CLBlast defaults");
}
