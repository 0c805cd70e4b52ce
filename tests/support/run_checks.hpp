// What tests that run the real executable share: reading its outputs back, comparing tensors bit for bit, and the
// device the tests were told to use (MIPNERF_TEST_DEVICE) passed on to the executable.
#pragma once

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace mipnerf::test {

// The whole file (a child's log, a JSON output); "" when it cannot be read.
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Appends `--device D` when the tests run on a chosen device (MIPNERF_TEST_DEVICE), so the executable uses it too.
inline void add_test_device(std::vector<std::string>& argv) {
  if (const char* device = std::getenv("MIPNERF_TEST_DEVICE")) {
    argv.push_back("--device");
    argv.push_back(device);
  }
}

}  // namespace mipnerf::test
