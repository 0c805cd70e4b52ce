// OpenEXR output of a render: linear RGB, depth and accumulated opacity as channels of one file.
//
// Channels (float32, ZIP-compressed, one scanline image):
//   "R", "G", "B"  linear RGB. The network's colours are sRGB-encoded like its training PNGs (io/color.hpp):
//                  convert with io::srgb_to_linear before writing. With a white or black background the
//                  background is already composited into them.
//   "Z"            depth: the expected ray distance t, in scene units. Ray directions have camera-frame
//                  z = −1, so t is the distance along the camera's optical axis (planar depth), which is
//                  what OpenEXR's standard depth channel "Z" and tools reading it (OIIO, Nuke, Blender) expect.
//   "acc"          accumulated opacity Σ weights in [0, 1]. Deliberately not "A": EXR readers take "A" as the
//                  alpha of premultiplied colour and composite with it, but R, G, B may already hold the
//                  background, so a compositor would add it twice. A custom name keeps the data without
//                  that promise.
// Z and acc are optional (written only when given). The header also records what each channel holds
// ("mipnerf:channels") and any string attributes given (e.g. step, checkpoint, camera).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace mipnerf::io {

inline constexpr const char* kExrDepthChannel = "Z";
inline constexpr const char* kExrAccChannel = "acc";

struct ExrImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<float> rgb;    // [height][width][3], linear RGB (required)
  std::vector<float> depth;  // [height][width], scene units along the optical axis; empty = no "Z" channel
  std::vector<float> acc;    // [height][width], accumulated opacity; empty = no "acc" channel
  std::map<std::string, std::string> attributes;  // string attributes for the header (names not starting
                                                  // with a standard attribute's name)
};

// Writes `image` to `path` atomically (io/atomic_file.hpp). Throws mipnerf::Error naming the file for
// sizes that do not match width × height, an empty image, or a failed write.
void write_exr(const std::string& path, const ExrImage& image);

// Reads an EXR written by write_exr (or any scanline or tiled EXR with R, G, B; half channels are converted
// to float; Z and acc read when present). String attributes come back in `attributes`, except
// "mipnerf:channels", which write_exr adds itself. Throws mipnerf::Error naming the file when it is missing,
// not an EXR, or lacks R, G or B.
ExrImage read_exr(const std::string& path);

}  // namespace mipnerf::io
