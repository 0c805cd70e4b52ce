// Host wrapper of kernels/encode.cl: integrated positional encoding (IPE), positional encoding (PE), and the
// fused Gaussian + IPE. Feature order (docs/ARCHITECTURE.md): [identity (PE only)] [3L sines] [3L cosines],
// index (l − min_deg)·3 + axis inside each block.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <tuple>
#include <utility>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"
#include "core/stage_options.hpp"
#include "ops/gaussian.hpp"

namespace mipnerf::ops {

struct IpeInputs {
  const ocl::DeviceArray<float>& means;  // [rows][3]
  const ocl::DeviceArray<float>& covs;   // [rows][3] diagonal
  size_t n_rows;
};

struct PeInputs {
  const ocl::DeviceArray<float>& x;  // [rows][3] (view directions: [R][3])
  size_t n_rows;
};

// How gaussian_ipe_fwd spreads its work (the GAUSSIAN_IPE_PER_ROW tunable of encode.cl).
struct EncodeTuning {
  // per_row_and_axis: gaussian_ipe_axis_fwd, arithmetic sin/cos and exp with the degrees compiled in (a program per
  // degree range, built on first use), which PoCL vectorises; needs fp64. With it ipe_fwd and pe_fwd also run per
  // (row, axis) (ipe_axis_fwd, pe_axis_fwd, a sincos per degree); otherwise per (row, degree).
  enum class FusedItems { device_default, per_row, per_row_and_degree, per_row_and_axis };
  // default: per (row, axis) on CPUs with fp64, per row on other CPUs, per (row, degree) elsewhere
  FusedItems fused_items = FusedItems::device_default;
  // gaussian_ipe_fwd's per-row items: one sincos every this many degrees, the others by angle doubling
  // (IPE_SINCOS_EVERY of encode.cl, with its error bound). 0: the device's default (encode.cpp); 1: a sincos per
  // degree. MIPNERF_IPE_SINCOS_EVERY=K overrides the default (benchmarks).
  int sincos_every = 0;
  // Build the concatenated-PE kernel (MIPNERF_CONCAT_PE) into the program: only a scene that uses it pays for its
  // compilation; without it the program is the one every other scene builds.
  bool concat_pe = false;
};

// Degrees are kernel arguments (EncodingOptions per call: positions and view directions differ); the program is
// the one specialisation of RAY_SHAPE that the fused gaussian_ipe needs. The per-(row, axis) fused kernel is the
// exception: its degrees are compiled in, a program per degree range on first use.
class Encode {
 public:
  Encode(ocl::Context& ctx, const GaussianOptions& options, const EncodeTuning& tuning = {});
  bool fused_per_row() const { return fused_items_ == EncodeTuning::FusedItems::per_row; }
  EncodeTuning::FusedItems fused_items() const { return fused_items_; }
  int sincos_every() const { return sincos_every_; }

  // Enqueues ipe_fwd: features [rows][options.ipe_width()].
  void ipe(const EncodingOptions& options, const IpeInputs& in, ocl::DeviceArray<float>& features);
  // Enqueues pe_fwd: features [rows][options.pe_width()].
  void pe(const EncodingOptions& options, const PeInputs& in, ocl::DeviceArray<float>& features);
  // Enqueues gaussian_ipe_fwd: the same features as Gaussian::fwd then ipe(), without the means/covs buffers.
  void gaussian_ipe(const EncodingOptions& options, const GaussianInputs& in, ocl::DeviceArray<float>& features);
  // Enqueues gaussian_concat_pe_fwd: features [rows][options.concat_pe_width()], PE of the Gaussian's mean then PE
  // of its signed-sqrt covariance (supplement §7). Needs an Encode built with EncodeTuning::concat_pe.
  void gaussian_concat_pe(const EncodingOptions& options, const GaussianInputs& in, ocl::DeviceArray<float>& features);

 private:
  ocl::Context* ctx_;
  // Kernel `name` of the per-(row, axis) program for degrees [min_deg, max_deg) and a sincos every `sincos_every`
  // degrees, built on first use.
  ::cl::Kernel& axis_kernel(const EncodingOptions& options, const std::string& name, int sincos_every);
  struct AxisKernelKey {
    std::string name;
    int min_deg, max_deg, sincos_every;
    bool operator<(const AxisKernelKey& other) const {
      return std::tie(name, min_deg, max_deg, sincos_every) <
             std::tie(other.name, other.min_deg, other.max_deg, other.sincos_every);
    }
  };

  GaussianOptions gaussian_options_;
  EncodeTuning::FusedItems fused_items_;
  int sincos_every_;
  std::map<AxisKernelKey, ::cl::Kernel*> axis_kernels_;
  ::cl::Kernel* ipe_;
  ::cl::Kernel* pe_;
  ::cl::Kernel* gaussian_ipe_;
  ::cl::Kernel* gaussian_concat_pe_ = nullptr;
};

}  // namespace mipnerf::ops
