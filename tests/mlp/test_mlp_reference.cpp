// The double reference MLP's backward (parameters and features) against central finite differences of its own
// forward, and its per-ray view term against an explicitly per-sample computation.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "mlp/mlp_config.hpp"
#include "mlp_checks.hpp"
#include "ref/mlp.hpp"

using namespace mipnerf;

namespace {

struct Problem {
  mlp::MlpConfig config;
  size_t n_rays = 3, samples_per_ray = 4;
  std::vector<double> params, features, view_encoding, d_density, d_rgb;
};

// skip: the features concatenated again after layer index 2; without, they feed layer 0 only.
Problem make_problem(bool view_dependence, unsigned seed, bool skip = true) {
  Problem p;
  p.config.input_width = 5;
  p.config.depth = 4;
  p.config.width = 8;
  p.config.skip_layer = skip ? 2 : 0;
  p.config.view_dependence = view_dependence;
  p.config.view_width = 3;
  p.config.view_branch_width = 6;
  p.config.bottleneck_width = 7;
  p.config.density_outputs = 2;
  p.config.rgb_outputs = 3;
  p.config.seed = seed;
  std::mt19937 rng(seed);
  const size_t rows = p.n_rays * p.samples_per_ray;
  // Glorot weights, and biases made non-zero so their gradients and the ReLU pattern are not trivial.
  auto params = mlp::initial_parameters(p.config);
  const auto layout = mlp::parameter_layout(p.config);
  for (const auto* layer : layout.all()) {
    const auto biases = test::random_floats(layer->out, rng, -0.3f, 0.3f);
    std::copy(biases.begin(), biases.end(), params.begin() + layer->bias_offset);
  }
  p.params = test::as_double(params);
  p.features = test::as_double(test::random_floats(rows * p.config.input_width, rng));
  p.view_encoding = test::as_double(test::random_floats(p.n_rays * p.config.view_width, rng));
  p.d_density = test::as_double(test::random_floats(rows * p.config.density_outputs, rng));
  p.d_rgb = test::as_double(test::random_floats(rows * p.config.rgb_outputs, rng));
  return p;
}

// loss = Σ d_density · raw_density + Σ d_rgb · raw_rgb, so ∂loss/∂raw = the given upstream gradients.
double loss(const Problem& p, const std::vector<double>& params, const std::vector<double>& features,
            ref::MlpTape* tape) {
  std::vector<double> density, rgb;
  ref::mlp_forward(p.config, params, features, p.view_encoding, p.n_rays, p.samples_per_ray, density, rgb, tape);
  double total = 0.0;
  for (size_t i = 0; i < density.size(); ++i) total += p.d_density[i] * density[i];
  for (size_t i = 0; i < rgb.size(); ++i) total += p.d_rgb[i] * rgb[i];
  return total;
}

double loss(const Problem& p, const std::vector<double>& params, ref::MlpTape* tape) {
  return loss(p, params, p.features, tape);
}

// Whether two tapes have the same ReLU pattern (a difference step across a kink is not a derivative test).
bool same_pattern(const ref::MlpTape& a, const ref::MlpTape& b) {
  for (size_t l = 0; l < a.activations.size(); ++l) {
    for (size_t i = 0; i < a.activations[l].size(); ++i) {
      if ((a.activations[l][i] > 0.0) != (b.activations[l][i] > 0.0)) return false;
    }
  }
  for (size_t i = 0; i < a.view_hidden.size(); ++i) {
    if ((a.view_hidden[i] > 0.0) != (b.view_hidden[i] > 0.0)) return false;
  }
  return true;
}

void check_finite_differences(bool view_dependence) {
  const Problem p = make_problem(view_dependence, view_dependence ? 21 : 22);
  ref::MlpTape tape;
  loss(p, p.params, &tape);
  std::vector<double> grads;
  ref::mlp_backward(p.config, p.params, tape, p.d_density, p.d_rgb, grads);
  REQUIRE(grads.size() == p.params.size());
  // Central differences with h = 1e-5. Within one ReLU pattern the loss is affine in any single parameter
  // (each weight sits in one layer, and the layers after it are linear maps), so the difference quotient is
  // exact up to rounding: ≈ ε_double·|loss|/h ≈ 1e-10 here.
  const double h = 1e-5;
  size_t checked = 0, skipped = 0;
  double worst = 0.0;
  for (size_t i = 0; i < p.params.size(); ++i) {
    auto plus = p.params, minus = p.params;
    plus[i] += h;
    minus[i] -= h;
    ref::MlpTape tape_plus, tape_minus;
    const double f_plus = loss(p, plus, &tape_plus), f_minus = loss(p, minus, &tape_minus);
    if (!same_pattern(tape_plus, tape_minus)) {
      ++skipped;
      continue;
    }
    const double numeric = (f_plus - f_minus) / (2.0 * h);
    worst = std::max(worst, std::abs(numeric - grads[i]));
    ++checked;
  }
  INFO("checked " << checked << " parameters, skipped " << skipped << " at a ReLU kink; worst |error| " << worst);
  // Rounding only (see above): 1e-8 is about 100× the expected error, far below any real gradient mistake.
  CHECK(worst <= 1e-8);
  CHECK(skipped * 100 <= p.params.size());  // kinks are rare: at most 1 % of the parameters skipped
  CHECK(checked > 0);
}

// ∂loss/∂features against central differences of the forward's loss in each feature. Within one ReLU pattern the
// network is affine in any single feature (every layer is, and the ReLUs are fixed), so, as for the parameters, the
// quotient is exact up to rounding.
void check_feature_gradient(bool view_dependence, bool skip, unsigned seed) {
  const Problem p = make_problem(view_dependence, seed, skip);
  ref::MlpTape tape;
  loss(p, p.params, &tape);
  std::vector<double> grads, d_features(3, 7.0);  // of the wrong size and not zero: the backward sets it
  ref::mlp_backward(p.config, p.params, tape, p.d_density, p.d_rgb, grads, &d_features);
  REQUIRE(d_features.size() == p.features.size());
  // The parameter gradients do not depend on whether the features' gradient is asked for.
  std::vector<double> grads_alone;
  ref::mlp_backward(p.config, p.params, tape, p.d_density, p.d_rgb, grads_alone);
  CHECK(grads == grads_alone);
  const double h = 1e-5;
  size_t checked = 0, skipped = 0, nonzero = 0;
  double worst = 0.0;
  for (size_t i = 0; i < p.features.size(); ++i) {
    auto plus = p.features, minus = p.features;
    plus[i] += h;
    minus[i] -= h;
    ref::MlpTape tape_plus, tape_minus;
    const double f_plus = loss(p, p.params, plus, &tape_plus), f_minus = loss(p, p.params, minus, &tape_minus);
    if (!same_pattern(tape_plus, tape_minus)) {
      ++skipped;
      continue;
    }
    const double numeric = (f_plus - f_minus) / (2.0 * h);
    worst = std::max(worst, std::abs(numeric - d_features[i]));
    nonzero += std::abs(d_features[i]) > 1e-3;
    ++checked;
  }
  INFO("checked " << checked << " features, skipped " << skipped << " at a ReLU kink; worst |error| " << worst);
  CHECK(worst <= 1e-8);                      // rounding only, as for the parameters
  CHECK(skipped * 50 <= p.features.size());  // at most 2 % skipped (60 features: at most one)
  CHECK(nonzero * 2 > checked);              // a real gradient, not zeros matching zeros
}

}  // namespace

TEST_CASE("mlp reference: the features' gradient matches finite differences (skip and view dependence or not)") {
  for (const bool view : {true, false}) {
    for (const bool skip : {true, false}) {
      INFO("view dependence " << view << ", skip layer " << skip);
      check_feature_gradient(view, skip, 31 + 2 * view + skip);
    }
  }
}

TEST_CASE("mlp reference: backward matches finite differences, with view dependence") {
  check_finite_differences(true);
}

TEST_CASE("mlp reference: backward matches finite differences, without view dependence") {
  check_finite_differences(false);
}

TEST_CASE("mlp reference: gradients accumulate across calls") {
  const Problem p = make_problem(true, 23);
  ref::MlpTape tape;
  loss(p, p.params, &tape);
  std::vector<double> once, twice;
  ref::mlp_backward(p.config, p.params, tape, p.d_density, p.d_rgb, once);
  ref::mlp_backward(p.config, p.params, tape, p.d_density, p.d_rgb, twice);
  ref::mlp_backward(p.config, p.params, tape, p.d_density, p.d_rgb, twice);
  for (size_t i = 0; i < once.size(); ++i) CHECK(twice[i] == doctest::Approx(2.0 * once[i]).epsilon(1e-12));
}
