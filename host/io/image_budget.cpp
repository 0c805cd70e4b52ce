// The decode budget of one image.
#include "io/image_budget.hpp"

#include <atomic>

#include "core/error.hpp"

namespace mipnerf::io {
namespace {

std::atomic<uint64_t>& budget() {
  static std::atomic<uint64_t> bytes{kDefaultImageBudgetBytes};
  return bytes;
}

std::string mib(uint64_t bytes) { return std::to_string((bytes + (uint64_t{1} << 20) - 1) >> 20); }

}  // namespace

uint64_t image_budget_bytes() { return budget().load(); }

void set_image_budget_bytes(uint64_t bytes) { budget().store(bytes); }

void check_image_budget(const std::string& name, uint64_t width, uint64_t height, uint64_t bytes_per_pixel,
                        const std::string& what) {
  // width, height < 2^32 each and bytes_per_pixel small: the product fits 64 bits unless it is absurd anyway.
  const uint64_t pixels = width * height;
  const uint64_t limit = image_budget_bytes();
  if (bytes_per_pixel != 0 && pixels > limit / bytes_per_pixel) {
    const uint64_t needed = pixels > UINT64_MAX / bytes_per_pixel ? UINT64_MAX : pixels * bytes_per_pixel;
    throw Error(name + ": a " + std::to_string(width) + "x" + std::to_string(height) + " image needs " + mib(needed) +
                " MiB to decode (" + what + "), more than the " + mib(limit) +
                " MiB one image may take: downsample it, or raise the limit with mipnerf-cl --max-image-mib");
  }
}

}  // namespace mipnerf::io
