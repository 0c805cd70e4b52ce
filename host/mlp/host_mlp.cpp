// The MLP fused on the host, block of rays by block of rays (see host_mlp.hpp).
#include "mlp/host_mlp.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>

#include "core/error.hpp"
#include "core/flush_denormals.hpp"
#include "gemm/host_gemm.hpp"

namespace mipnerf::mlp {

namespace {

using Clock = std::chrono::steady_clock;

enum class ProductKind { forward, backward_data, backward_weights };

// ReLU that keeps NaN (NaN < 0 is false), as kernels/mlp.cl: a non-finite value must reach the outputs.
inline float relu_keep_nan(float v) { return v < 0.0f ? 0.0f : v; }

}  // namespace

struct HostMlp::Worker {
  const gemm::HostProductTable* products = nullptr;
  bool timed = false;
  HostMlpTimes times;
  std::vector<float> scratch[3];  // [block rows][widest layer] each
  std::vector<float> ray_term;    // [rays per block][view_branch_width]
  std::vector<float> grads;       // [parameters]: this thread's share of a backward
  Clock::time_point busy_start;

  // Ready for a call: times reset, scratch for blocks of block_rows rows (cols wide) and of `rays` rays (ray_cols).
  void begin_call(bool timed_call, size_t block_rows, size_t cols, size_t rays, size_t ray_cols) {
    timed = timed_call;
    times = HostMlpTimes{};
    busy_start = Clock::now();
    for (auto& s : scratch) s.resize(std::max(s.size(), block_rows * cols));
    ray_term.resize(std::max(ray_term.size(), rays * ray_cols));
  }
  // The call's thread time outside the products: the element-wise work.
  void end_call() {
    if (timed) times.elementwise = std::max(0.0, std::chrono::duration<double>(Clock::now() - busy_start).count() - times.total());
  }

  // C[m][n] = beta·C + op(A)·op(B), row-major, one BLAS thread (the caller's).
  void product(ProductKind kind, bool trans_a, bool trans_b, size_t m, size_t n, size_t k, const float* a, size_t lda,
               const float* b, size_t ldb, float beta, float* c, size_t ldc) {
    if (m == 0 || n == 0) return;
    const double flops = 2.0 * static_cast<double>(m) * n * k;
    const auto start = timed ? Clock::now() : Clock::time_point{};
    const gemm::HostProductShape shape{trans_a, trans_b, m, n, k};
    products->library_for(shape).sgemm(trans_a, trans_b, static_cast<int>(m), static_cast<int>(n),
                                       static_cast<int>(k), a, static_cast<int>(lda), b, static_cast<int>(ldb), beta,
                                       c, static_cast<int>(ldc));
    const double seconds = timed ? std::chrono::duration<double>(Clock::now() - start).count() : 0.0;
    switch (kind) {
      case ProductKind::forward:
        times.gemm_forward += seconds;
        times.flops_forward += flops;
        break;
      case ProductKind::backward_data:
        times.gemm_backward_data += seconds;
        times.flops_backward_data += flops;
        break;
      case ProductKind::backward_weights:
        times.gemm_backward_weights += seconds;
        times.flops_backward_weights += flops;
        break;
    }
  }
};

namespace {

// The element-wise epilogues below run on every block between the products (4-6 % of a quick-preset step). The
// library is built for the baseline x86-64 (SSE2: 4 floats a vector), so each is also compiled for AVX2 and AVX-512
// and the loader picks the widest the CPU has (GCC function multi-versioning). Every loop is element-wise or sums
// each column in row order, so the result is the same float for float whichever version runs.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define MIPNERF_WIDEST_VECTORS __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define MIPNERF_WIDEST_VECTORS
#endif

// z[r][c] = act(z[r][c] + bias[c]) over a block, act = ReLU when relu.
MIPNERF_WIDEST_VECTORS
void add_bias(float* __restrict z, size_t ld, size_t rows, size_t cols, const float* __restrict bias, bool relu) {
  for (size_t r = 0; r < rows; ++r) {
    float* row = z + r * ld;
    if (relu) {
      for (size_t c = 0; c < cols; ++c) row[c] = relu_keep_nan(row[c] + bias[c]);
    } else {
      for (size_t c = 0; c < cols; ++c) row[c] += bias[c];
    }
  }
}

// The view layer's epilogue: z[r][c] = ReLU(z[r][c] + ray_term[r / samples_per_ray][c] + bias[c]).
MIPNERF_WIDEST_VECTORS
void add_ray_term_relu(float* __restrict z, size_t ld, size_t rows, size_t cols, const float* __restrict ray_term,
                       size_t samples_per_ray, const float* __restrict bias) {
  for (size_t r = 0; r < rows; ++r) {
    float* row = z + r * ld;
    const float* term = ray_term + (r / samples_per_ray) * cols;
    for (size_t c = 0; c < cols; ++c) row[c] = relu_keep_nan(row[c] + term[c] + bias[c]);
  }
}

// The backward of a ReLU and of its bias, in place: dz[r][c] = act[r][c] > 0 ? dz[r][c] : 0 (act is the ReLU's
// output, > 0 exactly where its input was), and bias_grad[c] += Σ_r dz[r][c].
MIPNERF_WIDEST_VECTORS
void relu_mask_and_sum(float* __restrict dz, size_t ld, const float* __restrict act, size_t act_ld, size_t rows,
                       size_t cols, float* __restrict bias_grad) {
  for (size_t r = 0; r < rows; ++r) {
    float* row = dz + r * ld;
    const float* a = act + r * act_ld;
    for (size_t c = 0; c < cols; ++c) {
      row[c] = a[c] > 0.0f ? row[c] : 0.0f;
      bias_grad[c] += row[c];
    }
  }
}

// acc[c] += Σ_r d[r][c].
MIPNERF_WIDEST_VECTORS
void column_sums(const float* __restrict d, size_t ld, size_t rows, size_t cols, float* __restrict acc) {
  for (size_t r = 0; r < rows; ++r) {
    const float* row = d + r * ld;
    for (size_t c = 0; c < cols; ++c) acc[c] += row[c];
  }
}

}  // namespace

HostMlp::HostMlp(const MlpConfig& config, HostMlpOptions options)
    : config_(config), layout_(parameter_layout(config)), options_(options) {
  config_.validate();
  if (options_.threads == 0) options_.threads = 1;
  if (options_.target_block_rows == 0) options_.target_block_rows = 1;
  products_ = std::make_unique<gemm::HostProductTable>(options_.libraries);
  workers_.resize(options_.threads);
  for (auto& worker : workers_) worker.products = products_.get();
}

HostMlp::~HostMlp() = default;

size_t rays_per_block(size_t target_rows, size_t samples_per_ray) {
  return std::max<size_t>(1, target_rows / std::max<size_t>(1, samples_per_ray));
}

size_t backward_block_rows_for(size_t width, size_t target_block_rows) {
  return width >= 256 ? 2 * target_block_rows : target_block_rows;
}

size_t forward_block_rows(const HostMlpOptions& options, size_t samples_per_ray) {
  return rays_per_block(options.target_block_rows, samples_per_ray) * std::max<size_t>(1, samples_per_ray);
}

size_t backward_block_rows(const HostMlpOptions& options, size_t width, size_t samples_per_ray) {
  const size_t target = options.backward_target_block_rows > 0
                            ? options.backward_target_block_rows
                            : backward_block_rows_for(width, options.target_block_rows);
  return rays_per_block(target, samples_per_ray) * std::max<size_t>(1, samples_per_ray);
}

size_t HostMlp::rays_per_block(size_t samples_per_ray) const {
  return forward_block_rows(options_, samples_per_ray) / std::max<size_t>(1, samples_per_ray);
}

size_t HostMlp::backward_rays_per_block(size_t samples_per_ray) const {
  return backward_block_rows(options_, config_.width, samples_per_ray) / std::max<size_t>(1, samples_per_ray);
}

namespace {

// MIPNERF_KEEP_DENORMALS=1: the host MLP computes with denormals as they come (bench/studies/denormals.py compares the two);
// by default its threads flush them (core/flush_denormals.hpp: training's steps slowed 1.7x without).
bool keep_denormals() {
  static const bool keep = [] {
    const char* value = std::getenv("MIPNERF_KEEP_DENORMALS");
    return value != nullptr && std::string(value) == "1";
  }();
  return keep;
}

// Runs work(worker, first_block, end_block) on `threads` threads over n_blocks blocks, contiguous ranges in thread
// order (the calling thread takes the first), each thread holding the table's libraries to itself first (oneDNN's
// OpenMP thread count is per calling thread) and flushing denormals while it works (the calling thread gets its
// setting back). Rethrows the first exception after every thread has ended. Returns how
// many threads ran (at least one, at most one per block).
template <typename Work>
size_t run_blocks(size_t threads, size_t n_blocks, const gemm::HostProductTable& products, const Work& work) {
  const size_t t_count = std::max<size_t>(1, std::min(threads, n_blocks));
  std::vector<std::exception_ptr> errors(t_count);
  auto range = [&](size_t t) {
    const FlushDenormalsInScope flush(!keep_denormals());  // core/flush_denormals.hpp
    try {
      for (const gemm::CpuSgemmLibrary* library : products.libraries()) library->set_threads(1);
      work(t, t * n_blocks / t_count, (t + 1) * n_blocks / t_count);
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < t_count; ++t) pool.emplace_back(range, t);
  range(0);
  for (auto& thread : pool) thread.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return t_count;
}

// Sets the host BLAS to one thread per call while it lives (our threads split the rows), then restores it.
class SingleThreadedBlas {
 public:
  SingleThreadedBlas() : previous_(gemm::host_blas_threads()) { gemm::set_host_blas_threads(1); }
  ~SingleThreadedBlas() { gemm::set_host_blas_threads(previous_); }
  SingleThreadedBlas(const SingleThreadedBlas&) = delete;
  SingleThreadedBlas& operator=(const SingleThreadedBlas&) = delete;

 private:
  int previous_;
};

}  // namespace

// The first `threads` workers' times of the last call, summed.
HostMlpTimes HostMlp::summed_times(size_t threads) const {
  HostMlpTimes t;
  for (size_t i = 0; i < threads; ++i) {
    const HostMlpTimes& w = workers_[i].times;
    t.gemm_forward += w.gemm_forward;
    t.gemm_backward_data += w.gemm_backward_data;
    t.gemm_backward_weights += w.gemm_backward_weights;
    t.elementwise += w.elementwise;
    t.flops_forward += w.flops_forward;
    t.flops_backward_data += w.flops_backward_data;
    t.flops_backward_weights += w.flops_backward_weights;
  }
  return t;
}

HostMlpTimes HostMlp::forward(const HostForwardBuffers& b, bool timed) {
  const MlpConfig& c = config_;
  const bool training = !b.trunk.empty();
  if (training && b.trunk.size() != c.depth) throw Error("host MLP forward: expected one activation per trunk layer");
  if (training && b.rgb == nullptr) throw Error("host MLP forward: a training forward needs its colour output");
  const size_t spr = b.samples_per_ray, W = c.width, F = c.input_width, cols = widest_hidden(c);
  const size_t rays_per = rays_per_block(spr);
  const size_t n_blocks = (b.n_rays + rays_per - 1) / rays_per;
  const float* P = b.params;
  SingleThreadedBlas one_thread;

  const size_t threads = run_blocks(options_.threads, n_blocks, *products_, [&](size_t t, size_t first, size_t end) {
    Worker& w = workers_[t];
    w.begin_call(timed, rays_per * spr, cols, rays_per, c.view_dependence ? c.view_branch_width : 0);
    for (size_t block = first; block < end; ++block) {
      const size_t ray0 = block * rays_per, rays = std::min(rays_per, b.n_rays - ray0);
      const size_t row0 = ray0 * spr, rows = rays * spr;
      const float* x = b.features + row0 * b.features_ld;
      // Trunk: act_i = ReLU(in_i · W_i + b_i); a skip layer's input [act_{i−1} | features] as two products.
      float* prev = nullptr;
      for (size_t i = 0; i < c.depth; ++i) {
        const DenseLayer& L = layout_.trunk[i];
        float* out = training ? b.trunk[i] + row0 * W : w.scratch[i % 2].data();
        if (i == 0) {
          w.product(ProductKind::forward, false, false, rows, W, F, x, b.features_ld, P + L.weight_offset, W, 0.0f,
                    out, W);
        } else {
          w.product(ProductKind::forward, false, false, rows, W, W, prev, W, P + L.weight_offset, W, 0.0f, out, W);
          if (skip_after(c, i - 1)) {
            w.product(ProductKind::forward, false, false, rows, W, F, x, b.features_ld, P + L.weight_offset + W * W,
                      W, 1.0f, out, W);
          }
        }
        add_bias(out, W, rows, W, P + L.bias_offset, true);
        prev = out;
      }
      const float* h = prev;
      const DenseLayer& D = layout_.density;
      float* density = b.density + row0 * b.density_ld;
      w.product(ProductKind::forward, false, false, rows, D.out, W, h, W, P + D.weight_offset, D.out, 0.0f, density,
                b.density_ld);
      add_bias(density, b.density_ld, rows, D.out, P + D.bias_offset, false);
      if (b.rgb == nullptr) continue;  // density only
      const DenseLayer& R = layout_.rgb;
      float* rgb = b.rgb + row0 * b.rgb_ld;
      if (!c.view_dependence) {
        w.product(ProductKind::forward, false, false, rows, R.out, W, h, W, P + R.weight_offset, R.out, 0.0f, rgb,
                  b.rgb_ld);
        add_bias(rgb, b.rgb_ld, rows, R.out, P + R.bias_offset, false);
        continue;
      }
      // View branch: bottleneck (no activation); [bottleneck | view] · W_view with the view part once per ray.
      const DenseLayer& B = layout_.bottleneck;
      const DenseLayer& V = layout_.view;
      const size_t Wb = B.out, Wv = V.out;
      // Inference: the bottleneck into the scratch h is not in, the view layer back into h's (h is done with).
      float* bneck = training ? b.bottleneck + row0 * Wb : w.scratch[c.depth % 2].data();
      float* hidden = training ? b.view_hidden + row0 * Wv : w.scratch[(c.depth - 1) % 2].data();
      w.product(ProductKind::forward, false, false, rows, Wb, W, h, W, P + B.weight_offset, Wb, 0.0f, bneck, Wb);
      add_bias(bneck, Wb, rows, Wb, P + B.bias_offset, false);
      w.product(ProductKind::forward, false, false, rays, Wv, c.view_width, b.view_encoding + ray0 * b.view_ld,
                b.view_ld, P + V.weight_offset + Wb * Wv, Wv, 0.0f, w.ray_term.data(), Wv);
      w.product(ProductKind::forward, false, false, rows, Wv, Wb, bneck, Wb, P + V.weight_offset, Wv, 0.0f, hidden,
                Wv);
      add_ray_term_relu(hidden, Wv, rows, Wv, w.ray_term.data(), spr, P + V.bias_offset);
      w.product(ProductKind::forward, false, false, rows, R.out, Wv, hidden, Wv, P + R.weight_offset, R.out, 0.0f,
                rgb, b.rgb_ld);
      add_bias(rgb, b.rgb_ld, rows, R.out, P + R.bias_offset, false);
    }
    w.end_call();
  });
  return summed_times(threads);
}

HostMlpTimes HostMlp::backward(const HostBackwardBuffers& bb, bool timed) {
  const MlpConfig& c = config_;
  const HostForwardBuffers& b = bb.saved;
  if (b.trunk.size() != c.depth) throw Error("host MLP backward: the forward kept no activations (inference?)");
  const size_t spr = b.samples_per_ray, W = c.width, F = c.input_width, cols = widest_hidden(c);
  const size_t rays_per = backward_rays_per_block(spr);
  const size_t n_blocks = (b.n_rays + rays_per - 1) / rays_per;
  const float* P = b.params;
  SingleThreadedBlas one_thread;

  const size_t t_count = run_blocks(options_.threads, n_blocks, *products_, [&](size_t t, size_t first, size_t end) {
    Worker& w = workers_[t];
    w.begin_call(timed, rays_per * spr, cols, rays_per, c.view_dependence ? c.view_branch_width : 0);
    w.grads.assign(layout_.total, 0.0f);
    float* G = w.grads.data();
    for (size_t block = first; block < end; ++block) {
      const size_t ray0 = block * rays_per, rays = std::min(rays_per, b.n_rays - ray0);
      const size_t row0 = ray0 * spr, rows = rays * spr;
      const float* x = b.features + row0 * b.features_ld;
      const float* h = b.trunk[c.depth - 1] + row0 * W;
      const float* d_density = bb.d_density + row0 * bb.d_density_ld;
      const float* d_rgb = bb.d_rgb + row0 * bb.d_rgb_ld;
      float* dh = w.scratch[0].data();  // ∂loss/∂h [rows][W]
      const DenseLayer& D = layout_.density;
      const DenseLayer& R = layout_.rgb;
      column_sums(d_density, bb.d_density_ld, rows, D.out, G + D.bias_offset);
      w.product(ProductKind::backward_weights, true, false, W, D.out, rows, h, W, d_density, bb.d_density_ld, 1.0f,
                G + D.weight_offset, D.out);
      column_sums(d_rgb, bb.d_rgb_ld, rows, R.out, G + R.bias_offset);
      if (!c.view_dependence) {
        w.product(ProductKind::backward_weights, true, false, W, R.out, rows, h, W, d_rgb, bb.d_rgb_ld, 1.0f,
                  G + R.weight_offset, R.out);
        w.product(ProductKind::backward_data, false, true, rows, W, R.out, d_rgb, bb.d_rgb_ld, P + R.weight_offset,
                  R.out, 0.0f, dh, W);
      } else {
        const DenseLayer& B = layout_.bottleneck;
        const DenseLayer& V = layout_.view;
        const size_t Wb = B.out, Wv = V.out;
        const float* hidden = b.view_hidden + row0 * Wv;
        const float* bneck = b.bottleneck + row0 * Wb;
        float* d_hidden = w.scratch[1].data();
        float* d_bneck = w.scratch[2].data();
        w.product(ProductKind::backward_weights, true, false, Wv, R.out, rows, hidden, Wv, d_rgb, bb.d_rgb_ld, 1.0f,
                  G + R.weight_offset, R.out);
        w.product(ProductKind::backward_data, false, true, rows, Wv, R.out, d_rgb, bb.d_rgb_ld, P + R.weight_offset,
                  R.out, 0.0f, d_hidden, Wv);
        // View layer: the ReLU's mask, then each ray's samples summed (its view-encoding row was shared by them).
        float* d_ray = w.ray_term.data();
        std::fill(d_ray, d_ray + rays * Wv, 0.0f);
        for (size_t r = 0; r < rows; ++r) {
          float* g = d_hidden + r * Wv;
          const float* a = hidden + r * Wv;
          float* sum = d_ray + (r / spr) * Wv;
          for (size_t k = 0; k < Wv; ++k) {
            g[k] = a[k] > 0.0f ? g[k] : 0.0f;
            sum[k] += g[k];
          }
        }
        column_sums(d_ray, Wv, rays, Wv, G + V.bias_offset);
        w.product(ProductKind::backward_weights, true, false, c.view_width, Wv, rays, b.view_encoding + ray0 * b.view_ld,
                  b.view_ld, d_ray, Wv, 1.0f, G + V.weight_offset + Wb * Wv, Wv);
        w.product(ProductKind::backward_weights, true, false, Wb, Wv, rows, bneck, Wb, d_hidden, Wv, 1.0f,
                  G + V.weight_offset, Wv);
        w.product(ProductKind::backward_data, false, true, rows, Wb, Wv, d_hidden, Wv, P + V.weight_offset, Wv, 0.0f,
                  d_bneck, Wb);
        // Bottleneck (no activation).
        column_sums(d_bneck, Wb, rows, Wb, G + B.bias_offset);
        w.product(ProductKind::backward_weights, true, false, W, Wb, rows, h, W, d_bneck, Wb, 1.0f, G + B.weight_offset,
                  Wb);
        w.product(ProductKind::backward_data, false, true, rows, W, Wb, d_bneck, Wb, P + B.weight_offset, Wb, 0.0f, dh,
                  W);
      }
      // h also feeds the density head: its share adds on.
      w.product(ProductKind::backward_data, false, true, rows, W, D.out, d_density, bb.d_density_ld,
                P + D.weight_offset, D.out, 1.0f, dh, W);
      // Trunk, last layer first: dz_i = dact_i masked; W_i's gradient from its input; dact_{i−1} = dz_i · W_iᵀ.
      // Asked for, ∂loss/∂features = Σ over the layers the features feed of dz_i · W_i[their input rows]ᵀ: the
      // deepest skip layer's share overwrites the block's rows, the others (layer 0 last) add on.
      float* d_x = bb.d_features ? bb.d_features + row0 * bb.d_features_ld : nullptr;
      float d_x_beta = 0.0f;
      auto features_gradient = [&](const float* dz, const DenseLayer& L, size_t first_row) {
        w.product(ProductKind::backward_data, false, true, rows, F, W, dz, W, P + L.weight_offset + first_row * W, W,
                  d_x_beta, d_x, bb.d_features_ld);
        d_x_beta = 1.0f;
      };
      float* current = dh;
      float* other = w.scratch[1].data();
      for (size_t i = c.depth; i-- > 0;) {
        const DenseLayer& L = layout_.trunk[i];
        relu_mask_and_sum(current, W, b.trunk[i] + row0 * W, W, rows, W, G + L.bias_offset);
        if (i == 0) {
          w.product(ProductKind::backward_weights, true, false, F, W, rows, x, b.features_ld, current, W, 1.0f,
                    G + L.weight_offset, W);
          if (d_x) features_gradient(current, L, 0);
          break;
        }
        const float* prev = b.trunk[i - 1] + row0 * W;
        w.product(ProductKind::backward_weights, true, false, W, W, rows, prev, W, current, W, 1.0f,
                  G + L.weight_offset, W);
        if (skip_after(c, i - 1)) {
          w.product(ProductKind::backward_weights, true, false, F, W, rows, x, b.features_ld, current, W, 1.0f,
                    G + L.weight_offset + W * W, W);
          if (d_x) features_gradient(current, L, W);
        }
        // The first W input rows of a skip layer come from act_{i−1}, the rest from the features (above).
        w.product(ProductKind::backward_data, false, true, rows, W, W, current, W, P + L.weight_offset, W, 0.0f, other,
                  W);
        std::swap(current, other);
      }
    }
    w.end_call();
  });
  // The threads' gradients into the network's, in thread order (a fixed order: the same sums every time).
  const auto start = timed ? Clock::now() : Clock::time_point{};
  for (size_t t = 0; t < t_count; ++t) {
    const float* g = workers_[t].grads.data();
    for (size_t k = 0; k < layout_.total; ++k) bb.grads[k] += g[k];
  }
  HostMlpTimes total = summed_times(t_count);
  if (timed) total.elementwise += std::chrono::duration<double>(Clock::now() - start).count();
  return total;
}

}  // namespace mipnerf::mlp
