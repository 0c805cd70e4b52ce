// End to end: the device MLP with Adam and the eq. 24 schedule fits a small known view-dependent function.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "mlp/adam.hpp"
#include "mlp/network.hpp"
#include "mlp_checks.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

constexpr size_t kFeatures = 10;  // (x, y) and sin/cos of x and y at two frequencies

struct Samples {
  size_t n_rays = 0, samples_per_ray = 0;
  std::vector<float> features;       // [rows][10]
  std::vector<float> view_encoding;  // [rays][3]: a unit direction
  std::vector<float> target;         // [rows][4]: density logit, then 3 colour logits
};

// density(x, y) = sin(2x)·cos(3y); colour_c = 0.5·sin(x + c·y) + 0.4·d_c (view dependent), on (x, y) ∈ [−1, 1]².
Samples make_samples(size_t n_rays, size_t samples_per_ray, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  Samples s;
  s.n_rays = n_rays;
  s.samples_per_ray = samples_per_ray;
  for (size_t r = 0; r < n_rays; ++r) {
    float d[3] = {normal(rng), normal(rng), normal(rng)};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (float& c : d) {
      c /= len;
      s.view_encoding.push_back(c);
    }
    for (size_t k = 0; k < samples_per_ray; ++k) {
      const float x = u(rng), y = u(rng);
      for (float f : {x, y, std::sin(x), std::cos(x), std::sin(y), std::cos(y), std::sin(2 * x), std::cos(2 * x),
                      std::sin(2 * y), std::cos(2 * y)}) {
        s.features.push_back(f);
      }
      s.target.push_back(std::sin(2 * x) * std::cos(3 * y));
      for (int c = 0; c < 3; ++c) s.target.push_back(0.5f * std::sin(x + c * y) + 0.4f * d[c]);
    }
  }
  return s;
}

class Fit {
 public:
  Fit(ocl::Context& ctx, const mlp::MlpConfig& config, const Samples& s)
      : ctx_(ctx),
        s_(s),
        rows_(s.n_rays * s.samples_per_ray),
        features_(test::device_copy(ctx, s.features, "features")),
        view_(test::device_copy(ctx, s.view_encoding, "view encoding")),
        density_(ctx, rows_, "raw_density"),
        rgb_(ctx, rows_ * 3, "raw_rgb"),
        d_density_(ctx, rows_, "d_raw_density"),
        d_rgb_(ctx, rows_ * 3, "d_raw_rgb") {}

  mlp::MlpInputs inputs() const { return {ocl::view(features_, kFeatures), ocl::view(view_, 3), s_.n_rays, s_.samples_per_ray}; }

  // Mean squared error over rows and the 4 outputs; with gradients, uploads ∂loss/∂raw outputs.
  double loss(mlp::Network& net, mlp::Workspace& ws, bool upload_gradients) {
    net.forward(inputs(), {ocl::view(density_, 1), ocl::view(rgb_, 3)}, ws);
    const auto density = density_.download(ctx_), rgb = rgb_.download(ctx_);
    std::vector<float> d_density(rows_), d_rgb(rows_ * 3);
    double sum = 0.0;
    const double scale = 2.0 / static_cast<double>(rows_ * 4);
    for (size_t r = 0; r < rows_; ++r) {
      const double e = density[r] - s_.target[4 * r];
      sum += e * e;
      d_density[r] = static_cast<float>(scale * e);
      for (int c = 0; c < 3; ++c) {
        const double ec = rgb[3 * r + c] - s_.target[4 * r + 1 + c];
        sum += ec * ec;
        d_rgb[3 * r + c] = static_cast<float>(scale * ec);
      }
    }
    if (upload_gradients) {
      d_density_.upload(ctx_, d_density);
      d_rgb_.upload(ctx_, d_rgb);
    }
    return sum / static_cast<double>(rows_ * 4);
  }

  mlp::MlpOutputGradients gradients() const { return {ocl::view(d_density_, 1), ocl::view(d_rgb_, 3)}; }
  size_t rows() const { return rows_; }

 private:
  ocl::Context& ctx_;
  const Samples& s_;
  size_t rows_;
  ocl::DeviceArray<float> features_, view_, density_, rgb_, d_density_, d_rgb_;
};

}  // namespace

TEST_CASE("mlp fit: Adam with the eq. 24 schedule fits a view-dependent function (loss falls over 1000x)") {
  auto& ctx = test::test_context();
  mlp::MlpConfig config;
  config.input_width = kFeatures;
  config.depth = 4;
  config.width = 32;
  config.skip_layer = 2;
  config.view_width = 3;
  config.view_branch_width = 16;
  config.bottleneck_width = 32;
  config.seed = 1;
  const auto net_owner = mlp::make_network(ctx, config, gemm::GemmBackend::automatic);
  mlp::Network& net = *net_owner;
  mlp::AdamHyper hyper;
  hyper.grad_max_norm = 1.0;  // exercise clipping on the way
  mlp::Adam adam(ctx, net.parameter_count(), hyper);
  mlp::LrSchedule schedule;
  const int steps = 400;
  schedule.lr_init = 1e-2;
  schedule.lr_final = 1e-3;
  schedule.max_steps = steps;
  schedule.warmup_steps = 20;

  const Samples train = make_samples(64, 8, 41), held_out = make_samples(64, 8, 42);
  Fit fit(ctx, config, train), check(ctx, config, held_out);
  auto ws = net.make_workspace(fit.rows(), train.n_rays, mlp::WorkspaceMode::training);
  auto ws_check = net.make_workspace(check.rows(), held_out.n_rays, mlp::WorkspaceMode::inference);
  const double initial = fit.loss(net, ws, false), initial_held_out = check.loss(net, ws_check, false);
  double last = initial;
  for (int step = 1; step <= steps; ++step) {
    net.zero_grad();
    last = fit.loss(net, ws, true);
    net.backward(ws, fit.gradients());
    const auto stats = adam.gradient_stats(net.grads());
    REQUIRE(stats.finite());
    adam.step(net.params(), net.grads(), mlp::learning_rate(schedule, step), &stats);
  }
  const double final_loss = fit.loss(net, ws, false), final_held_out = check.loss(net, ws_check, false);
  MESSAGE("fit: training MSE " << initial << " → " << final_loss << " (" << initial / final_loss << "x), held-out "
                               << initial_held_out << " → " << final_held_out << " ("
                               << initial_held_out / final_held_out << "x) in " << steps << " steps");
  // Stated target: the training loss falls by more than 1000x and the held-out loss by more than 300x (the
  // function is smooth, so what is learnt carries over to new samples of it). Measured here: ≈ 4400x and
  // ≈ 2500x.
  CHECK(final_loss < initial / 1000.0);
  CHECK(final_held_out < initial_held_out / 300.0);
  CHECK(std::isfinite(last));
}
