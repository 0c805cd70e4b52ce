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

// How the element-wise kernels give out work-items (ACTIVATION_ITEMS of activations.cl): one per value (the 3·rows
// colour values' items in whole work-groups, then one per density), one per row (its density and 3 colour values),
// or one per vector of 16 consecutive values (colour vectors, then density vectors, split by work-group as per
// value). Measured on 524,288 rows: PoCL's vectoriser handles per value and not per row (6.2 against 17 ms on the
// AMD EPYC), and runs per vector faster still (bench/results/kernel_runtimes/kernel_runtimes_xeon.md); Intel's CPU runtime is 4x
// faster per row than per value (2.0 against 8 ms); GPUs read consecutive floats with consecutive items per value.
enum class ActivationItems { device_default, per_value, per_row, per_vector };

class Activations {
 public:
  // device_default: per vector on PoCL's CPU device, per row on other CPU runtimes, per value elsewhere.
  Activations(ocl::Context& ctx, const ActivationOptions& options,
              ActivationItems items = ActivationItems::device_default);
  const ActivationOptions& options() const { return options_; }

  // Enqueues activations_fwd.
  void fwd(const ActivationInputs& in, const ActivationOutputs& out);
  // Enqueues activations_bwd. The forward's inputs (the raw values) are all the backward needs.
  void bwd(const ActivationInputs& in, const ActivationGradients& grads, const ActivationRawGradients& out);

 private:
  // Launches `kernel` with the items ACTIVATION_ITEMS asks for.
  void launch(::cl::Kernel& kernel, size_t n_rows, const std::string& where);

  ocl::Context* ctx_;
  ActivationOptions options_;
  ActivationItems items_;  // never device_default
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
};

}  // namespace mipnerf::ops
