// The device MLP (products on each GEMM backend the test device supports + mlp.cl) against the double reference:
// outputs and every gradient, with two passes accumulating into one gradient (coarse and fine through one shared
// MLP), at a small size and at the paper's size, through CLBlast's direct and indirect GEMM paths; the backends
// against each other. Also the API's errors.
#include <doctest/doctest.h>

#include <clblast.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <unordered_map>

#include "core/error.hpp"
#include "core/flush_denormals.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/cpu_sgemm.hpp"
#include "mlp/host_mlp.hpp"
#include "mlp/host_network.hpp"
#include "mlp/mlp_products.hpp"
#include "mlp/network.hpp"
#include "mlp_checks.hpp"
#include "ref/mlp.hpp"
#include "support/gemm_backends.hpp"
#include "support/mlp_fixtures.hpp"
#include "support/profile_once.hpp"
#include "support/skip.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

// Float32 against double through the whole network. Each value is a chain of ≤ 2·(depth + 4) ≈ 24 products
// (forward, then backward) of length K ≤ width + input_width = 352, and float32 rounding errors of such sums
// grow like √K·u (u = 2^-24) per product in practice: √24 · √352 · 6e-8 ≈ 5.5e-6 of the magnitudes
// involved. We allow 3e-5 of each tensor's largest reference value (the weight gradients also sum over the
// rows); the worst seen here is ≈ 1e-6. A wrong transpose, a missing term or a missed accumulation errs by
// far more. Plus 1e-7 absolute for tensors that are all ~0.
constexpr double kRelative = 3e-5;
constexpr double kAbsolute = 1e-7;

struct Pass {
  size_t n_rays = 0, samples_per_ray = 0;
  size_t features_ld = 0, features_offset = 0;
  std::vector<float> features, view_encoding, d_density, d_rgb;
  size_t rows() const { return n_rays * samples_per_ray; }
};

Pass make_pass(const mlp::MlpConfig& config, size_t n_rays, size_t samples_per_ray, std::mt19937& rng) {
  Pass p;
  p.n_rays = n_rays;
  p.samples_per_ray = samples_per_ray;
  p.features_ld = config.input_width + 2;  // padded rows and an offset exercise MatrixView
  p.features_offset = 1;
  p.features = test::random_floats(p.features_offset + p.rows() * p.features_ld, rng);
  p.view_encoding = test::random_floats(n_rays * config.view_width, rng);
  p.d_density = test::random_floats(p.rows() * config.density_outputs, rng);
  p.d_rgb = test::random_floats(p.rows() * config.rgb_outputs, rng);
  return p;
}

// The features as the reference takes them: dense [rows][input_width].
std::vector<double> dense_features(const Pass& p, size_t width) {
  std::vector<double> out(p.rows() * width);
  for (size_t r = 0; r < p.rows(); ++r) {
    for (size_t c = 0; c < width; ++c) out[r * width + c] = p.features[p.features_offset + r * p.features_ld + c];
  }
  return out;
}

struct DevicePass {
  ocl::DeviceArray<float> features, view_encoding, raw_density, raw_rgb, d_density, d_rgb;
  DevicePass(ocl::Context& ctx, const mlp::MlpConfig& config, const Pass& p)
      : features(test::device_copy(ctx, p.features, "features")),
        view_encoding(test::device_copy(ctx, p.view_encoding, "view encoding")),
        raw_density(ctx, p.rows() * config.density_outputs, "raw_density"),
        raw_rgb(ctx, p.rows() * config.rgb_outputs, "raw_rgb"),
        d_density(test::device_copy(ctx, p.d_density, "d_raw_density")),
        d_rgb(test::device_copy(ctx, p.d_rgb, "d_raw_rgb")) {}
};

mlp::MlpInputs inputs_for(const DevicePass& d, const Pass& p, const mlp::MlpConfig& config) {
  return {ocl::view(d.features, p.features_ld, p.features_offset), ocl::view(d.view_encoding, config.view_width),
          p.n_rays, p.samples_per_ray};
}

mlp::MlpOutputs outputs_for(DevicePass& d, const mlp::MlpConfig& config) {
  return {ocl::view(d.raw_density, config.density_outputs), ocl::view(d.raw_rgb, config.rgb_outputs)};
}

mlp::MlpOutputGradients gradients_for(const DevicePass& d, const mlp::MlpConfig& config) {
  return {ocl::view(d.d_density, config.density_outputs), ocl::view(d.d_rgb, config.rgb_outputs)};
}

// ∂loss/∂features as a backward writes it: [rows][input_width] at an offset, rows padded (ld > input_width), filled
// with a sentinel first so that the test sees that the backward overwrites every value and leaves the padding alone.
struct FeatureGradient {
  static constexpr float kSentinel = 1234.5f;
  size_t offset = 3, ld = 0, rows = 0, width = 0;
  ocl::DeviceArray<float> array;
  FeatureGradient(ocl::Context& ctx, const mlp::MlpConfig& config, size_t rows_)
      : ld(config.input_width + 2),
        rows(rows_),
        width(config.input_width),
        array(test::device_copy(ctx, std::vector<float>(offset + rows_ * ld, kSentinel), "d_features")) {}
  ocl::MatrixView view() const { return ocl::view(array, ld, offset); }
  // The gradient, dense [rows][input_width]; CHECKs that the padding kept its sentinel.
  std::vector<float> download(ocl::Context& ctx) const {
    const std::vector<float> all = array.download(ctx);
    std::vector<float> dense(rows * width);
    size_t padding_changed = 0;
    for (size_t i = 0; i < all.size(); ++i) {
      const bool inside = i >= offset && (i - offset) % ld < width && (i - offset) / ld < rows;
      if (inside) {
        dense[((i - offset) / ld) * width + (i - offset) % ld] = all[i];
      } else {
        padding_changed += all[i] != kSentinel;
      }
    }
    CHECK(padding_changed == 0);
    return dense;
  }
};

// Two passes (think coarse and fine, different sample counts) through one MLP: forward A, forward B,
// backward B, backward A, as the training graph orders them; gradients accumulate into one buffer. Pass A's backward
// also asks for ∂loss/∂features, pass B's does not (both paths against the reference in one run).
// host_options: how the host path splits the rows (blocks, threads); its defaults when null.
void check_against_reference_on(gemm::GemmBackend backend, const mlp::MlpConfig& config, size_t n_rays,
                                size_t samples_a, size_t samples_b, unsigned seed,
                                const mlp::HostMlpOptions* host_options = nullptr) {
  auto& ctx = test::test_context();
  INFO("gemm_backend = " << enum_name(backend));
  std::mt19937 rng(seed);
  const auto network =
      host_options ? mlp::make_host_network(ctx, config, *host_options) : mlp::make_network(ctx, config, backend);
  REQUIRE(network->backend() == backend);
  mlp::Network& net = *network;
  // Random biases (Glorot leaves them at zero) so every bias path carries a value.
  auto params = net.download_params();
  for (const auto* layer : net.layout().all()) {
    const auto biases = test::random_floats(layer->out, rng, -0.2f, 0.2f);
    std::copy(biases.begin(), biases.end(), params.begin() + layer->bias_offset);
  }
  net.upload_params(params);
  const auto params_d = test::as_double(params);

  const Pass a = make_pass(config, n_rays, samples_a, rng), b = make_pass(config, n_rays, samples_b, rng);
  DevicePass da(ctx, config, a), db(ctx, config, b);
  auto ws_a = net.make_workspace(a.rows(), n_rays, mlp::WorkspaceMode::training);
  auto ws_b = net.make_workspace(b.rows() + 5, n_rays + 1, mlp::WorkspaceMode::training);  // larger than needed
  net.zero_grad();
  net.forward(inputs_for(da, a, config), outputs_for(da, config), ws_a);
  net.forward(inputs_for(db, b, config), outputs_for(db, config), ws_b);
  FeatureGradient d_features_a(ctx, config, a.rows());
  net.backward(ws_b, gradients_for(db, config));
  net.backward(ws_a, gradients_for(da, config), d_features_a.view());
  const auto grads = net.download_grads();

  std::vector<double> ref_grads, ref_d_features_a;
  for (const Pass* p : {&a, &b}) {
    const DevicePass& d = p == &a ? da : db;
    std::vector<double> density, rgb;
    ref::MlpTape tape;
    ref::mlp_forward(config, params_d, dense_features(*p, config.input_width), test::as_double(p->view_encoding),
                     p->n_rays, p->samples_per_ray, density, rgb, &tape);
    const std::string pass = p == &a ? "pass A" : "pass B";
    test::check_close(d.raw_density.download(ctx), density, 0, density.size(), kRelative, kAbsolute,
                      pass + " raw_density");
    test::check_close(d.raw_rgb.download(ctx), rgb, 0, rgb.size(), kRelative, kAbsolute, pass + " raw_rgb");
    ref::mlp_backward(config, params_d, tape, test::as_double(p->d_density), test::as_double(p->d_rgb), ref_grads,
                      p == &a ? &ref_d_features_a : nullptr);
  }
  test::check_close(d_features_a.download(ctx), ref_d_features_a, 0, ref_d_features_a.size(), kRelative, kAbsolute,
                    "pass A d_features");
  for (const auto* layer : net.layout().all()) {
    test::check_close(grads, ref_grads, layer->weight_offset, layer->in * layer->out, kRelative, kAbsolute,
                      layer->name + " weight gradient");
    test::check_close(grads, ref_grads, layer->bias_offset, layer->out, kRelative, kAbsolute,
                      layer->name + " bias gradient");
  }

  // Inference (ping-pong buffers, nothing saved) computes exactly the same products in the same order.
  auto ws_infer = net.make_workspace(a.rows(), n_rays, mlp::WorkspaceMode::inference);
  ocl::DeviceArray<float> density2(ctx, a.rows() * config.density_outputs, "raw_density (inference)");
  ocl::DeviceArray<float> rgb2(ctx, a.rows() * config.rgb_outputs, "raw_rgb (inference)");
  net.forward(inputs_for(da, a, config),
              {ocl::view(density2, config.density_outputs), ocl::view(rgb2, config.rgb_outputs)}, ws_infer);
  CHECK(density2.download(ctx) == da.raw_density.download(ctx));
  CHECK(rgb2.download(ctx) == da.raw_rgb.download(ctx));
}

// The same check on every GEMM backend the test device supports, same tolerances.
void check_against_reference(const mlp::MlpConfig& config, size_t n_rays, size_t samples_a, size_t samples_b,
                             unsigned seed) {
  for (const gemm::GemmBackend backend : test::supported_gemm_backends(test::test_context())) {
    check_against_reference_on(backend, config, n_rays, samples_a, samples_b, seed);
  }
}

// Sets CLBlast's direct/indirect switch for this test and restores the database value afterwards.
class GemmRoutineOverride {
 public:
  GemmRoutineOverride(cl_device_id device, size_t min_indirect_size) : device_(device) {
    gemm::check_clblast(clblast::RetrieveParameters(device_, "GemmRoutine", clblast::Precision::kSingle, saved_),
                       "clblast::RetrieveParameters(GemmRoutine)");
    set({{"XGEMM_MIN_INDIRECT_SIZE", min_indirect_size}});
  }
  ~GemmRoutineOverride() { clblast::OverrideParameters(device_, "GemmRoutine", clblast::Precision::kSingle, saved_); }

 private:
  void set(const std::unordered_map<std::string, size_t>& p) {
    gemm::check_clblast(clblast::OverrideParameters(device_, "GemmRoutine", clblast::Precision::kSingle, p),
                       "clblast::OverrideParameters(GemmRoutine)");
  }
  cl_device_id device_;
  std::unordered_map<std::string, size_t> saved_;
};

// Whether the test device can run the host GEMM backend (host BLAS on shared memory); reports the test skipped if not.
bool host_backend_runs_here() {
  if (test::supported_gemm_backends(test::test_context()).size() >= 2) return true;
  test::skip_test("the test device cannot run the host GEMM backend (host BLAS, shared memory)");
  return false;
}

// Host MLP options with these block rows and threads, the rest (the library choice: OpenBLAS) by default.
mlp::HostMlpOptions host_options(size_t target_block_rows, size_t threads) {
  mlp::HostMlpOptions options;
  options.target_block_rows = target_block_rows;
  options.threads = threads;
  return options;
}

}  // namespace

TEST_CASE("mlp device: small network with view dependence matches the reference") {
  check_against_reference(test::small_mlp_config(true), 5, 6, 9, 101);
}

TEST_CASE("mlp device: small network without view dependence matches the reference") {
  check_against_reference(test::small_mlp_config(false), 4, 7, 3, 102);
}

TEST_CASE("mlp device: small network without a skip layer matches the reference") {
  // The features feed the first layer only: their gradient is that layer's input gradient alone.
  mlp::MlpConfig config = test::small_mlp_config(true);
  config.skip_layer = 0;
  check_against_reference(config, 4, 5, 3, 112);
}

TEST_CASE("mlp device: the paper's network (8x256, skip, view branch) matches the reference") {
  mlp::MlpConfig config;  // paper defaults
  config.seed = 4;
  check_against_reference(config, 4, 16, 24, 103);
}

TEST_CASE("mlp device: the paper's network through CLBlast's indirect GEMM path matches the reference") {
  // At test sizes CLBlast picks its direct kernel (m·n·k below XGEMM_MIN_INDIRECT_SIZE³); real chunks take the
  // indirect one (pad/transpose helpers + Xgemm). A threshold of 1 forces every product through it here.
  GemmRoutineOverride indirect(test::test_context().raw_device(), 1);
  mlp::MlpConfig config;
  config.seed = 5;
  check_against_reference_on(gemm::GemmBackend::clblast, config, 3, 16, 8, 104);
}

TEST_CASE("mlp device: the host path's blocks and threads do not change what it computes") {
  // At test sizes every pass is one block on one thread; here blocks of one ray (and of several rays with a ragged
  // last block) on more threads than blocks or cores, through both networks.
  if (!host_backend_runs_here()) return;
  for (const auto& rows_threads : {std::pair<size_t, size_t>{1, 3}, {20, 2}, {40, 7}}) {
    const size_t rows = rows_threads.first, threads = rows_threads.second;  // INFO cannot capture a structured binding
    INFO("target_block_rows " << rows << ", threads " << threads);
    const mlp::HostMlpOptions options = host_options(rows, threads);
    check_against_reference_on(gemm::GemmBackend::host, test::small_mlp_config(true), 5, 6, 9, 106, &options);
    check_against_reference_on(gemm::GemmBackend::host, test::small_mlp_config(false), 4, 7, 3, 107, &options);
  }
  // Backward blocks of their own size (longer, or shorter, than the forward's): the same gradients within the bounds.
  for (const auto& forward_backward : {std::pair<size_t, size_t>{6, 30}, {40, 7}}) {
    mlp::HostMlpOptions options = host_options(forward_backward.first, 2);
    options.backward_target_block_rows = forward_backward.second;
    INFO("target_block_rows " << options.target_block_rows << ", backward " << options.backward_target_block_rows);
    check_against_reference_on(gemm::GemmBackend::host, test::small_mlp_config(true), 5, 6, 9, 110, &options);
  }
  mlp::MlpConfig paper;
  paper.seed = 8;
  const mlp::HostMlpOptions one_ray_per_block = host_options(1, 2);
  check_against_reference_on(gemm::GemmBackend::host, paper, 3, 16, 8, 108, &one_ray_per_block);
  // By default the backward of a network 256 wide takes blocks twice as long as its forward's; narrower ones the same.
  CHECK(mlp::backward_block_rows_for(paper.width, 256) == 512);
  CHECK(mlp::backward_block_rows_for(test::small_mlp_config(true).width, 256) == 256);
}

TEST_CASE("mlp device: the host path flushes denormals in its threads and gives the caller's setting back") {
  // Why the host path flushes: core/flush_denormals.hpp. Every weight 1 but the first layer's, 2^-70, features 2^-70:
  // the first products are 2^-140 (denormal), so a thread that flushes computes 0 all the way to the outputs, while
  // the exact values grow back to normal floats (~2^-121) by the outputs (the reference shows them). Blocks of one
  // ray on two threads: the caller's thread and a worker both compute.
#if defined(__x86_64__)
  if (!host_backend_runs_here()) return;
  auto& ctx = test::test_context();
  mlp::MlpConfig config = test::small_mlp_config(false);
  config.skip_layer = 0;  // no skip: the features reach the first layer only
  const mlp::HostMlpOptions options = host_options(1, 2);
  const auto network = mlp::make_host_network(ctx, config, options);
  const float tiny = std::ldexp(1.0f, -70);
  auto params = network->download_params();
  std::fill(params.begin(), params.end(), 0.0f);  // biases 0
  const auto layers = network->layout().all();
  for (const auto* layer : layers) {
    const float weight = layer == layers.front() ? tiny : 1.0f;
    std::fill_n(params.begin() + layer->weight_offset, layer->in * layer->out, weight);
  }
  network->upload_params(params);
  std::mt19937 rng(5);
  Pass pass = make_pass(config, 4, 3, rng);
  std::fill(pass.features.begin(), pass.features.end(), tiny);
  DevicePass device(ctx, config, pass);
  auto workspace = network->make_workspace(pass.rows(), pass.n_rays, mlp::WorkspaceMode::inference);

  REQUIRE_FALSE(FlushDenormalsInScope::active());
  network->forward(inputs_for(device, pass, config), outputs_for(device, config), workspace);
  CHECK_FALSE(FlushDenormalsInScope::active());  // the caller's thread has its own setting back

  std::vector<double> density_ref, rgb_ref;
  ref::mlp_forward(config, test::as_double(params), dense_features(pass, config.input_width), {}, pass.n_rays,
                   pass.samples_per_ray, density_ref, rgb_ref, nullptr);
  const auto density = device.raw_density.download(ctx);
  REQUIRE(density.size() == density_ref.size());
  for (size_t i = 0; i < density.size(); ++i) {
    CAPTURE(i);
    CHECK(density_ref[i] > std::ldexp(1.0, -126));  // the exact value is a normal float...
    CHECK(density[i] == 0.0f);                      // ...which only a chain of flushed denormals makes 0
  }
  {
    const FlushDenormalsInScope flush;
    CHECK(FlushDenormalsInScope::active());
  }
  CHECK_FALSE(FlushDenormalsInScope::active());
#else
  test::skip_test("denormals are flushed on x86-64 only (core/flush_denormals.hpp)");
#endif
}

TEST_CASE("mlp device: the host path on every CPU GEMM library built in matches the reference") {
  // Each library for every product (libxsmm, which cannot run backward-data products, for all the others), two
  // threads on blocks of a few rays, the small networks and the paper's.
  if (!host_backend_runs_here()) return;
  mlp::MlpConfig paper;
  paper.seed = 9;
  for (const auto& library : gemm::cpu_sgemm_libraries()) {
    INFO("CPU GEMM library " << library.name);
    for (const size_t block_rows : {size_t{20}, size_t{256}}) {
      mlp::HostMlpOptions options = host_options(block_rows, 2);
      if (library.every_shape) {
        options.libraries.fallback = library.name;
      } else {
        // By label, as tune stores it: every product of the passes below that the library can run. The blocks are
        // whole rays (block_rows / samples rays each, the last one ragged), so list the labels of each block size.
        for (const auto* config : {&paper}) {
          for (size_t rows = 1; rows <= 256; ++rows) {
            for (const auto& p : mlp::mlp_gemm_problems(*config, rows)) {
              if (p.shape.transpose_b) continue;
              const gemm::HostProductShape shape{p.shape.transpose_a, false, p.shape.m, p.shape.n, p.shape.k};
              options.libraries.by_product[gemm::host_product_label(shape)] = library.name;
            }
          }
        }
      }
      check_against_reference_on(gemm::GemmBackend::host, paper, 3, 16, 8, 109, &options);
      if (library.every_shape) {
        check_against_reference_on(gemm::GemmBackend::host, test::small_mlp_config(true), 5, 6, 9, 110, &options);
      }
    }
  }
}

TEST_CASE("mlp device: zero_grad clears, and a repeated backward accumulates exactly twice") {
  auto& ctx = test::test_context();
  const auto config = test::small_mlp_config(true);
  std::mt19937 rng(7);
  const auto net_owner = mlp::make_network(ctx, config, gemm::GemmBackend::automatic);
  mlp::Network& net = *net_owner;
  const Pass p = make_pass(config, 3, 4, rng);
  DevicePass d(ctx, config, p);
  auto ws = net.make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::training);
  net.forward(inputs_for(d, p, config), outputs_for(d, config), ws);
  net.backward(ws, gradients_for(d, config));
  const auto once = net.download_grads();
  net.backward(ws, gradients_for(d, config));
  const auto twice = net.download_grads();
  size_t nonzero = 0;
  for (size_t i = 0; i < once.size(); ++i) {
    CHECK(twice[i] == 2.0f * once[i]);  // x + x is exact in float
    nonzero += once[i] != 0.0f;
  }
  CHECK(nonzero > once.size() / 2);
  net.zero_grad();
  for (float g : net.download_grads()) CHECK(g == 0.0f);
}

TEST_CASE("mlp device: misuse is refused with a message that says what to do, on every backend") {
  auto& ctx = test::test_context();
  const auto config = test::small_mlp_config(true);
  for (const gemm::GemmBackend backend : test::supported_gemm_backends(ctx)) {
    INFO("gemm_backend = " << enum_name(backend));
    std::mt19937 rng(8);
    const auto net_owner = mlp::make_network(ctx, config, backend);
    mlp::Network& net = *net_owner;
    const Pass p = make_pass(config, 4, 4, rng);
    DevicePass d(ctx, config, p);
    auto ws = net.make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::training);
    CHECK_THROWS_WITH_AS(net.backward(ws, gradients_for(d, config)), doctest::Contains("no forward"), Error);
    auto small = net.make_workspace(p.rows() - 1, p.n_rays, mlp::WorkspaceMode::training);
    CHECK_THROWS_WITH_AS(net.forward(inputs_for(d, p, config), outputs_for(d, config), small),
                         doctest::Contains("exceeds the workspace"), Error);
    auto infer = net.make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::inference);
    net.forward(inputs_for(d, p, config), outputs_for(d, config), infer);
    CHECK_THROWS_WITH_AS(net.backward(infer, gradients_for(d, config)), doctest::Contains("inference workspace"),
                         Error);
    auto other = mlp::make_network(ctx, test::small_mlp_config(false), backend)
                     ->make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::training);
    CHECK_THROWS_WITH_AS(net.forward(inputs_for(d, p, config), outputs_for(d, config), other),
                         doctest::Contains("another MLP configuration"), Error);
    CHECK_THROWS_WITH_AS(net.upload_params(std::vector<float>(3)), doctest::Contains("parameter values"), Error);
    // Buffers too small for the chunk are refused before either backend touches them (the host one would write
    // through a mapped pointer past the end).
    ocl::DeviceArray<float> short_density(ctx, p.rows() - 1, "raw_density too short");
    CHECK_THROWS_WITH_AS(net.forward(inputs_for(d, p, config),
                                     {ocl::view(short_density, 1), ocl::view(d.raw_rgb, config.rgb_outputs)}, ws),
                         doctest::Contains("raw_density too short"), Error);
    ocl::DeviceArray<float> short_features(ctx, p.rows() * config.input_width - 1, "features too short");
    mlp::MlpInputs short_in = inputs_for(d, p, config);
    short_in.features = ocl::view(short_features, config.input_width);
    CHECK_THROWS_WITH_AS(net.forward(short_in, outputs_for(d, config), ws), doctest::Contains("features too short"),
                         Error);
    net.forward(inputs_for(d, p, config), outputs_for(d, config), ws);
    CHECK_THROWS_WITH_AS(net.backward(ws, {ocl::view(short_density, 1), ocl::view(d.d_rgb, config.rgb_outputs)}),
                         doctest::Contains("raw_density too short"), Error);
    // ∂loss/∂features: too short, or over the features it is the gradient of (the backward would read what it wrote).
    ocl::DeviceArray<float> short_d_features(ctx, p.rows() * config.input_width - 1, "d_features too short");
    CHECK_THROWS_WITH_AS(net.backward(ws, gradients_for(d, config), ocl::view(short_d_features, config.input_width)),
                         doctest::Contains("d_features too short"), Error);
    CHECK_THROWS_WITH_AS(net.backward(ws, gradients_for(d, config), inputs_for(d, p, config).features),
                         doctest::Contains("overlaps the features"), Error);
    mlp::MlpInputs no_view = inputs_for(d, p, config);
    no_view.view_encoding = {};
    CHECK_THROWS_WITH_AS(net.forward(no_view, outputs_for(d, config), ws), doctest::Contains("view encoding"), Error);
  }
}

TEST_CASE("mlp device: a training workspace made by another backend's network is refused, saying whose it is") {
  auto& ctx = test::test_context();
  const auto backends = test::supported_gemm_backends(ctx);
  if (backends.size() < 2) {
    test::skip_test("the device runs one GEMM backend: no other backend's workspace to refuse");
    return;
  }
  const auto config = test::small_mlp_config(true);
  std::mt19937 rng(9);
  const Pass p = make_pass(config, 4, 4, rng);
  DevicePass d(ctx, config, p);
  for (const gemm::GemmBackend backend : backends) {
    for (const gemm::GemmBackend maker : backends) {
      if (maker == backend) continue;
      INFO("network on " << enum_name(backend) << ", workspace from " << enum_name(maker));
      const auto net = mlp::make_network(ctx, config, backend);
      const auto other = mlp::make_network(ctx, config, maker);
      auto foreign = other->make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::training);
      CHECK_THROWS_WITH_AS(net->forward(inputs_for(d, p, config), outputs_for(d, config), foreign),
                           doctest::Contains("made by a network on another GEMM backend"), Error);
      CHECK_THROWS_WITH_AS(net->forward(inputs_for(d, p, config), outputs_for(d, config), foreign),
                           doctest::Contains("make each network's workspaces with its own make_workspace"), Error);
    }
  }
}

TEST_CASE("mlp device: workspace size estimate matches what it allocates, and bounds memory by chunk") {
  mlp::MlpConfig config;
  const size_t rows = 4096 * 4, rays = 4096 / 32;
  const size_t training = mlp::Workspace::bytes_for(config, rows, rays, mlp::WorkspaceMode::training);
  const size_t inference = mlp::Workspace::bytes_for(config, rows, rays, mlp::WorkspaceMode::inference);
  // Training keeps 8 trunk activations, the bottleneck (256 wide), the view branch (128) and 2 backward
  // buffers: 11.5 [rows][256] matrices, plus small per-block and per-ray sums.
  CHECK(training > 11.5 * rows * 256 * sizeof(float));
  CHECK(training < 12 * rows * 256 * sizeof(float));
  CHECK(inference < training / 5);
  CHECK(mlp::Workspace::bytes_for(config, 2 * rows, rays, mlp::WorkspaceMode::training) < 2 * training + 1);
}

namespace {

struct BackendRun {
  std::vector<float> raw_density, raw_rgb, grads;
};

// One forward and backward of the paper's network on `backend`, from the same seed (so the same data and weights).
BackendRun run_on(gemm::GemmBackend backend, unsigned seed) {
  auto& ctx = test::test_context();
  mlp::MlpConfig config;
  config.seed = 6;
  std::mt19937 rng(seed);
  const auto network = mlp::make_network(ctx, config, backend);
  REQUIRE(network->backend() == backend);
  mlp::Network& net = *network;
  const Pass p = make_pass(config, 6, 32, rng);
  DevicePass d(ctx, config, p);
  auto ws = net.make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::training);
  net.zero_grad();
  net.forward(inputs_for(d, p, config), outputs_for(d, config), ws);
  net.backward(ws, gradients_for(d, config));
  return {d.raw_density.download(ctx), d.raw_rgb.download(ctx), net.download_grads()};
}

}  // namespace

TEST_CASE("mlp device: the host BLAS and CLBlast backends agree on outputs and gradients") {
  if (!host_backend_runs_here()) return;
  const BackendRun clblast = run_on(gemm::GemmBackend::clblast, 105);
  const BackendRun host = run_on(gemm::GemmBackend::host, 105);
  // Both are float32 with different summation orders. Each stays within the float32 bound above (≈ 5.5e-6 of a
  // tensor's largest value, from √(chain) · √K · u) of the exact result, so they differ by at most twice that:
  // 1.1e-5 of the tensor's largest value (plus 1e-7 absolute for tensors that are all ~0). Not kRelative (3e-5):
  // that bound has head room over the estimate, this one is the estimate itself for two float32 results.
  constexpr double kBetweenBackends = 1.1e-5;
  const auto as_ref = [](const std::vector<float>& v) { return test::as_double(v); };
  test::check_close(host.raw_density, as_ref(clblast.raw_density), 0, clblast.raw_density.size(), kBetweenBackends,
                    kAbsolute, "raw_density host vs clblast");
  test::check_close(host.raw_rgb, as_ref(clblast.raw_rgb), 0, clblast.raw_rgb.size(), kBetweenBackends, kAbsolute,
                    "raw_rgb host vs clblast");
  const mlp::ParameterLayout layout = mlp::parameter_layout(mlp::MlpConfig{});  // all() points into it
  for (const auto* layer : layout.all()) {
    test::check_close(host.grads, as_ref(clblast.grads), layer->weight_offset, layer->in * layer->out,
                      kBetweenBackends, kAbsolute, layer->name + " weight gradient host vs clblast");
    test::check_close(host.grads, as_ref(clblast.grads), layer->bias_offset, layer->out, kBetweenBackends, kAbsolute,
                      layer->name + " bias gradient host vs clblast");
  }
}

namespace {

// FLOPs of the products of one forward over `rows` samples of `rays` rays, counted from the architecture (mlp.hpp):
// 2·m·n·k per product, the view encoding's product once per ray.
double forward_flops(const mlp::MlpConfig& c, double rows, double rays) {
  double per_row = c.input_width * c.width;
  for (size_t i = 1; i < c.depth; ++i) per_row += (c.width + (mlp::skip_after(c, i - 1) ? c.input_width : 0)) * c.width;
  per_row += c.width * c.density_outputs;
  return 2.0 * rows * per_row + test::colour_head_flops(c, rows, rays);
}

// The backward's input-gradient products: every layer's but the first's and the inputs' (features, view encoding).
double backward_data_flops(const mlp::MlpConfig& c, double rows) {
  const double per_row = (c.depth - 1) * c.width * c.width + c.width * c.density_outputs;
  return 2.0 * rows * per_row + test::colour_head_flops(c, rows, 0.0);  // no per-ray product: the view encoding
}

// Runs body(config, net, pass, device pass, workspace) for the small network with and without view dependence on
// every backend the test device supports: a pass of 5 rays × 6 samples drawn with `seed`, a workspace of `mode`.
template <typename Body>
void for_each_small_network(ocl::Context& ctx, unsigned seed, mlp::WorkspaceMode mode, const Body& body) {
  for (const bool view : {true, false}) {
    const mlp::MlpConfig config = test::small_mlp_config(view);
    for (const gemm::GemmBackend backend : test::supported_gemm_backends(ctx)) {
      INFO("gemm_backend = " << enum_name(backend) << ", view dependence " << view);
      std::mt19937 rng(seed);
      const auto network = mlp::make_network(ctx, config, backend);
      const Pass p = make_pass(config, 5, 6, rng);
      DevicePass d(ctx, config, p);
      auto ws = network->make_workspace(p.rows(), p.n_rays, mode);
      body(config, *network, p, d, ws);
    }
  }
}

}  // namespace

TEST_CASE("mlp device: the stage profile counts every product's FLOPs, the same on each backend") {
  ocl::Context ctx(test::test_context().device_info(), true);
  for_each_small_network(ctx, 109, mlp::WorkspaceMode::training, [&](const mlp::MlpConfig& config, mlp::Network& net,
                                                                     const Pass& p, DevicePass& d, mlp::Workspace& ws) {
    const ocl::StageProfile profile = test::profile_once(ctx, [&] {
      net.forward(inputs_for(d, p, config), outputs_for(d, config), ws);
      net.backward(ws, gradients_for(d, config));
    });
    const auto* forward = profile.find("gemm forward");
    const auto* data = profile.find("gemm backward_data");
    const auto* weights = profile.find("gemm backward_weights");
    REQUIRE(forward != nullptr);
    REQUIRE(data != nullptr);
    REQUIRE(weights != nullptr);
    const double rows = static_cast<double>(p.rows()), rays = static_cast<double>(p.n_rays);
    CHECK(forward->flops == forward_flops(config, rows, rays));
    CHECK(weights->flops == forward_flops(config, rows, rays));  // one weight-gradient product per weight block
    CHECK(data->flops == backward_data_flops(config, rows));
    CHECK(forward->seconds > 0.0);
    CHECK(profile.stage_seconds() <= profile.wall_seconds);
  });
}

namespace {

// The features feed layer 0 and every skip layer: their gradient takes one [rows][input_width] × width product each.
double features_gradient_flops(const mlp::MlpConfig& c, double rows) {
  size_t layers = 1;
  for (size_t i = 1; i < c.depth; ++i) layers += mlp::skip_after(c, i - 1) ? 1 : 0;
  return 2.0 * rows * c.input_width * c.width * static_cast<double>(layers);
}

// The parameter gradients of one backward of `pass` (after net's forward through ws) from zero, and its profile.
std::vector<float> gradients_of_backward(ocl::Context& ctx, mlp::Network& net, mlp::Workspace& ws,
                                         const mlp::MlpOutputGradients& d_out, const ocl::MatrixView& d_features,
                                         ocl::StageProfile* profile) {
  net.zero_grad();
  const auto run = [&] { net.backward(ws, d_out, d_features); };
  if (profile) {
    *profile = test::profile_once(ctx, run);
  } else {
    run();
  }
  return net.download_grads();
}

}  // namespace

TEST_CASE("mlp device: asking for the features' gradient changes no parameter gradient and adds only its products") {
  // mip-NeRF's paths never ask for it: they must compute what they did, bit for bit, with no product more.
  ocl::Context ctx(test::test_context().device_info(), true);  // profiling on
  for_each_small_network(ctx, 113, mlp::WorkspaceMode::training, [&](const mlp::MlpConfig& config, mlp::Network& net,
                                                                      const Pass& p, DevicePass& d, mlp::Workspace& ws) {
    net.forward(inputs_for(d, p, config), outputs_for(d, config), ws);
    FeatureGradient d_features(ctx, config, p.rows());
    ocl::StageProfile without, with;
    const auto grads_without = gradients_of_backward(ctx, net, ws, gradients_for(d, config), {}, &without);
    const auto grads_with = gradients_of_backward(ctx, net, ws, gradients_for(d, config), d_features.view(), &with);
    CHECK(grads_with == grads_without);
    const auto* data_without = without.find("gemm backward_data");
    const auto* data_with = with.find("gemm backward_data");
    const auto* weights_without = without.find("gemm backward_weights");
    const auto* weights_with = with.find("gemm backward_weights");
    REQUIRE(data_without != nullptr);
    REQUIRE(data_with != nullptr);
    REQUIRE(weights_without != nullptr);
    REQUIRE(weights_with != nullptr);
    const double rows = static_cast<double>(p.rows());
    CHECK(data_without->flops == backward_data_flops(config, rows));  // nothing extra when not asked for
    CHECK(data_with->flops == backward_data_flops(config, rows) + features_gradient_flops(config, rows));
    CHECK(weights_with->flops == weights_without->flops);
    CHECK(without.find("gemm forward") == nullptr);
    // A second backward overwrites the features' gradient (it does not add to it).
    const auto first = d_features.download(ctx);
    gradients_of_backward(ctx, net, ws, gradients_for(d, config), d_features.view(), nullptr);
    CHECK(d_features.download(ctx) == first);
  });
}

TEST_CASE("mlp device: the host path's threads leave the parameter gradients bit for bit when asked for the features'") {
  // Blocks of one ray on three threads (each block writes its own rows of the features' gradient), the paper's network.
  if (!host_backend_runs_here()) return;
  auto& ctx = test::test_context();
  mlp::MlpConfig config;
  config.seed = 10;
  const auto network = mlp::make_host_network(ctx, config, host_options(1, 3));
  std::mt19937 rng(114);
  const Pass p = make_pass(config, 5, 8, rng);
  DevicePass d(ctx, config, p);
  auto ws = network->make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::training);
  network->forward(inputs_for(d, p, config), outputs_for(d, config), ws);
  FeatureGradient d_features(ctx, config, p.rows());
  const auto grads_without = gradients_of_backward(ctx, *network, ws, gradients_for(d, config), {}, nullptr);
  const auto grads_with =
      gradients_of_backward(ctx, *network, ws, gradients_for(d, config), d_features.view(), nullptr);
  CHECK(grads_with == grads_without);
}

// Rendering evaluates the levels before the last for their densities only (graph.hpp): an inference forward without
// a colour output runs the trunk and the density head and nothing else, with the full forward's densities.
TEST_CASE("mlp device: a density-only inference forward gives the full forward's densities from the trunk alone") {
  ocl::Context ctx(test::test_context().device_info(), true);  // profiling on
  for_each_small_network(ctx, 111, mlp::WorkspaceMode::inference, [&](const mlp::MlpConfig& config, mlp::Network& net,
                                                                      const Pass& p, DevicePass& d, mlp::Workspace& ws) {
    net.forward(inputs_for(d, p, config), outputs_for(d, config), ws);
    const auto full_density = d.raw_density.download(ctx);
    const std::vector<float> sentinel(p.rows() * config.rgb_outputs, 7.0f);
    d.raw_rgb.upload(ctx, sentinel);
    d.raw_density.upload(ctx, std::vector<float>(full_density.size(), 0.0f));
    const mlp::MlpOutputs density_only{ocl::view(d.raw_density, config.density_outputs), {}};
    const ocl::StageProfile profile =
        test::profile_once(ctx, [&] { net.forward(inputs_for(d, p, config), density_only, ws); });
    CHECK(d.raw_density.download(ctx) == full_density);
    CHECK(d.raw_rgb.download(ctx) == sentinel);  // no colour written
    // The products are the trunk's and the density head's only: the forward's count minus the colour head's.
    const double rows = static_cast<double>(p.rows()), rays = static_cast<double>(p.n_rays);
    const auto* forward = profile.find("gemm forward");
    REQUIRE(forward != nullptr);
    CHECK(forward->flops == forward_flops(config, rows, rays) - test::colour_head_flops(config, rows, rays));
    // A training forward must compute the colour its backward needs.
    auto training = net.make_workspace(p.rows(), p.n_rays, mlp::WorkspaceMode::training);
    CHECK_THROWS_WITH_AS(net.forward(inputs_for(d, p, config), density_only, training),
                         doctest::Contains("density-only forward is for inference"), Error);
  });
}

