// JPEG files for tests: the library's encoder (io::write_jpeg) with the signature the tests use.
#pragma once

#include <string>
#include <vector>

#include "io/jpeg.hpp"

namespace mipnerf::test {

// Writes rgb [height][width][3] in [0, 1] as a baseline JPEG of `quality` (1..100).
inline void write_jpeg(const std::string& path, unsigned width, unsigned height, const std::vector<float>& rgb,
                       int quality = 95) {
  io::write_jpeg(path, width, height, rgb.data(), quality);
}

}  // namespace mipnerf::test
