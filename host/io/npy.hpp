// NumPy .npy files of floating-point numbers (LLFF's poses_bounds.npy): a strict reader and a writer.
//
// Our own small reader rather than a library's: we need one kind of array (little-endian float32/float64, C order)
// and every malformed header must become one line naming the file, which a general reader's asserts and exceptions
// do not give; the whole format is a magic string, a version, a length and a Python dict literal.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace mipnerf::io {

struct NpyArray {
  std::vector<size_t> shape;   // e.g. {N, 17}
  std::vector<double> values;  // C order (last index fastest), converted to double
};

// Format versions 1.0, 2.0 and 3.0; dtype '<f8' or '<f4'; fortran_order False. Throws mipnerf::Error "<where>: ..."
// for anything else, a malformed header, or a data size that does not match the shape.
NpyArray parse_npy(std::string_view bytes, const std::string& where);
NpyArray read_npy(const std::string& path);

// Format 1.0, dtype '<f8', C order; written atomically.
std::string npy_bytes(const std::vector<double>& values, const std::vector<size_t>& shape);
void write_npy(const std::string& path, const std::vector<double>& values, const std::vector<size_t>& shape);

}  // namespace mipnerf::io
