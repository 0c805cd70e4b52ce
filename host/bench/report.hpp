// The record of `mipnerf-cl bench`: bench.json (every figure with the settings it was measured with, per device) and
// bench.md (the same as tables), with the device, driver, OpenCL C and CLBlast versions and the date.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/gemm_bench.hpp"
#include "bench/kernel_bench.hpp"
#include "bench/preset_bench.hpp"
#include "io/json.hpp"

namespace mipnerf::bench {

// Everything measured on one device. A section that failed leaves its result empty and an entry in `errors`.
struct DeviceBench {
  io::Json device = io::Json::object();  // eval::device_record: name, platform, driver and OpenCL C versions, ...
  std::string clblast_version;
  std::string tuning_file;                // where tuned GEMM parameters for this device would be
  bool tuning_found = false;              // and whether they were there (the tuned column needs them)
  std::optional<GemmBenchResult> gemm;
  std::optional<KernelBenchResult> kernels;
  std::vector<PresetBenchResult> presets;
  std::vector<std::pair<std::string, std::string>> errors;  // section, message
};

// How the training and render measurements were set up (shared by every device of a run).
struct PresetBenchSettings {
  std::string scene;           // what was trained on, e.g. "procedural scene, 64x64, 40 train views"
  std::map<std::string, std::string> settings;  // applied over every preset (--set), as given
  int64_t warm_steps = 0;      // CPU presets (tiny, quick, small)
  int64_t paper_warm_steps = 0;
  double time_box_seconds = 0.0;
  size_t render_reps = 0;
};

struct BenchRun {
  std::string version;               // mipnerf-cl's
  std::string date;                  // ISO 8601, UTC, when it started
  std::string command;               // the command line
  bool quick = false;
  io::Json host = io::Json::object();         // host_record() when it started
  io::Json host_at_end = io::Json::object();  // host_record() when it ended (load averages), empty until then
  io::Json machine = io::Json::object();      // probe_machine() at the start: FMA peak, triad, large sgemm
  PresetBenchSettings presets;
  std::vector<DeviceBench> devices;
  double seconds = 0.0;              // wall time of the whole run so far
  bool complete = false;             // false while running, or when interrupted
};

// The machine around the devices: CPU model, hardware threads, load averages, PoCL's kernel cache setting.
io::Json host_record();

// bench.json's content, keys in reading order.
nlohmann::ordered_json bench_json(const BenchRun& run);

// bench.md: what ran where, then per device the GEMM, kernel, training and render tables with their settings.
std::string bench_markdown(const BenchRun& run);

}  // namespace mipnerf::bench
