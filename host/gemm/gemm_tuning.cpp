// Per-device CLBlast GEMM parameters: problems, the tuning store, and installing it.
#include "gemm/gemm_tuning.hpp"

#include <iostream>

#include <clblast.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "gemm/clblast_check.hpp"

namespace mipnerf::gemm {
namespace {

// ---- what is installed, per device (CLBlast's own parameter cache is process-wide per device too) ----

struct DeviceState {
  GemmTuning tuning;
  bool installed = false;
  ParameterSet originals;  // CLBlast's database values of every kernel this process overrode
  ParameterSet applied;    // what CLBlast holds now for those kernels
  bool told_to_tune = false;
};

std::mutex& registry_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::map<cl_device_id, DeviceState>& registry() {
  static std::map<cl_device_id, DeviceState> states;
  return states;
}

std::unordered_map<std::string, size_t> to_clblast(const KernelParameters& p) { return {p.begin(), p.end()}; }

KernelParameters retrieve(cl_device_id device, const std::string& kernel) {
  std::unordered_map<std::string, size_t> values;
  check_clblast(clblast::RetrieveParameters(device, kernel, clblast::Precision::kSingle, values),
                "clblast::RetrieveParameters(" + kernel + ")");
  return {values.begin(), values.end()};
}

// Overrides one kernel's parameters unless CLBlast already holds exactly these.
void apply(cl_device_id device, DeviceState& state, const std::string& kernel, const KernelParameters& values) {
  if (!state.originals.count(kernel)) state.originals[kernel] = retrieve(device, kernel);
  auto it = state.applied.find(kernel);
  if (it != state.applied.end() && it->second == values) return;
  check_clblast(clblast::OverrideParameters(device, kernel, clblast::Precision::kSingle, to_clblast(values)),
                "clblast::OverrideParameters(" + kernel + ")");
  state.applied[kernel] = values;
}

// The values `kernel` should have for products of `kind`: the kind's set, else common, else the default.
const KernelParameters& wanted(const DeviceState& state, GemmKind kind, const std::string& kernel) {
  const auto kind_it = state.tuning.per_kind.find(kind);
  if (kind_it != state.tuning.per_kind.end()) {
    auto it = kind_it->second.find(kernel);
    if (it != kind_it->second.end()) return it->second;
  }
  auto it = state.tuning.common.find(kernel);
  if (it != state.tuning.common.end()) return it->second;
  return state.originals.at(kernel);
}

void restore_originals(cl_device_id device, DeviceState& state) {
  for (const auto& [kernel, values] : state.originals) {
    clblast::OverrideParameters(device, kernel, clblast::Precision::kSingle, to_clblast(values));
  }
  state.applied.clear();
  state.installed = false;
  state.tuning = GemmTuning{};
}

std::string sanitize(const std::string& text) {
  std::string out;
  for (char c : text) {
    const bool safe = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                      c == '-' || c == '+';
    out += safe ? c : '_';
  }
  // Runs of '_' collapse, so "pthread-haswell-AMD EPYC 7B13" stays readable.
  std::string collapsed;
  for (char c : out) {
    if (c == '_' && !collapsed.empty() && collapsed.back() == '_') continue;
    collapsed += c;
  }
  return collapsed;
}


const std::map<GemmKind, std::string>& kind_names() {
  static const std::map<GemmKind, std::string> names = {{GemmKind::forward, "forward"},
                                                        {GemmKind::backward_data, "backward_data"},
                                                        {GemmKind::backward_weights, "backward_weights"},
                                                        {GemmKind::other, "other"}};
  return names;
}

nlohmann::json set_to_json(const ParameterSet& set) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [kernel, values] : set) j[kernel] = values;
  return j;
}

ParameterSet set_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw Error(where + ": a parameter set must be an object of kernels");
  ParameterSet set;
  for (const auto& [kernel, values] : j.items()) {
    if (!values.is_object()) throw Error(where + ": kernel " + kernel + " must map parameter names to numbers");
    for (const auto& [name, value] : values.items()) {
      if (!value.is_number_unsigned()) throw Error(where + ": " + kernel + "." + name + " is not a whole number");
      set[kernel][name] = value.get<size_t>();
    }
  }
  return set;
}

}  // namespace

GemmKind gemm_kind(const GemmShape& s) {
  if (!s.transpose_a && !s.transpose_b) return GemmKind::forward;
  if (!s.transpose_a && s.transpose_b) return GemmKind::backward_data;
  if (s.transpose_a && !s.transpose_b) return GemmKind::backward_weights;
  return GemmKind::other;
}

const char* gemm_kind_name(GemmKind kind) { return kind_names().at(kind).c_str(); }

void add_gemm_problem(std::vector<GemmProblem>& problems, size_t m, size_t n, size_t k, bool ta, bool tb, size_t count) {
  if (count == 0) return;
  for (auto& p : problems) {
    if (p.shape.m == m && p.shape.n == n && p.shape.k == k && p.shape.transpose_a == ta && p.shape.transpose_b == tb) {
      p.count += count;
      return;
    }
  }
  GemmProblem p;
  p.shape.m = m;
  p.shape.n = n;
  p.shape.k = k;
  p.shape.transpose_a = ta;
  p.shape.transpose_b = tb;
  p.count = count;
  p.label = std::string(gemm_kind_name(p.kind())) + " " + std::to_string(m) + "x" + std::to_string(n) + "x" +
            std::to_string(k);
  problems.push_back(p);
}

std::string tuning_cache_dir() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg == '/') return std::string(xdg) + "/mipnerf-cl";
  const char* home = std::getenv("HOME");
  if (!home || !*home) throw Error("neither XDG_CACHE_HOME nor HOME is set: no folder for the GEMM tuning file");
  return std::string(home) + "/.cache/mipnerf-cl";
}

std::string tuning_file_path(const ocl::DeviceInfo& device) {
  return tuning_cache_dir() + "/gemm-" + sanitize(device.name) + "-" + sanitize(device.driver_version) +
         "-clblast-" + clblast_version() + ".json";
}

std::string to_json(const GemmTuning& t) {
  nlohmann::json j;
  j["format"] = "mipnerf-cl gemm tuning 1";
  j["device_name"] = t.device_name;
  j["driver_version"] = t.driver_version;
  j["clblast_version"] = t.clblast_version;
  j["common"] = set_to_json(t.common);
  nlohmann::json per_kind = nlohmann::json::object();
  for (const auto& [kind, set] : t.per_kind) per_kind[gemm_kind_name(kind)] = set_to_json(set);
  j["per_kind"] = per_kind;
  j["report"] = nlohmann::json::parse(t.report_json.empty() ? "{}" : t.report_json);
  if (t.auto_backend) {
    j["auto_backend"] = enum_name(*t.auto_backend);
    j["backend_measurement"] =
        nlohmann::json::parse(t.backend_measurement_json.empty() ? "{}" : t.backend_measurement_json);
  }
  if (!t.host_libraries.empty()) {
    j["host_libraries"] = t.host_libraries;
    j["host_libraries_measurement"] =
        nlohmann::json::parse(t.host_libraries_measurement_json.empty() ? "{}" : t.host_libraries_measurement_json);
  }
  return j.dump(2) + "\n";
}

GemmTuning tuning_from_json(const std::string& text, const std::string& where) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    throw Error(where + ": not valid JSON (" + e.what() + "); delete it and run `mipnerf-cl tune` again");
  }
  if (!j.is_object() || j.value("format", "") != "mipnerf-cl gemm tuning 1") {
    throw Error(where + ": not a mipnerf-cl GEMM tuning file");
  }
  GemmTuning t;
  t.device_name = j.value("device_name", "");
  t.driver_version = j.value("driver_version", "");
  t.clblast_version = j.value("clblast_version", "");
  t.common = set_from_json(j.value("common", nlohmann::json::object()), where);
  const nlohmann::json per_kind = j.value("per_kind", nlohmann::json::object());
  if (!per_kind.is_object()) throw Error(where + ": per_kind must be an object");
  for (const auto& [name, set] : per_kind.items()) {
    bool known = false;
    for (const auto& [kind, kind_name] : kind_names()) {
      if (kind_name == name) {
        t.per_kind[kind] = set_from_json(set, where + " per_kind." + name);
        known = true;
      }
    }
    if (!known) throw Error(where + ": unknown product kind '" + name + "'");
  }
  t.report_json = j.value("report", nlohmann::json::object()).dump();
  if (j.contains("auto_backend")) {
    const auto& value = j["auto_backend"];
    const std::string name = value.is_string() ? value.get<std::string>() : value.dump();
    t.auto_backend = enum_from_name<GemmBackend>(name);
    if (!t.auto_backend || *t.auto_backend == GemmBackend::automatic) {
      std::string names;
      for (const GemmBackend backend : gemm_backends()) {
        names += std::string(names.empty() ? "" : " or ") + enum_name(backend);
      }
      throw Error(where + ": auto_backend '" + name + "' is not " + names + "; run `mipnerf-cl tune` again");
    }
    t.backend_measurement_json = j.value("backend_measurement", nlohmann::json::object()).dump();
  }
  if (j.contains("host_libraries")) {
    const auto& choices = j["host_libraries"];
    if (!choices.is_object()) throw Error(where + ": host_libraries must be an object (product label → library)");
    for (const auto& [label, library] : choices.items()) {
      if (!library.is_string()) throw Error(where + ": host_libraries." + label + " must be a library name");
      t.host_libraries[label] = library.get<std::string>();
    }
    t.host_libraries_measurement_json = j.value("host_libraries_measurement", nlohmann::json::object()).dump();
  }
  return t;
}

void save_tuning(const std::string& path, const GemmTuning& tuning) {
  try {
    io::write_bytes_atomically(path, to_json(tuning));  // creates the folder; fsync, rename
  } catch (const Error& e) {
    throw Error(std::string(e.what()) + " (the GEMM tuning file; set XDG_CACHE_HOME to a writable folder)");
  }
}

std::optional<GemmTuning> read_tuning(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::stringstream text;
  text << in.rdbuf();
  return tuning_from_json(text.str(), path);
}

void install_gemm_tuning(ocl::Context& ctx, const GemmTuning& tuning) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  const cl_device_id device = ctx.raw_device();
  DeviceState& state = registry()[device];
  restore_originals(device, state);
  state.tuning = tuning;
  state.installed = true;
  try {
    // Validate every set now (CLBlast checks kernel names and completeness), then leave `common` applied.
    for (const auto& [kind, set] : tuning.per_kind) {
      for (const auto& [kernel, values] : set) apply(device, state, kernel, values);
    }
    for (const auto& [kernel, values] : tuning.common) apply(device, state, kernel, values);
    for (const auto& [kernel, values] : state.originals) apply(device, state, kernel, wanted(state, GemmKind::other, kernel));
  } catch (const Error&) {
    restore_originals(device, state);
    throw;
  }
}

void clear_gemm_tuning(ocl::Context& ctx) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  auto it = registry().find(ctx.raw_device());
  if (it != registry().end()) restore_originals(ctx.raw_device(), it->second);
}

bool gemm_tuning_installed(const ocl::Context& ctx) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  auto it = registry().find(ctx.raw_device());
  return it != registry().end() && it->second.installed;
}

void select_gemm_kind(ocl::Context& ctx, GemmKind kind) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  auto it = registry().find(ctx.raw_device());
  if (it == registry().end() || !it->second.installed || it->second.tuning.per_kind.empty()) return;
  DeviceState& state = it->second;
  for (const auto& [kernel, values] : state.originals) {
    (void)values;
    apply(ctx.raw_device(), state, kernel, wanted(state, kind, kernel));
  }
}

bool tuning_matches(const GemmTuning& tuning, const ocl::DeviceInfo& device) {
  return tuning.device_name == device.name && tuning.driver_version == device.driver_version &&
         tuning.clblast_version == clblast_version();
}

bool load_gemm_tuning(ocl::Context& ctx) {
  const ocl::DeviceInfo& device = ctx.device_info();
  const std::string path = tuning_file_path(device);
  std::optional<GemmTuning> tuning;
  try {
    tuning = read_tuning(path);
  } catch (const Error& e) {
    ctx.log(LogLevel::warning, std::string(e.what()) + "; using CLBlast's default GEMM parameters");
    return false;
  }
  if (tuning && !tuning_matches(*tuning, device)) {
    ctx.log(LogLevel::warning, path + " was written for another device, driver or CLBlast version; ignoring it "
                               "(run `mipnerf-cl tune` again)");
    tuning.reset();
  }
  if (tuning) {
    try {
      install_gemm_tuning(ctx, *tuning);
      ctx.log(LogLevel::info, "GEMM parameters tuned for " + device.name + " loaded from " + path);
      return true;
    } catch (const Error& e) {
      ctx.log(LogLevel::warning, path + " was refused by CLBlast (" + e.what() +
                                     "); using its default GEMM parameters; run `mipnerf-cl tune` again");
    }
  }
  std::lock_guard<std::mutex> lock(registry_mutex());
  DeviceState& state = registry()[ctx.raw_device()];
  if (!state.told_to_tune) {
    state.told_to_tune = true;
    ctx.log(LogLevel::info, "no tuned GEMM parameters for " + device.name +
                                "; CLBlast's defaults are used (`mipnerf-cl tune` measures better ones for this "
                                "device, which can speed training up several times on a CPU)");
  }
  return false;
}

void prepare_clblast_tuning(ocl::Context& ctx) {
  if (!gemm_tuning_installed(ctx)) load_gemm_tuning(ctx);
}

}  // namespace mipnerf::gemm

namespace mipnerf::gemm {

HostProductLibraries host_product_libraries_for(const ocl::DeviceInfo& device) {
  HostProductLibraries choice;
  const std::string path = tuning_file_path(device);
  std::optional<GemmTuning> tuning;
  try {
    tuning = read_tuning(path);
  } catch (const Error& e) {
    std::cerr << "mipnerf-cl: " << e.what() << "; the host MLP uses OpenBLAS for every product\n";
    return choice;
  }
  if (!tuning || !tuning_matches(*tuning, device)) return choice;
  for (const auto& [label, name] : tuning->host_libraries) {
    bool built_in = false;
    for (const auto& library : cpu_sgemm_libraries()) built_in = built_in || library.name == name;
    if (built_in) {
      choice.by_product[label] = name;
    } else {
      std::cerr << "mipnerf-cl: " << path << " chose " << name << " for " << label
                << ", which this build does not have; OpenBLAS runs it\n";
    }
  }
  return choice;
}

}  // namespace mipnerf::gemm
