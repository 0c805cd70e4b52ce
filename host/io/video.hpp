// H.264 MP4 video, written (and read back, for tests and checks) through Debian's FFmpeg libraries: libavformat for
// the MP4 container, libavcodec's libx264 encoder (constant quality, `crf`), libswscale for RGB ↔ YUV 4:2:0. The
// dependency is optional: a build without FFmpeg still builds, and every function here then throws an Error naming
// the packages to install (video_supported() says which build this is).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mipnerf::io {

// Whether this build can write and read videos (FFmpeg was found when it was configured).
bool video_supported();
// The Debian packages a build needs for video: "libavformat-dev libavcodec-dev libswscale-dev libavutil-dev".
extern const char* const kVideoPackages;

// The checks a caller can make before producing any frame; each throws a one-line mipnerf::Error naming `path`:
// - check_video_path: video support is built in, the name ends in .mp4 (any case) and is not a folder, and a file
//   can be written in its folder (created if missing; a probe file is created there and removed again).
// - check_video_settings: fps finite and in (0, 1000], crf an integer in 0..51 (libx264's range: 0 lossless, 18
//   visually lossless, 23 its default, 51 worst).
// - check_video_frame_size: width and height even and at least 2 (4:2:0 chroma covers 2×2 pixels; odd sizes are
//   refused, not padded, so the video shows exactly the frames rendered).
void check_video_path(const std::string& path);
void check_video_settings(const std::string& path, double fps, int crf);
void check_video_frame_size(const std::string& path, uint32_t width, uint32_t height);

// Writes an H.264 (libx264, yuv420p, limited range, tagged BT.709 primaries and matrix with the sRGB transfer) MP4
// with its index at the front (+faststart, so it plays while it downloads). The file is encoded under a temporary
// name beside `path` and renamed over it by finish() (io/atomic_file.hpp); a writer destroyed before finish()
// removes the temporary and leaves `path` as it was. Every failure is a mipnerf::Error naming `path` and libav's
// message (av_strerror, and the last error libav logged). libav's own log is silenced: the library never prints.
class VideoWriter {
 public:
  // Checks settings and size as above, opens the encoder and the temporary file.
  VideoWriter(std::string path, uint32_t width, uint32_t height, double fps, int crf);
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // rgb: [height][width][3] in [0, 1], sRGB-encoded as our PNGs are; quantised as the PNG writer does (clamped,
  // rounded to the nearest of 0..255, NaN → 0), then converted to YUV 4:2:0 and encoded.
  void add_frame(const float* rgb);
  // Flushes the encoder, writes the MP4 index and renames the temporary to `path`. At least one frame is needed.
  void finish();

  const std::string& path() const;
  size_t frames() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// A decoded video: every frame as RGB, [height][width][3] in [0, 1] (code / 255), in presentation order.
struct VideoFrames {
  uint32_t width = 0, height = 0;
  double fps = 0.0;          // the stream's average frame rate
  std::string codec;         // libavcodec's name of the stream's codec, e.g. "h264"
  std::string pixel_format;  // of the decoded frames, e.g. "yuv420p"
  std::vector<std::vector<float>> frames;
};
// Reads and decodes the first video stream of any file libavformat opens. Throws mipnerf::Error naming `path` and
// libav's message.
VideoFrames read_video_frames(const std::string& path);

}  // namespace mipnerf::io
