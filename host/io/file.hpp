// Whole-file reading and folder creation, with errors that name the file (atomic writing: io/atomic_file.hpp).
#pragma once

#include <string>
#include <vector>

namespace mipnerf::io {

// The bytes of `path`. Throws mipnerf::Error "<path>: no such file" (or "is a directory", "cannot read").
std::vector<unsigned char> read_file_bytes(const std::string& path);
// Its first `count` bytes (fewer when the file is shorter), with the same errors.
std::vector<unsigned char> read_file_prefix(const std::string& path, size_t count);
std::string read_file_text(const std::string& path);

// Creates `path` and its parents; throws naming the folder when that fails (e.g. a file is in the way).
void make_directories(const std::string& path);

}  // namespace mipnerf::io
