// Whole-file reading and atomic writing.
#include "io/file.hpp"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

#include <unistd.h>

#include "cl/error.hpp"

namespace mipnerf::io {
namespace fs = std::filesystem;

std::vector<unsigned char> read_file_bytes(const std::string& path) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) throw Error(path + ": no such file");
  if (fs::is_directory(status)) throw Error(path + ": is a directory, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open for reading (" + std::strerror(errno) + ")");
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(path + ": read error");
  return bytes;
}

std::string read_file_text(const std::string& path) {
  const auto bytes = read_file_bytes(path);
  return std::string(bytes.begin(), bytes.end());
}

void make_directories(const std::string& path) {
  if (path.empty()) return;
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec || !fs::is_directory(path)) {
    throw Error(path + ": cannot create folder (" + (ec ? ec.message() : std::string("a file is in the way")) + ")");
  }
}

void write_file_atomic(const std::string& path, const void* bytes, size_t size) {
  const fs::path target(path);
  if (target.has_parent_path()) make_directories(target.parent_path().string());
  // A name unique to this process and call, so concurrent writers never share a temporary.
  static std::atomic<unsigned> counter{0};
  const std::string temp = path + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  std::FILE* file = std::fopen(temp.c_str(), "wb");
  if (!file) throw Error(path + ": cannot write (" + std::strerror(errno) + ")");
  const bool written = size == 0 || std::fwrite(bytes, 1, size, file) == size;
  const int saved_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) {
    std::remove(temp.c_str());
    throw Error(path + ": write failed (" + std::strerror(written ? errno : saved_errno) + "); is the disk full?");
  }
  std::error_code ec;
  fs::rename(temp, target, ec);
  if (ec) {
    std::remove(temp.c_str());
    throw Error(path + ": cannot replace the file (" + ec.message() + ")");
  }
}

}  // namespace mipnerf::io
