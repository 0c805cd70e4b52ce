// CLBlast status names.
#include "gemm/clblast_check.hpp"

#include "cl/error.hpp"

namespace mipnerf::gemm {

std::string clblast_status_name(clblast::StatusCode status) {
  using S = clblast::StatusCode;
  switch (status) {
    case S::kNotImplemented: return "kNotImplemented";
    case S::kInvalidMatrixA: return "kInvalidMatrixA";
    case S::kInvalidMatrixB: return "kInvalidMatrixB";
    case S::kInvalidMatrixC: return "kInvalidMatrixC";
    case S::kInvalidVectorX: return "kInvalidVectorX";
    case S::kInvalidVectorY: return "kInvalidVectorY";
    case S::kInvalidDimension: return "kInvalidDimension";
    case S::kInvalidLeadDimA: return "kInvalidLeadDimA";
    case S::kInvalidLeadDimB: return "kInvalidLeadDimB";
    case S::kInvalidLeadDimC: return "kInvalidLeadDimC";
    case S::kInvalidIncrementX: return "kInvalidIncrementX";
    case S::kInvalidIncrementY: return "kInvalidIncrementY";
    case S::kInsufficientMemoryA: return "kInsufficientMemoryA";
    case S::kInsufficientMemoryB: return "kInsufficientMemoryB";
    case S::kInsufficientMemoryC: return "kInsufficientMemoryC";
    case S::kInsufficientMemoryX: return "kInsufficientMemoryX";
    case S::kInsufficientMemoryY: return "kInsufficientMemoryY";
    case S::kInsufficientMemoryTemp: return "kInsufficientMemoryTemp";
    case S::kInvalidBatchCount: return "kInvalidBatchCount";
    case S::kInvalidOverrideKernel: return "kInvalidOverrideKernel";
    case S::kMissingOverrideParameter: return "kMissingOverrideParameter";
    case S::kInvalidLocalMemUsage: return "kInvalidLocalMemUsage";
    case S::kNoHalfPrecision: return "kNoHalfPrecision";
    case S::kNoDoublePrecision: return "kNoDoublePrecision";
    case S::kInvalidVectorScalar: return "kInvalidVectorScalar";
    case S::kInsufficientMemoryScalar: return "kInsufficientMemoryScalar";
    case S::kDatabaseError: return "kDatabaseError";
    case S::kUnknownError: return "kUnknownError";
    case S::kUnexpectedError: return "kUnexpectedError";
    default:
      // The remaining CLBlast codes are the OpenCL codes themselves.
      return ocl::status_name(static_cast<cl_int>(status));
  }
}

void check_clblast(clblast::StatusCode status, const std::string& call) {
  if (status == clblast::StatusCode::kSuccess) return;
  throw Error(call + " failed with " + clblast_status_name(status), {}, static_cast<int>(status));
}

std::string clblast_version() {
  return std::to_string(CLBLAST_VERSION_MAJOR) + "." + std::to_string(CLBLAST_VERSION_MINOR) + "." +
         std::to_string(CLBLAST_VERSION_PATCH);
}

}  // namespace mipnerf::gemm
