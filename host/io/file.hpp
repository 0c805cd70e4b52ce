// Whole-file reading and atomic writing, with errors that name the file.
#pragma once

#include <string>
#include <vector>

namespace mipnerf::io {

// The bytes of `path`. Throws mipnerf::Error "<path>: no such file" (or "is a directory", "cannot read").
std::vector<unsigned char> read_file_bytes(const std::string& path);
std::string read_file_text(const std::string& path);

// Writes `bytes` to `path` atomically: first to a temporary file beside it, then renamed over it, so an
// interrupted run never leaves a half-written file under the final name. Creates missing parent folders.
void write_file_atomic(const std::string& path, const void* bytes, size_t size);
inline void write_file_atomic(const std::string& path, const std::string& text) {
  write_file_atomic(path, text.data(), text.size());
}

// Creates `path` and its parents; throws naming the folder when that fails (e.g. a file is in the way).
void make_directories(const std::string& path);

}  // namespace mipnerf::io
