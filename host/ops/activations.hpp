// Host wrapper of kernels/activations.cl: density and colour activations of the MLP's raw outputs, and their
// backward.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"
#include "core/stage_options.hpp"

namespace mipnerf::ops {

ocl::BuildOptions activation_build_options(const ActivationOptions& options);  // DENSITY_*, RGB_PADDING

struct ActivationInputs {
  const ocl::DeviceArray<float>& raw_density;  // [rows]
  const ocl::DeviceArray<float>& raw_rgb;      // [rows][3]
  size_t n_rows;
};

struct ActivationOutputs {
  ocl::DeviceArray<float>& density;  // [rows]
  ocl::DeviceArray<float>& rgb;      // [rows][3]
};

struct ActivationGradients {
  const ocl::DeviceArray<float>& d_density;  // [rows]
  const ocl::DeviceArray<float>& d_rgb;      // [rows][3]
};

struct ActivationRawGradients {
  ocl::DeviceArray<float>& d_raw_density;  // [rows]
  ocl::DeviceArray<float>& d_raw_rgb;      // [rows][3]
};

class Activations {
 public:
  Activations(ocl::Context& ctx, const ActivationOptions& options);
  const ActivationOptions& options() const { return options_; }

  // Enqueues activations_fwd.
  void fwd(const ActivationInputs& in, const ActivationOutputs& out);
  // Enqueues activations_bwd. The forward's inputs (the raw values) are all the backward needs.
  void bwd(const ActivationInputs& in, const ActivationGradients& grads, const ActivationRawGradients& out);

 private:
  ocl::Context* ctx_;
  ActivationOptions options_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
};

}  // namespace mipnerf::ops
