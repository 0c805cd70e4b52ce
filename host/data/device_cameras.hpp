// Cameras on the device: packed (core/camera.hpp's pack_cameras, [C][camera_layout::stride]) and, when any camera is
// behind a lens, the lens tables its rays read (data/lens_tables.hpp). The dataset upload and the image renderer each
// hold one; the graph's ray stage takes it whole and picks the lens variant by has_lens_tables().
#pragma once

#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "core/camera.hpp"

namespace mipnerf::data {

class DeviceCameras {
 public:
  // Uploads `cameras` (at least one) with their lens tables; `names[c]` names camera c in the lens errors (e.g. its
  // image file; may be empty), `label` the buffers ("train", "render"). Throws mipnerf::Error when a lens cannot be
  // inverted at some pixel (data/lens_tables.hpp).
  DeviceCameras(ocl::Context& ctx, const std::vector<Camera>& cameras, const std::vector<std::string>& names,
                const std::string& label);

  size_t size() const { return count_; }
  const ocl::DeviceArray<float>& packed() const { return packed_; }  // [C][camera_layout::stride]
  bool has_lens_tables() const { return has_lens_tables_; }
  // [pixels][4]; a one-element placeholder when no camera has a lens (has_lens_tables() is false).
  const ocl::DeviceArray<float>& lens_tables() const { return lens_tables_; }

  // Bytes of the packed cameras for `count` cameras (memory plans count them before any upload).
  static size_t packed_bytes(size_t count);

 private:
  size_t count_ = 0;
  ocl::DeviceArray<float> packed_;
  ocl::DeviceArray<float> lens_tables_;
  bool has_lens_tables_ = false;
};

}  // namespace mipnerf::data
