// The training data's digest.
#include "data/fingerprint.hpp"

#include <cstdint>
#include <cstdio>
#include <cstring>

namespace mipnerf::data {
namespace {

// 64-bit FNV-1a, fed piece by piece.
class Fnv1a64 {
 public:
  void add_bytes(const void* data, size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
      hash_ ^= bytes[i];
      hash_ *= 0x100000001b3ULL;
    }
  }
  template <typename T>
  void add(const T& value) {
    add_bytes(&value, sizeof(value));
  }
  uint64_t value() const { return hash_; }

 private:
  uint64_t hash_ = 0xcbf29ce484222325ULL;
};

void add_camera(Fnv1a64& h, const Camera& c) {
  for (double v : c.camera_to_world) h.add(v);
  for (double v : {c.focal_x_px, c.focal_y_px, c.center_x_px, c.center_y_px, c.near, c.far, c.lossmult}) h.add(v);
  h.add(c.width_px);
  h.add(c.height_px);
  h.add(static_cast<int>(c.lens.model));
  for (double v : {c.lens.k1, c.lens.k2, c.lens.k3, c.lens.k4, c.lens.p1, c.lens.p2}) h.add(v);
}

}  // namespace

std::string fingerprint(const Split& split) {
  Fnv1a64 h;
  h.add(static_cast<uint64_t>(split.cameras.size()));
  for (size_t c = 0; c < split.cameras.size(); ++c) {
    add_camera(h, split.cameras[c]);
    h.add(split.scale_levels[c]);
  }
  h.add_bytes(split.rgb.data(), split.rgb.size() * sizeof(float));
  char text[32];
  std::snprintf(text, sizeof(text), "fnv1a64:%016llx", static_cast<unsigned long long>(h.value()));
  return text;
}

}  // namespace mipnerf::data
