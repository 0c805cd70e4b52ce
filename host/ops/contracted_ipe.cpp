// Host wrapper of kernels/contracted_ipe.cl.
#include "ops/contracted_ipe.hpp"

#include <string>
#include <vector>

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "core/geodesic_basis.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {
namespace {

void check_degrees(const EncodingOptions& encoding, const std::string& where) {
  if (encoding.min_deg < 0 || encoding.max_deg > 60 || encoding.max_deg <= encoding.min_deg) {
    throw Error(where + ": degrees [" + std::to_string(encoding.min_deg) + ", " + std::to_string(encoding.max_deg) +
                ") are not a valid range (0 ≤ min_deg < max_deg ≤ 60; mip-NeRF 360: 0, 12)");
  }
}

// The kernel reads the basis 8 directions at a time (CONTRACTED_IPE_LANES).
constexpr size_t kLanes = 8;

}  // namespace

size_t contracted_ipe_width(const EncodingOptions& encoding, int tessellation) {
  return 2 * static_cast<size_t>(encoding.degrees()) * icosahedron_basis(tessellation).size();
}

ContractedIpe::ContractedIpe(ocl::Context& ctx, const GaussianOptions& options, int tessellation, int sincos_every)
    : ctx_(&ctx),
      sincos_every_(sincos_every > 0                                           ? sincos_every
                    : (ctx.device_info().type & CL_DEVICE_TYPE_CPU) != 0 ? 4
                                                                             : 1) {
  if (sincos_every_ > 8) {
    throw Error("ContractedIpe: sincos_every = " + std::to_string(sincos_every_) + " is not 1 to 8 (degrees per sincos)");
  }
  std::vector<float> basis = icosahedron_basis_floats(tessellation);
  n_basis_ = basis.size() / 3;
  basis.resize(3 * ((n_basis_ + kLanes - 1) / kLanes * kLanes), 0.0f);  // zero rows to a multiple of the lanes
  basis_ = ocl::DeviceArray<float>(ctx, basis.size(), "contracted IPE basis [K][3]");
  basis_.upload(ctx, basis);
  auto& program = ctx.program({"common.cl", "gaussian.cl", "encode.cl", "contract.cl", "contracted_ipe.cl"},
                              gaussian_build_options(options).define("CONTRACTED_IPE_SINCOS_EVERY", sincos_every_));
  fwd_ = &program.kernel("contracted_ipe_fwd");
}

size_t ContractedIpe::width(const EncodingOptions& encoding) const {
  return 2 * static_cast<size_t>(encoding.degrees()) * n_basis_;
}

void ContractedIpe::fwd(const EncodingOptions& encoding, const GaussianInputs& in, ocl::DeviceArray<float>& features) {
  const std::string where = "contracted_ipe_fwd";
  check_degrees(encoding, where);
  detail::require(in.rays.origins, 3 * in.n_rays, where);
  detail::require(in.rays.directions, 3 * in.n_rays, where);
  detail::require(in.rays.radii, in.n_rays, where);
  detail::require(in.t_edges, in.n_rays * (in.n_samples + 1), where);
  const size_t rows = in.n_rays * in.n_samples;
  detail::require(features, rows * width(encoding), where);
  if (rows == 0) return;
  ocl::set_args(*fwd_, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, basis_, features,
                detail::to_uint(in.n_rays, where, "rays"), detail::to_uint(in.n_samples, where, "samples"),
                static_cast<cl_uint>(n_basis_), static_cast<cl_int>(encoding.min_deg),
                static_cast<cl_int>(encoding.max_deg));
  ocl::launch_1d(*ctx_, *fwd_, rows, where);
}

}  // namespace mipnerf::ops
