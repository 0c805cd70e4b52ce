// CLBlast (and a caller's host BLAS) on the MLP's products, and the whole network on one chunk (see gemm_bench.hpp).
#include "bench/gemm_bench.hpp"

#include <algorithm>
#include <cstdio>
#include <random>

#include <clblast.h>

#include "core/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/gemm_backend.hpp"

namespace mipnerf::bench {

std::string GemmProduct::label() const {
  return kind + " " + std::to_string(shape.m) + "x" + std::to_string(shape.n) + "x" + std::to_string(shape.k);
}

std::string GemmProduct::layout() const {
  return shape.transpose_a ? "Aᵀ·B" : (shape.transpose_b ? "A·Bᵀ" : "A·B");
}

std::vector<GemmProduct> mlp_products(const std::vector<size_t>& widths, size_t rows) {
  std::vector<GemmProduct> products;
  for (size_t w : widths) {
    gemm::GemmShape forward, data, weights;
    forward.m = data.m = rows;
    forward.n = forward.k = data.n = data.k = w;
    data.transpose_b = true;
    weights.m = weights.n = w;
    weights.k = rows;
    weights.transpose_a = true;
    products.push_back({"forward", forward});
    products.push_back({"backward data", data});
    products.push_back({"backward weights", weights});
  }
  return products;
}

namespace {

struct OperandSizes {
  size_t a = 0, b = 0, c = 0;
};

OperandSizes largest_operands(const std::vector<GemmProduct>& products) {
  OperandSizes s;
  for (const auto& p : products) {
    s.a = std::max(s.a, p.shape.m * p.shape.k);
    s.b = std::max(s.b, p.shape.k * p.shape.n);
    s.c = std::max(s.c, p.shape.m * p.shape.n);
  }
  if (s.a == 0 || s.b == 0 || s.c == 0) throw Error("GEMM benchmark: every product needs rows and a width of at least 1");
  return s;
}

}  // namespace

GemmOperands::GemmOperands(ocl::Context& ctx, const std::vector<GemmProduct>& products)
    : a(largest_operands(products).a),
      b(largest_operands(products).b),
      c(largest_operands(products).c),
      a_device(ctx, a.size(), "A"),
      b_device(ctx, b.size(), "B"),
      c_device(ctx, c.size(), "C") {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  for (auto& v : a) v = dist(rng);
  for (auto& v : b) v = dist(rng);
  a_device.upload(ctx, a);
  b_device.upload(ctx, b);
}

double time_gemm(ocl::Context& ctx, gemm::GemmBackend backend, GemmOperands& operands, const GemmProduct& product) {
  const auto& s = product.shape;
  const size_t lda = s.transpose_a ? s.m : s.k, ldb = s.transpose_b ? s.k : s.n;
  return time_call([&] {
    gemm::sgemm(ctx, backend, s, 1.0f, ocl::view(operands.a_device, lda), ocl::view(operands.b_device, ldb), 0.0f,
                ocl::view(operands.c_device, s.n), product.label());
    ctx.finish();
  });
}

double GemmSeries::gflops_best(const GemmProduct& p, size_t i) const {
  const double s = calls.at(i).best();
  return s > 0 ? p.flops() / s * 1e-9 : 0.0;
}

double GemmSeries::gflops_median(const GemmProduct& p, size_t i) const {
  const double s = calls.at(i).median();
  return s > 0 ? p.flops() / s * 1e-9 : 0.0;
}

namespace {

void install(ocl::Context& ctx, const GemmConfig& config) {
  if (config.on_host()) return;
  if (config.tuning) {
    gemm::install_gemm_tuning(ctx, *config.tuning);
  } else {
    gemm::clear_gemm_tuning(ctx);
  }
}

// One configuration's pass over every product.
void time_round(ocl::Context& ctx, GemmOperands& operands, const std::vector<GemmProduct>& products,
                const GemmConfig& config, const GemmBenchOptions& options, bool first_round, GemmSeries& series,
                const std::function<void(size_t)>& after_product) {
  install(ctx, config);
  const auto call = [&](const GemmProduct& p) {
    return config.on_host() ? config.host_call(p, operands) : time_gemm(ctx, gemm::GemmBackend::clblast, operands, p);
  };
  for (size_t i = 0; i < products.size(); ++i) {
    const double first = call(products[i]);
    if (first_round) series.first_call_seconds.push_back(first);
    if (!config.on_host()) call(products[i]);  // warm-up after a parameter switch
    for (size_t r = 0; r < options.reps; ++r) series.calls[i].add(call(products[i]));
    after_product(i);
  }
}

}  // namespace

GemmBenchResult run_gemm_bench(ocl::Context& ctx, const GemmBenchOptions& options,
                               const std::vector<GemmConfig>& configs, const ProgressFn& progress) {
  if (options.reps == 0 || options.rounds == 0) throw Error("GEMM benchmark: reps and rounds must be at least 1");
  GemmBenchResult result;
  result.options = options;
  result.products = mlp_products(options.widths, options.rows);
  GemmOperands operands(ctx, result.products);
  for (const auto& config : configs) {
    GemmSeries series;
    series.name = config.name;
    series.calls.resize(result.products.size());
    result.series.push_back(std::move(series));
  }
  const size_t total = options.rounds * configs.size() * result.products.size();
  size_t done = 0;
  try {
    for (size_t round = 0; round < options.rounds; ++round) {
      for (size_t c = 0; c < configs.size(); ++c) {
        GemmSeries& series = result.series[c];
        time_round(ctx, operands, result.products, configs[c], options, round == 0, series, [&](size_t i) {
          if (!progress) return;
          char figure[64];
          std::snprintf(figure, sizeof(figure), ": %.1f GFLOP/s", series.gflops_best(result.products[i], i));
          progress("round " + std::to_string(round + 1) + " " + series.name + " " + result.products[i].label() + figure,
                   ++done, total);
        });
      }
    }
  } catch (...) {
    gemm::clear_gemm_tuning(ctx);
    throw;
  }
  gemm::clear_gemm_tuning(ctx);
  return result;
}

std::vector<GemmConfig> clblast_configs(const std::optional<gemm::GemmTuning>& tuning) {
  std::vector<GemmConfig> configs = {{"CLBlast default", std::nullopt, {}}};
  if (tuning) configs.push_back({"CLBlast tuned", tuning, {}});
  return configs;
}

std::optional<GemmConfig> host_backend_config(ocl::Context& ctx) {
  try {
    gemm::resolve_gemm_backend(gemm::GemmBackend::host, ctx.device_info(), gemm::host_blas_available());
  } catch (const Error&) {
    return std::nullopt;  // a device with its own memory, or no host BLAS in this build
  }
  gemm::choose_gemm_backend(ctx, gemm::GemmBackend::host);  // sets the BLAS's threads as a run would
  GemmConfig config;
  config.name = "host BLAS (mapped)";
  config.host_call = [&ctx](const GemmProduct& product, GemmOperands& operands) {
    return time_gemm(ctx, gemm::GemmBackend::host, operands, product);
  };
  return config;
}

MlpChunkTimes time_mlp_chunk(ocl::Context& ctx, mlp::Network& net, size_t rays, size_t samples, size_t reps) {
  const size_t rows = rays * samples;
  const auto& c = net.config();
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  auto random_array = [&](size_t n, const char* name) {
    std::vector<float> v(n);
    for (auto& x : v) x = dist(rng);
    ocl::DeviceArray<float> a(ctx, n, name);
    a.upload(ctx, v);
    return a;
  };
  auto features = random_array(rows * c.input_width, "features");
  auto view = random_array(rays * c.view_width, "view encoding");
  auto d_density = random_array(rows, "d_raw_density"), d_rgb = random_array(rows * 3, "d_raw_rgb");
  ocl::DeviceArray<float> density(ctx, rows, "raw_density"), rgb(ctx, rows * 3, "raw_rgb");
  auto train_ws = net.make_workspace(rows, rays, mlp::WorkspaceMode::training);
  auto infer_ws = net.make_workspace(rows, rays, mlp::WorkspaceMode::inference);
  const mlp::MlpInputs in{mlp::view(features, c.input_width), mlp::view(view, c.view_width), rays, samples};
  const mlp::MlpOutputs out{mlp::view(density, 1), mlp::view(rgb, 3)};
  const mlp::MlpOutputGradients d_out{mlp::view(d_density, 1), mlp::view(d_rgb, 3)};
  auto timed = [&](const std::function<void()>& work) {
    return time_call([&] {
      work();
      ctx.finish();
    });
  };
  MlpChunkTimes best{rows, 1e30, 1e30, 1e30};
  for (size_t r = 0; r <= reps; ++r) {  // the first pass builds programs
    const double f = timed([&] { net.forward(in, out, train_ws); });
    const double b = timed([&] { net.backward(train_ws, d_out); });
    const double i = timed([&] { net.forward(in, out, infer_ws); });
    if (r == 0) continue;
    best.forward = std::min(best.forward, f);
    best.backward = std::min(best.backward, b);
    best.inference = std::min(best.inference, i);
  }
  return best;
}

void clear_clblast_programs() { gemm::check_clblast(clblast::ClearCache(), "clblast::ClearCache"); }

}  // namespace mipnerf::bench
