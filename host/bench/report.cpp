// bench.json and bench.md of `mipnerf-cl bench` (see report.hpp).
#include "bench/report.hpp"

#include "bench/machine_probe.hpp"
#include "bench/stage_report.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

namespace mipnerf::bench {
namespace {

using Ordered = nlohmann::ordered_json;

constexpr double kMiB = 1024.0 * 1024.0;

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "–";
  char text[32];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  return text;
}

std::string general(double v) {  // 3 significant digits: 6.71e+07
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", v);
  return text;
}

std::string cpu_model() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
    }
  }
  return "unknown";
}

std::string pocl_kernel_cache() {
  const char* cache = std::getenv("POCL_KERNEL_CACHE");
  const char* dir = std::getenv("POCL_CACHE_DIR");
  std::string text = cache && std::string(cache) == "0" ? "off (POCL_KERNEL_CACHE=0): first builds compile"
                                                        : "on: first builds may be served from PoCL's disk cache";
  if (dir) text += std::string(", POCL_CACHE_DIR=") + dir;
  return text;
}

std::string json_text(const io::Json& j, const char* key) {
  if (!j.contains(key)) return "?";
  return j[key].is_string() ? j[key].get<std::string>() : j[key].dump();
}

std::string load_text(const io::Json& host) {
  if (!host.contains("load_average_1_5_15_min")) return "?";
  std::string text;
  for (const auto& v : host["load_average_1_5_15_min"]) text += (text.empty() ? "" : ", ") + fixed(v.get<double>(), 2);
  return text;
}

std::string settings_text(const std::map<std::string, std::string>& settings) {
  std::string text;
  for (const auto& [name, value] : settings) text += (text.empty() ? "" : ", ") + name + " = " + value;
  return text;
}

// ---- bench.json ----

Ordered gemm_json(const DeviceBench& d) {
  Ordered j;
  j["tuning_file"] = d.tuning_file;
  j["tuned"] = d.tuning_found;
  if (!d.tuning_found) j["note"] = "no tuning file for this device: CLBlast's defaults only (run `mipnerf-cl tune`)";
  if (!d.gemm) return j;
  const auto& g = *d.gemm;
  j["settings"] = {{"rows", g.options.rows},
                   {"widths", g.options.widths},
                   {"rounds", g.options.rounds},
                   {"reps", g.options.reps},
                   {"warm_up_calls", 1},
                   {"timing", "wall time of one mlp::gemm call with clFinish; GFLOP/s = 2mnk / time, from the best "
                              "and the median of rounds x reps calls; the first call of each product timed apart"}};
  Ordered products = Ordered::array();
  for (size_t i = 0; i < g.products.size(); ++i) {
    const auto& p = g.products[i];
    Ordered row = {{"kind", p.kind}, {"layout", p.layout()}, {"m", p.shape.m}, {"n", p.shape.n}, {"k", p.shape.k}};
    for (const auto& s : g.series) {
      row[s.name] = {{"gflops_best", s.gflops_best(p, i)},
                     {"gflops_median", s.gflops_median(p, i)},
                     {"seconds_best", s.calls[i].best()},
                     {"seconds_median", s.calls[i].median()},
                     {"first_call_seconds", s.first_call_seconds.at(i)}};
    }
    products.push_back(row);
  }
  j["products"] = products;
  return j;
}

Ordered kernels_json(const KernelBenchResult& k) {
  Ordered j;
  j["settings"] = {{"rays", k.options.rays},
                   {"samples", k.options.samples},
                   {"reps", k.options.reps},
                   {"reference_reps", k.options.reference_reps},
                   {"timing", "wall time per call with clFinish after one first call (timed apart); items/s from the "
                              "best call; CPU reference: host/ref in double, one thread, best call"}};
  Ordered programs = Ordered::array();
  for (const auto& b : k.builds) programs.push_back({{"program", b.program}, {"first_build_seconds", b.seconds}});
  j["programs"] = programs;
  Ordered stages = Ordered::array();
  for (const auto& s : k.stages) {
    stages.push_back({{"stage", s.stage},
                      {"unit", s.unit},
                      {"items", s.items},
                      {"first_call_seconds", s.first_call_seconds},
                      {"seconds_best", s.device.best()},
                      {"seconds_median", s.device.median()},
                      {"items_per_second", s.items_per_second()},
                      {"reference_seconds", s.reference_seconds},
                      {"reference_items_per_second", s.reference_items_per_second()}});
  }
  j["stages"] = stages;
  return j;
}

Ordered training_json(const PresetBenchResult& p) {
  const auto& t = p.train;
  return {{"preset", p.preset},
          {"batch_rays", t.batch_rays},
          {"samples_per_level", p.config.num_samples},
          {"levels", p.config.num_levels},
          {"parameters", t.parameters},
          {"chunk_rays", t.chunk_rays},
          {"gemm_backend", t.gemm_backend},
          {"gemm_parameters", t.gemm_parameters()},
          {"setup_seconds", t.setup_seconds},
          {"first_step_seconds", t.first_step_seconds},
          {"warm_steps", t.warm_steps.count()},
          {"warm_step_seconds", t.warm_steps.seconds},
          {"step_seconds_best", t.warm_steps.best()},
          {"step_seconds_median", t.warm_steps.median()},
          {"rays_per_second", t.rays_per_second()},
          {"time_boxed", t.time_boxed},
          {"planned_device_bytes", t.planned_device_bytes},
          {"memory_budget_bytes", t.memory_budget_bytes},
          {"peak_rss_bytes", t.peak_rss_bytes},
          {"peak_rss_scope", t.peak_rss_reset ? "setup and steps of this preset" : "the whole process so far"},
          {"stage_profile", t.profile ? stage_profile_json(*t.profile, t.batch_rays) : Ordered(nullptr)},
          {"config", nlohmann::ordered_json::parse(train::to_json(p.config))}};
}

Ordered render_json(const PresetBenchResult& p) {
  const auto& r = *p.render;
  return {{"preset", p.preset},
          {"width", r.width},
          {"height", r.height},
          {"rays_per_pixel", 1},
          {"chunk_rays", r.chunk_rays},
          {"warm_up_seconds", r.warm_up_seconds},
          {"renders", r.renders.count()},
          {"render_seconds_best", r.renders.best()},
          {"render_seconds_median", r.renders.median()},
          {"seconds_per_megapixel", r.seconds_per_megapixel()},
          {"stage_profile", r.profile ? stage_profile_json(*r.profile, static_cast<size_t>(r.width) * r.height)
                                      : Ordered(nullptr)}};
}

Ordered device_json(const DeviceBench& d) {
  Ordered j;
  j["device"] = d.device;
  j["clblast_version"] = d.clblast_version;
  j["gemm"] = gemm_json(d);
  j["kernels"] = d.kernels ? kernels_json(*d.kernels) : Ordered(nullptr);
  Ordered training = Ordered::array(), render = Ordered::array();
  for (const auto& p : d.presets) {
    training.push_back(training_json(p));
    if (p.render) render.push_back(render_json(p));
  }
  j["training"] = training;
  j["render"] = render;
  Ordered errors = Ordered::array();
  for (const auto& [section, message] : d.errors) errors.push_back({{"section", section}, {"message", message}});
  j["errors"] = errors;
  return j;
}

// ---- bench.md ----

std::string gemm_markdown(const DeviceBench& d) {
  std::ostringstream md;
  md << "### GEMM (CLBlast), GFLOP/s\n\n";
  if (!d.tuning_found) {
    md << "No tuning file for this device (" << d.tuning_file << "): CLBlast's defaults only; `mipnerf-cl tune` "
       << "measures better parameters.\n\n";
  } else {
    md << "Tuned parameters: " << d.tuning_file << ".\n\n";
  }
  if (!d.gemm) return md.str();
  const auto& g = *d.gemm;
  md << "Settings: " << g.options.rows << " rows, widths";
  for (size_t w : g.options.widths) md << " " << w;
  md << "; per configuration and product a first call (timed apart), one warm-up call, then " << g.options.rounds
     << " round(s) x " << g.options.reps << " calls, each with clFinish. GFLOP/s = 2mnk / wall time of the best call "
     << "(median in brackets).\n\n";
  md << "| product | m×n×k |";
  for (const auto& s : g.series) md << " " << s.name << " |";
  md << "\n|---|---|";
  for (size_t c = 0; c < g.series.size(); ++c) md << "---:|";
  md << "\n";
  for (size_t i = 0; i < g.products.size(); ++i) {
    const auto& p = g.products[i];
    md << "| " << p.kind << " (" << p.layout() << ") | " << p.shape.m << "×" << p.shape.n << "×" << p.shape.k << " |";
    for (const auto& s : g.series) md << " " << fixed(s.gflops_best(p, i), 1) << " (" << fixed(s.gflops_median(p, i), 1) << ") |";
    md << "\n";
  }
  md << "\nFirst call of each product kind (cold: CLBlast builds the program of its parameter set; width "
     << (g.options.widths.empty() ? 0 : g.options.widths.front()) << "), seconds:\n\n";
  for (const auto& s : g.series) {
    md << "- " << s.name << ":";
    for (size_t i = 0; i < std::min<size_t>(3, s.first_call_seconds.size()); ++i) {
      md << " " << g.products[i].kind << " " << fixed(s.first_call_seconds[i], 2) << ";";
    }
    if (s.first_call_seconds.size() > 3) md << " later widths:";
    for (size_t i = 3; i < s.first_call_seconds.size(); ++i) md << " " << fixed(s.first_call_seconds[i], 2);
    md << "\n";
  }
  md << "\n";
  return md.str();
}

std::string kernels_markdown(const KernelBenchResult& k) {
  std::ostringstream md;
  md << "### Ray-math kernels\n\nSettings: " << k.options.rays << " rays x " << k.options.samples
     << " samples; a first call (timed apart), then " << k.options.reps
     << " calls with clFinish, items/s from the best (median ms in brackets). CPU reference: host/ref in double, one "
        "thread, best of "
     << k.options.reference_reps << ".\n\n";
  md << "| stage | items | first call ms | device ms best (median) | device items/s | CPU ref items/s | device / ref |\n";
  md << "|---|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& s : k.stages) {
    const bool ref = s.reference_seconds > 0;
    md << "| " << s.stage << " | " << s.items << " " << s.unit << " | " << fixed(1e3 * s.first_call_seconds, 3) << " | "
       << fixed(1e3 * s.device.best(), 3) << " (" << fixed(1e3 * s.device.median(), 3) << ") | "
       << general(s.items_per_second()) << " | " << (ref ? general(s.reference_items_per_second()) : "–") << " | "
       << (ref ? fixed(s.reference_seconds / s.device.best(), 1) + "x" : "–") << " |\n";
  }
  md << "\nFirst build of each program (cold, in a fresh context):\n\n| program | first build s |\n|---|---:|\n";
  for (const auto& b : k.builds) md << "| " << b.program << " | " << fixed(b.seconds, 2) << " |\n";
  md << "\n";
  return md.str();
}

std::string network_text(const train::TrainConfig& c) {
  return std::to_string(c.mlp_depth) + "×" + std::to_string(c.mlp_width);
}

std::string training_markdown(const DeviceBench& d, const PresetBenchSettings& s) {
  std::ostringstream md;
  md << "### Training steps\n\nSettings: " << s.scene << "; each preset as `mipnerf-cl train --preset P` has it, "
     << "trained for a first step (cold: kernel first launches, CLBlast's program builds) then up to " << s.warm_steps
     << " warm steps (paper: " << s.paper_warm_steps << ")";
  if (!s.settings.empty()) md << ", with " << settings_text(s.settings) << " over every preset";
  if (s.time_box_seconds > 0) md << ", no new warm step after " << fixed(s.time_box_seconds, 0) << " s of them";
  md << ". Setup = loading and uploading the data and building the graph. rays/s from the median warm step. Planned "
        "device memory: the trainer's plan (graph, data, networks, Adam); peak RSS: the process's (getrusage), "
        "which on a CPU device holds the device buffers.\n\n";
  md << "| preset | rays × samples/level × levels | MLP | parameters | chunk | GEMM | setup s | first step s | warm "
        "s/step best (median) | warm steps | rays/s | planned device MiB | peak RSS MiB |\n";
  md << "|---|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& p : d.presets) {
    const auto& t = p.train;
    md << "| " << p.preset << " | " << t.batch_rays << " × " << p.config.num_samples << " × " << p.config.num_levels
       << " | " << network_text(p.config) << " | " << t.parameters << " | " << t.chunk_rays << " | "
       << t.gemm_label() << " | " << fixed(t.setup_seconds, 2) << " | "
       << fixed(t.first_step_seconds, 2) << " | " << fixed(t.warm_steps.best(), 3) << " ("
       << fixed(t.warm_steps.median(), 3) << ") | " << t.warm_steps.count() << (t.time_boxed ? " (time box)" : "")
       << " | " << fixed(t.rays_per_second(), 0) << " | " << fixed(t.planned_device_bytes / kMiB, 0) << " | "
       << fixed(t.peak_rss_bytes / kMiB, 0) << (t.peak_rss_reset ? "" : " (process)") << " |\n";
  }
  md << "\n";
  return md.str();
}

std::string profile_markdown(const DeviceBench& d, const io::Json& machine) {
  std::ostringstream md;
  for (const auto& p : d.presets) {
    if (!p.train.profile) continue;
    md << "#### Where a " << p.preset << " step's time goes\n\n"
       << stage_profile_markdown(*p.train.profile, p.train.batch_rays, machine) << "\n";
  }
  const std::string tables = md.str();
  if (tables.empty()) return "";
  return "### Training step by stage\n\nProfiled steps after the timed ones (each ends with a clFinish and records an "
         "event per command, so they run a little slower than the timed steps). Stages: the graph's (host/graph) and "
         "the trainer's; \"gemm <kind>\" are the MLP's products by kind.\n\n" + tables;
}

std::string render_markdown(const DeviceBench& d, const PresetBenchSettings& s, const io::Json& machine) {
  std::ostringstream md;
  md << "### Rendering\n\nSettings: the first training camera resized, one ray per pixel, the trained networks of the "
        "row above; first chunk timed apart (programs the inference graph builds beyond training's), then "
     << s.render_reps << " timed render(s); s/MP from the best.\n\n";
  md << "| preset | image | chunk | first chunk s | render s best (median) | s/MP |\n|---|---|---:|---:|---:|---:|\n";
  for (const auto& p : d.presets) {
    if (!p.render) continue;
    const auto& r = *p.render;
    md << "| " << p.preset << " | " << r.width << "x" << r.height << " | " << r.chunk_rays << " | "
       << fixed(r.warm_up_seconds, 2) << " | " << fixed(r.renders.best(), 3) << " (" << fixed(r.renders.median(), 3)
       << ") | " << fixed(r.seconds_per_megapixel(), 2) << " |\n";
  }
  md << "\n";
  for (const auto& p : d.presets) {
    if (!p.render || !p.render->profile) continue;
    const auto& r = *p.render;
    md << "#### Where a " << p.preset << " render's time goes (" << r.width << "x" << r.height
       << ", one more render with profiling events)\n\n"
       << stage_profile_markdown(*r.profile, static_cast<size_t>(r.width) * r.height, machine, "image") << "\n";
  }
  return md.str();
}

std::string device_markdown(const DeviceBench& d, const BenchRun& run) {
  std::ostringstream md;
  md << "## " << json_text(d.device, "name") << "\n\n| | |\n|---|---|\n";
  md << "| platform | " << json_text(d.device, "platform") << " |\n";
  md << "| type | " << json_text(d.device, "type") << ", " << json_text(d.device, "compute_units") << " compute units, "
     << fixed(d.device.value("global_memory_bytes", 0.0) / (kMiB * 1024.0), 1) << " GiB global memory |\n";
  md << "| driver version | " << json_text(d.device, "driver_version") << " |\n";
  md << "| OpenCL C version | " << json_text(d.device, "opencl_c_version") << " |\n";
  md << "| CLBlast | " << d.clblast_version << " |\n\n";
  md << gemm_markdown(d);
  if (d.kernels) md << kernels_markdown(*d.kernels);
  if (!d.presets.empty())
    md << training_markdown(d, run.presets) << profile_markdown(d, run.machine) << render_markdown(d, run.presets, run.machine);
  if (!d.errors.empty()) {
    md << "### Sections that failed\n\n";
    for (const auto& [section, message] : d.errors) md << "- " << section << ": " << message << "\n";
    md << "\n";
  }
  return md.str();
}

}  // namespace

io::Json host_record() {
  double load[3] = {0, 0, 0};
  const int n = getloadavg(load, 3);
  io::Json j = {{"cpu", cpu_model()},
                {"hardware_threads", std::thread::hardware_concurrency()},
                {"pocl_kernel_cache", pocl_kernel_cache()}};
  if (n == 3) j["load_average_1_5_15_min"] = {load[0], load[1], load[2]};
  return j;
}

Ordered bench_json(const BenchRun& run) {
  Ordered j;
  j["tool"] = "mipnerf-cl bench";
  j["version"] = run.version;
  j["date"] = run.date;
  j["command"] = run.command;
  j["complete"] = run.complete;
  j["seconds"] = run.seconds;
  j["quick"] = run.quick;
  j["host"] = run.host;
  j["machine"] = run.machine;
  if (!run.host_at_end.empty()) j["host_at_end"] = run.host_at_end;
  j["definitions"] = {
      {"first_call", "the first call of a measurement in a fresh OpenCL context with CLBlast's compiled programs "
                     "forgotten: kernel and CLBlast program builds (PoCL's disk cache may serve them), first launches"},
      {"gflops", "2*m*n*k / wall seconds of one mlp::gemm call followed by clFinish"},
      {"items_per_second", "items / wall seconds of the best call followed by clFinish"},
      {"rays_per_second", "batch rays / seconds of the median warm training step (wall time between step reports)"},
      {"seconds_per_megapixel", "wall seconds of the best whole-image render / megapixels"},
      {"planned_device_bytes", "train::Trainer::memory().total(): graph buffers, MLP workspaces, data, networks, Adam"},
      {"peak_rss_bytes", "getrusage ru_maxrss of the process (reset before each preset where Linux allows)"}};
  j["training_settings"] = {{"scene", run.presets.scene},
                            {"settings_over_presets", run.presets.settings},
                            {"warm_steps", run.presets.warm_steps},
                            {"paper_warm_steps", run.presets.paper_warm_steps},
                            {"time_box_seconds", run.presets.time_box_seconds},
                            {"render_reps", run.presets.render_reps}};
  Ordered devices = Ordered::array();
  for (const auto& d : run.devices) devices.push_back(device_json(d));
  j["devices"] = devices;
  return j;
}

std::string bench_markdown(const BenchRun& run) {
  std::ostringstream md;
  md << "# mipnerf-cl bench\n\n";
  md << "Date: " << run.date << " (UTC). mipnerf-cl " << run.version << ". Command: `" << run.command << "`"
     << (run.complete ? "" : " — **incomplete** (still running, or interrupted)") << "; " << fixed(run.seconds, 0)
     << " s in all.\n\n";
  md << "Host: " << json_text(run.host, "cpu") << ", " << json_text(run.host, "hardware_threads")
     << " hardware threads; load average (1, 5, 15 min) at the start " << load_text(run.host);
  if (!run.host_at_end.empty()) md << ", at the end " << load_text(run.host_at_end);
  md << ". PoCL kernel cache: " << json_text(run.host, "pocl_kernel_cache") << ".\n\n";
  const std::string machine = machine_summary(run.machine);
  if (!machine.empty()) md << "Machine limits (probed at the start, host/bench/machine_probe.hpp): " << machine << ".\n\n";
  md << "Each section runs in a fresh OpenCL context with CLBlast's compiled programs forgotten, so \"first\" figures "
        "are what a new process pays (PoCL's disk cache aside). Figures are wall times, measured, never asserted.\n\n";
  for (const auto& d : run.devices) md << device_markdown(d, run);
  return md.str();
}

}  // namespace mipnerf::bench
