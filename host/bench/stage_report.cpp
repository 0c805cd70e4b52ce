// Stage profile tables (see stage_report.hpp).
#include "bench/stage_report.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace mipnerf::bench {
namespace {

const std::string kGemmPrefix = "gemm ";

std::string format(const char* pattern, double v) {
  char text[64];
  std::snprintf(text, sizeof text, pattern, v);
  return text;
}

double per_step(double total, size_t steps) { return steps ? total / static_cast<double>(steps) : 0.0; }

// A machine-probe figure on all threads (best of its runs), e.g. "triad_gbs"; 0 when the run did not probe.
double probed_all_threads(const io::Json& machine, const char* figure) {
  if (!machine.contains(figure)) return 0.0;
  return machine[figure].value("all_threads", io::Json::object()).value("best", 0.0);
}

}  // namespace

GemmLimit gemm_limit(const ocl::StageProfile& profile, size_t rays_per_step) {
  GemmLimit g;
  g.step_seconds = per_step(profile.wall_seconds, profile.steps);
  g.gemm_seconds = per_step(profile.seconds_with_prefix(kGemmPrefix), profile.steps);
  double flops = 0.0;
  for (const auto& s : profile.stages) {
    if (s.stage.rfind(kGemmPrefix, 0) == 0) flops += s.flops;
  }
  const double gemm_total = profile.seconds_with_prefix(kGemmPrefix);
  g.gemm_gflops = gemm_total > 0 ? flops / gemm_total * 1e-9 : 0.0;
  const double rays = static_cast<double>(rays_per_step);
  g.rays_per_second = g.step_seconds > 0 ? rays / g.step_seconds : 0.0;
  g.limit_rays_per_second = g.gemm_seconds > 0 ? rays / g.gemm_seconds : 0.0;
  return g;
}

std::string stage_profile_markdown(const ocl::StageProfile& profile, size_t rays_per_step, const io::Json& machine,
                                   const std::string& unit) {
  std::vector<ocl::StageTime> stages = profile.stages;
  std::stable_sort(stages.begin(), stages.end(),
                   [](const ocl::StageTime& a, const ocl::StageTime& b) { return a.seconds > b.seconds; });
  const size_t n = std::max<size_t>(1, profile.steps);
  const double step = per_step(profile.wall_seconds, n);
  auto share = [&](double seconds_per_step) { return step > 0 ? format("%.1f %%", 100.0 * seconds_per_step / step) : "–"; };
  const double triad = probed_all_threads(machine, "triad_gbs");
  std::ostringstream md;
  md << "| stage | ms/" << unit << " | share of " << unit << " | commands/" << unit
     << " | GFLOP/s | GB/s (least traffic) | of the triad |\n|---|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& s : stages) {
    const double ms = 1e3 * per_step(s.seconds, n);
    const double gbs = s.bytes > 0 && s.seconds > 0 ? s.bytes / s.seconds * 1e-9 : 0.0;
    md << "| " << s.stage << " | " << format("%.2f", ms) << " | " << share(ms * 1e-3) << " | "
       << format("%.0f", per_step(static_cast<double>(s.commands), n)) << " | "
       << (s.flops > 0 && s.seconds > 0 ? format("%.1f", s.flops / s.seconds * 1e-9) : "–") << " | "
       << (gbs > 0 ? format("%.2f", gbs) : "–") << " | "
       << (gbs > 0 && triad > 0 ? format("%.0f %%", 100.0 * gbs / triad) : "–") << " |\n";
  }
  const double outside = step - per_step(profile.stage_seconds(), n);
  md << "| (host time between commands: launches, waits) | " << format("%.2f", 1e3 * outside) << " | "
     << share(outside) << " | | | | |\n";
  md << "| **" << unit << " (wall)** | **" << format("%.2f", 1e3 * step) << "** | 100 % | | | | |\n\n";
  const GemmLimit g = gemm_limit(profile, rays_per_step);
  md << "GEMM-bound limit: " << format("%.0f", g.limit_rays_per_second) << " rays/s (the MLP products alone, "
     << format("%.1f", g.gemm_gflops) << " GFLOP/s); the " << unit << " runs " << format("%.0f", g.rays_per_second)
     << " rays/s = " << format("%.0f", 100.0 * g.fraction()) << " % of it. Per " << unit << " over " << profile.steps
     << " profiled " << unit << "(s); device times from OpenCL profiling events, host products from host timers.\n";
  const double peak = probed_all_threads(machine, "fma_peak_gflops");
  const double sgemm = machine.contains("large_sgemm_gflops") ? machine["large_sgemm_gflops"].value("best", 0.0) : 0.0;
  if (peak > 0 && sgemm > 0 && g.gemm_gflops > 0) {
    md << "\nThe products' " << format("%.1f", g.gemm_gflops) << " GFLOP/s are " << format("%.0f", 100 * g.gemm_gflops / peak)
       << " % of this machine's FMA peak (" << format("%.1f", peak) << " GFLOP/s) and "
       << format("%.0f", 100 * g.gemm_gflops / sgemm) << " % of its large-sgemm rate (" << format("%.1f", sgemm)
       << " GFLOP/s), both probed in this run.\n";
  }
  md << "\nGB/s (least traffic): the bytes a stage must move at least (each input read once, each output written once; "
        "host/graph/stage_traffic.hpp) per second of it — a lower bound on the bandwidth it achieved. Beside the "
        "machine's STREAM triad"
     << (triad > 0 ? " (" + format("%.1f", triad) + " GB/s, probed in this run)" : " (not probed in this run)")
     << ": a stage near 100 % is memory-bound, one far below it is limited by its arithmetic. The MLP's stages "
        "declare FLOPs instead (they work on blocks in cache).\n";
  return md.str();
}

nlohmann::ordered_json stage_profile_json(const ocl::StageProfile& profile, size_t rays_per_step) {
  nlohmann::ordered_json stages = nlohmann::ordered_json::array();
  for (const auto& s : profile.stages) {
    stages.push_back({{"stage", s.stage},
                      {"seconds_per_step", per_step(s.seconds, profile.steps)},
                      {"commands_per_step", per_step(static_cast<double>(s.commands), profile.steps)},
                      {"flops_per_step", per_step(s.flops, profile.steps)},
                      {"least_bytes_per_step", per_step(s.bytes, profile.steps)}});
  }
  const GemmLimit g = gemm_limit(profile, rays_per_step);
  return {{"profiled_steps", profile.steps},
          {"step_seconds", g.step_seconds},
          {"stages", stages},
          {"outside_stages_seconds_per_step", g.step_seconds - per_step(profile.stage_seconds(), profile.steps)},
          {"gemm_seconds_per_step", g.gemm_seconds},
          {"gemm_gflops", g.gemm_gflops},
          {"gemm_limit_rays_per_second", g.limit_rays_per_second},
          {"rays_per_second", g.rays_per_second},
          {"gemm_limit_fraction", g.fraction()}};
}

}  // namespace mipnerf::bench
