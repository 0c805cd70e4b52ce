// One training step against the official train.train_step's own results (tests/official/fixtures/adam.json, written by
// make_vectors.py / model_vectors.py from google/mipnerf), on model.json's weights and 16-ray multiscale batch with
// deterministic sampling: the per-level losses weighted by lossmult and their λ-weighted total (loss_fn), the gradient
// of that total (jax.grad), and the Adam update train.py applies at that step (its learning rate, bias correction, and
// gradient clipping off as in every official config or at half the gradient's norm). The coarse weight 1 instead of
// 0.1, no lossmult, or no clipping must not match.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "mlp/adam.hpp"
#include "official_fixtures.hpp"
#include "official_model.hpp"
#include "ops/loss.hpp"
#include "support/gemm_backends.hpp"
#include "train/train_step.hpp"

using namespace mipnerf;
using official::flat;
using official::kU;

namespace {

struct StepResult {
  std::vector<ops::LevelLoss> losses;
  std::vector<float> grads;
};

// Our training graph's step on the batch: the levels' losses and the parameter gradient of Σ_l weight_l·loss_l.
StepResult graph_step(const io::Json& fx, gemm::GemmBackend backend, const train::Bundle& overrides = {}) {
  auto& ctx = test::test_context();
  const auto model_fx = official::fixture("model.json");
  official::ModelBatch batch(model_fx);
  REQUIRE_FALSE(fx.at("config").at("randomized").get<bool>());
  REQUIRE(fx.at("config").at("white_bkgd").get<bool>());
  train::Bundle settings = {{"coarse_loss_mult", official::setting_text(fx.at("config").at("coarse_loss_mult"))}};
  for (const auto& [name, value] : overrides) settings[name] = value;
  const auto config = official::model_config(fx, false, settings);
  const auto spec = train::make_graph_spec(config, true);
  auto network = mlp::make_network(ctx, spec.mlps[0], backend);
  network->upload_params(official::model_params(model_fx, spec.mlps[0]));
  graph::Graph graph(ctx, spec, {network.get()}, graph::GraphMode::training, batch.n_rays, batch.n_rays);
  graph.begin_step(batch.n_rays, spec.loss.multiscale ? batch.lossmult_sum() : static_cast<double>(batch.n_rays));
  graph.train_chunk(batch.source(), {0, batch.n_rays},
                    {*batch.target_dev, spec.loss.multiscale ? batch.lossmult_dev.get() : nullptr}, {0, 1});
  return {graph.end_step(), network->download_grads()};
}

// The bound of each level's loss L = Σ_r m_r·Σ_c (c_rc − t_rc)² / Σ_r m_r: our colours within model.json's derived
// bound B_rc of the official ones (official_model.hpp) and our pixels within 4u of the official loader's
// (test_multicam; measured equal), so first order Σ_r m_r·Σ_c 2·|c_rc − t_rc|·(B_rc + 4u) / Σ m, plus (B + 4u)² for the
// second order and 16u·L for the squares and the sums (float products, 6 tree levels of 64 rays, the host's double
// sums).
std::vector<double> loss_bounds(const io::Json& model_fx, const official::ModelBatch& batch) {
  const auto config = official::model_config(model_fx, false);
  const auto bound = official::model_output_bounds(model_fx, train::make_graph_spec(config, true).mlps[0]);
  const auto values = flat(model_fx.at("outputs"));
  const size_t n_levels = model_fx.at("outputs").size(), R = batch.n_rays;
  std::vector<double> out(n_levels, 0.0);
  for (size_t l = 0; l < n_levels; ++l) {
    double first = 0, second = 0, loss = 0;
    for (size_t r = 0; r < R; ++r) {
      for (size_t c = 0; c < 3; ++c) {
        const size_t at = (l * R + r) * 5 + c;
        const double residual = values[at] - batch.target_rgb[3 * r + c], b = bound[at] + 4 * kU;
        first += batch.lossmult[r] * 2 * std::abs(residual) * b;
        second += batch.lossmult[r] * b * b;
        loss += batch.lossmult[r] * residual * residual;
      }
    }
    out[l] = (first + second + 16 * kU * loss) / batch.lossmult_sum();
  }
  return out;
}

}  // namespace

TEST_CASE("train_step loss: our levels' lossmult-weighted losses and their coarse-weighted total are the official") {
  const auto fx = official::fixture("adam.json");
  const auto model_fx = official::fixture("model.json");
  official::ModelBatch batch(model_fx);
  const auto bounds = loss_bounds(model_fx, batch);
  const auto official_losses = flat(fx.at("losses"), {2});
  const double lambda = fx.at("config").at("coarse_loss_mult").get<double>();
  REQUIRE(lambda == 0.1);
  REQUIRE(fx.at("weight_l2").get<double>() == 0.0);  // weight_decay_mult 0: the total is λ·L_coarse + L_fine
  const auto backend = test::supported_gemm_backends(test::test_context()).front();
  const auto step = graph_step(fx, backend);
  REQUIRE(step.losses.size() == 2);
  std::vector<double> ours;
  for (const auto& l : step.losses) ours.push_back(l.loss());
  OFFICIAL_CHECK_AGREES("level losses", ours, official_losses, [&](size_t l) { return bounds[l]; });
  const double total_bound = lambda * bounds[0] + bounds[1];
  OFFICIAL_CHECK_AGREES("loss (λ·coarse + fine)", std::vector<double>{ops::total_loss(step.losses, 0.1f)},
                        std::vector<double>{fx.at("loss").get<double>()}, official::constant_bound(total_bound));

  // The coarse level at full weight: the total grows by 0.9·L_coarse ≈ 0.26, ~10⁵ times its bound.
  OFFICIAL_CHECK_DISAGREES("loss with coarse weight 1", std::vector<double>{ops::total_loss(step.losses, 1.0f)},
                           std::vector<double>{fx.at("loss").get<double>()}, 100.0,
                           official::constant_bound(total_bound));
  // Every ray at weight 1 (no area loss): the scales' residuals weigh 1 instead of 1, 4, 16.
  const auto plain = graph_step(fx, backend, {{"area_loss", "false"}});
  std::vector<double> plain_losses;
  for (const auto& l : plain.losses) plain_losses.push_back(l.loss());
  OFFICIAL_CHECK_DISAGREES("level losses without lossmult", plain_losses, official_losses, 100.0,
                           [&](size_t l) { return bounds[l]; });
}

// The gradient is held to the bound the whole-step checks hold our step to against the CPU reference
// (tests/graph/test_graph.cpp): 1e-3 of its norm, in norm. Every stage's backward is held to its own bound elsewhere
// (render_bwd here against jax.grad: test_gradients.cpp); this checks their composition against the official one.
TEST_CASE("train_step gradient: our graph's parameter gradient is the official jax.grad of loss_fn") {
  const auto fx = official::fixture("adam.json");
  const auto official_grad = flat(fx.at("grad"));
  double norm = 0;
  for (double g : official_grad) norm += g * g;
  norm = std::sqrt(norm);
  REQUIRE(norm > 0);
  const auto relative_error = [&](const std::vector<float>& ours) {
    REQUIRE(ours.size() == official_grad.size());
    double diff = 0;
    for (size_t i = 0; i < ours.size(); ++i) {
      REQUIRE(std::isfinite(ours[i]));
      diff += (ours[i] - official_grad[i]) * (ours[i] - official_grad[i]);
    }
    return std::sqrt(diff) / norm;
  };
  for (const auto backend : test::supported_gemm_backends(test::test_context())) {
    const std::string backend_name = enum_name(backend);
    CAPTURE(backend_name);
    const double error = relative_error(graph_step(fx, backend).grads);
    INFO("relative error " << error << " = " << error / 1e-3 << " x bound");
    if (std::getenv("MIPNERF_TEST_VERBOSE"))
      MESSAGE("gradient: relative error " << error << " = " << error / 1e-3 << " x bound");
    CHECK(error <= 1e-3);
  }
  // The coarse level's gradient at weight 1 instead of 0.1.
  const double heavier = relative_error(
      graph_step(fx, test::supported_gemm_backends(test::test_context()).front(), {{"coarse_loss_mult", "1"}}).grads);
  INFO("with coarse weight 1: relative error " << heavier);
  if (std::getenv("MIPNERF_TEST_VERBOSE")) MESSAGE("gradient with coarse weight 1: " << heavier / 1e-3 << " x bound");
  CHECK(heavier > 100 * 1e-3);
}

namespace {

struct AdamResult {
  std::vector<float> params, m, v;
  double lr = 0;
};

// Our Adam on the official weights and gradient, its state restored to the fixture's (count_before updates; the
// moments zero but on state_indices), update number count_before + 1 at our schedule's rate for it.
AdamResult our_adam(const io::Json& fx, double grad_max_norm) {
  auto& ctx = test::test_context();
  const auto model_fx = official::fixture("model.json");
  const auto config = official::model_config(model_fx, false);
  const auto spec = train::make_graph_spec(config, true);
  const auto params = official::model_params(model_fx, spec.mlps[0]);
  const auto grads = official::as_float(flat(fx.at("grad")));
  REQUIRE(grads.size() == params.size());
  const auto& a = fx.at("adam");
  mlp::AdamState state;
  state.step = a.at("count_before").get<int64_t>();
  state.m.assign(params.size(), 0.0f);
  state.v.assign(params.size(), 0.0f);
  const auto indices = a.at("state_indices");
  const auto m = flat(a.at("m")), v = flat(a.at("v"));
  for (size_t k = 0; k < indices.size(); ++k) {
    state.m[indices.at(k).get<size_t>()] = static_cast<float>(m[k]);
    state.v[indices.at(k).get<size_t>()] = static_cast<float>(v[k]);
  }
  mlp::AdamHyper hyper;
  REQUIRE(hyper.beta1 == a.at("beta1").get<double>());
  REQUIRE(hyper.beta2 == a.at("beta2").get<double>());
  REQUIRE(hyper.epsilon == static_cast<float>(a.at("eps").get<double>()));
  hyper.grad_max_norm = grad_max_norm;
  mlp::Adam adam(ctx, params.size(), hyper);
  adam.restore(state);
  auto params_dev = official::upload(ctx, params, "params");
  auto grads_dev = official::upload(ctx, grads, "grads");
  const auto stats = adam.gradient_stats(grads_dev);
  // The rate train.py gives update number count_before + 1: learning_rate_fn(step) of the official defaults, which
  // are ours (the paper's), over our run's steps.
  const int64_t step = adam.step_count() + 1;
  REQUIRE(step == a.at("step").get<int64_t>());
  const double lr = mlp::learning_rate(train::schedule_of(config), step);
  adam.step(params_dev, grads_dev, lr, &stats);
  const auto after = adam.state();
  return {params_dev.download(ctx), after.m, after.v, lr};
}

template <typename T>
std::vector<T> at_indices(const std::vector<T>& values, const io::Json& indices) {
  std::vector<T> out;
  for (const auto& i : indices) out.push_back(values.at(i.get<size_t>()));
  return out;
}

}  // namespace

TEST_CASE("train_step Adam: our update of the official weights and gradient is the official one, clipping off and on") {
  const auto fx = official::fixture("adam.json");
  const auto model_fx = official::fixture("model.json");
  const auto& a = fx.at("adam");
  const auto& cfg = fx.at("config");
  // Our schedule's defaults are the official Config's (supplement eq. 24).
  const auto config = official::model_config(model_fx, false);
  CHECK(config.lr_init == cfg.at("lr_init").get<double>());
  CHECK(config.lr_final == cfg.at("lr_final").get<double>());
  CHECK(config.steps == cfg.at("max_steps").get<int64_t>());
  CHECK(config.lr_warmup_steps == cfg.at("lr_delay_steps").get<int64_t>());
  CHECK(config.lr_warmup_mult == cfg.at("lr_delay_mult").get<double>());

  const auto compared = a.at("compared_indices");
  const auto grad32 = flat(fx.at("grad"));
  const size_t n_params = grad32.size();
  std::vector<double> p0, g, m0(n_params, 0.0), v0(n_params, 0.0);
  {
    const auto spec = train::make_graph_spec(config, true);
    const auto flat_params = official::model_params(model_fx, spec.mlps[0]);
    p0.assign(flat_params.begin(), flat_params.end());
    g = grad32;
    const auto indices = a.at("state_indices");
    const auto m = flat(a.at("m")), v = flat(a.at("v"));
    for (size_t k = 0; k < indices.size(); ++k) {
      m0[indices.at(k).get<size_t>()] = m[k];
      v0[indices.at(k).get<size_t>()] = v[k];
    }
  }
  const double t = a.at("step").get<double>(), b1 = a.at("beta1").get<double>(), b2 = a.at("beta2").get<double>();
  const double eps = a.at("eps").get<double>();
  double grad_norm = 0;
  for (double x : g) grad_norm += x * x;
  grad_norm = std::sqrt(grad_norm);

  for (const auto& c : fx.at("cases")) {
    const double max_norm = c.at("grad_max_norm").get<double>();
    CAPTURE(max_norm);
    REQUIRE(c.at("grad_max_val").get<double>() == 0.0);  // not ours (tests/official/README.md, Known differences)
    const auto ours = our_adam(fx, max_norm);
    // train.py's rate for this update, against the fixture's (both in double: schedule.json's 1e-13).
    CHECK(ours.lr == doctest::Approx(a.at("lr").get<double>()).epsilon(1e-13));
    // The official clip, mult = min(1, max / (1e-7 + norm)) on the float64 gradient.
    const double scale = max_norm > 0 ? std::min(1.0, max_norm / (1e-7 + c.at("grad_norm").get<double>())) : 1.0;
    CHECK(c.at("grad_norm").get<double>() == doctest::Approx(grad_norm).epsilon(4 * kU));

    // Our float32 update against the official float64 one, per element i (values from the fixture's inputs):
    //  · the gradient: our float32 input (u), the clip scale (our norm adds the float32 squares of ⌈P/1024⌉ = 5
    //    elements per slice, ≤ 6u, then the division and the cast to float: ε_s ≤ 8u, when clipping), the product:
    //    ε_g = (2 + 8·[clipping])·u relative;
    //  · the constants, each rounded to float from the double hyperparameters (mlp::AdamHyper): β1, 1 − β1, β2,
    //    1 − β2 within u; the bias corrections 1/(1 − β^t) in double, cast to float: u;
    //  · m' = β1·m + (1 − β1)·g: |δm'| ≤ β1|m|·3u + (1 − β1)|g|·(3u + ε_g) + u|m'|;
    //  · v' = β2·v + (1 − β2)·g²: |δv'| ≤ β2·v·3u + (1 − β2)·g²·(4u + 2ε_g) + u·v';
    //  · the step lr·m̂/(√v̂ + ε): lr cast (u), m̂ (δm'/m' + 2u), √v̂ (½(δv'/v' + 2u) + 2u), the division and the
    //    product (3u): relative δm'/|m'| + ½δv'/v' + 9u of it;
    //  · p' = p − step: u·|p'|;
    //  · every float32 result (and the float32 gradient) also within 2^-150, half the smallest subnormal, of its value:
    //    an official moment of 1e-49 is 0 in float32.
    const double eps_g = (2 + (max_norm > 0 ? 8 : 0)) * kU;
    std::vector<double> p_bound, m_bound, v_bound;
    for (const auto& index : compared) {
      const size_t i = index.get<size_t>();
      const double gs = g[i] * scale;
      const double m1 = b1 * m0[i] + (1 - b1) * gs, v1 = b2 * v0[i] + (1 - b2) * gs * gs;
      const double dm = b1 * std::abs(m0[i]) * 3 * kU + (1 - b1) * std::abs(gs) * (3 * kU + eps_g) + kU * std::abs(m1);
      const double dv = b2 * v0[i] * 3 * kU + (1 - b2) * gs * gs * (4 * kU + 2 * eps_g) + kU * v1;
      const double m_hat = m1 / (1 - std::pow(b1, t)), v_hat = v1 / (1 - std::pow(b2, t));
      const double update = std::abs(a.at("lr").get<double>() * m_hat / (std::sqrt(v_hat) + eps));
      const double relative = (m1 != 0 ? dm / std::abs(m1) : 0) + (v1 > 0 ? 0.5 * dv / v1 : 0) + 9 * kU;
      const double p1 = p0[i] - update;
      const double underflow = std::ldexp(1.0, -150);
      p_bound.push_back(relative * update + kU * std::abs(p1) + underflow);
      m_bound.push_back(dm + 2 * underflow);
      v_bound.push_back(dv + 2 * underflow);
    }
    const auto new_params = flat(c.at("new_params")), new_m = flat(c.at("new_m")), new_v = flat(c.at("new_v"));
    OFFICIAL_CHECK_AGREES("new parameters", at_indices(ours.params, compared), new_params,
                          [&](size_t k) { return p_bound[k]; });
    OFFICIAL_CHECK_AGREES("new first moments", at_indices(ours.m, compared), new_m,
                          [&](size_t k) { return m_bound[k]; });
    OFFICIAL_CHECK_AGREES("new second moments", at_indices(ours.v, compared), new_v,
                          [&](size_t k) { return v_bound[k]; });
    if (max_norm > 0) {
      // Without the clip the gradient is twice as large: the moments move by ~(1 − β)·g, far beyond their bounds.
      const auto unclipped = our_adam(fx, 0.0);
      OFFICIAL_CHECK_DISAGREES("first moments without clipping", at_indices(unclipped.m, compared), new_m, 100.0,
                               [&](size_t k) { return m_bound[k]; });
    }
  }
}
