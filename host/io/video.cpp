// H.264 MP4 writing and reading through libavformat, libavcodec (libx264) and libswscale.
#include "io/video.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

#ifdef MIPNERF_HAVE_FFMPEG
#include <mutex>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/imgutils.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}
#endif

namespace mipnerf::io {
namespace fs = std::filesystem;

const char* const kVideoPackages = "libavformat-dev libavcodec-dev libswscale-dev libavutil-dev";

namespace {

[[noreturn]] void throw_unsupported(const std::string& path) {
  throw Error(path + ": this mipnerf-cl was built without FFmpeg, which encodes videos: install the Debian packages " +
              kVideoPackages + ", then rebuild (scripts/build.sh)");
}

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

}  // namespace

bool video_supported() {
#ifdef MIPNERF_HAVE_FFMPEG
  return true;
#else
  return false;
#endif
}

void check_video_path(const std::string& path) {
  if (!video_supported()) throw_unsupported(path);
  const fs::path target(path);
  if (lowercase(target.extension().string()) != ".mp4") {
    throw Error(path + ": a video is written as H.264 in an MP4 file: give a file name ending in .mp4");
  }
  std::error_code ec;
  if (fs::is_directory(target, ec)) throw Error(path + ": is a folder; give a file name ending in .mp4");
  // A probe file where the encoder's temporary will be: the folder exists (or is made) and takes a new file.
  AtomicFile probe(path);
  std::FILE* file = std::fopen(probe.temporary_path().c_str(), "wb");
  if (file == nullptr) {
    const std::string folder = target.has_parent_path() ? target.parent_path().string() : std::string(".");
    throw Error(path + ": cannot write a file in its folder '" + folder + "' (" + std::strerror(errno) + ")");
  }
  std::fclose(file);
}  // the probe's destructor removes the file

void check_video_settings(const std::string& path, double fps, int crf) {
  if (!(std::isfinite(fps) && fps > 0.0 && fps <= 1000.0)) {
    char text[64];
    std::snprintf(text, sizeof(text), "%g", fps);
    throw Error(path + ": " + text + " frames per second: the frame rate must lie in (0, 1000]");
  }
  if (crf < 0 || crf > 51) {
    throw Error(path + ": CRF " + std::to_string(crf) +
                ": libx264's constant rate factor lies in 0..51 (0 lossless, 18 visually lossless, 23 its default)");
  }
}

void check_video_frame_size(const std::string& path, uint32_t width, uint32_t height) {
  if (width >= 2 && height >= 2 && width % 2 == 0 && height % 2 == 0) return;
  const uint32_t even_w = std::max(2u, width + width % 2), even_h = std::max(2u, height + height % 2);
  throw Error(path + ": frames of " + std::to_string(width) + "x" + std::to_string(height) +
              " pixels: H.264 video in 4:2:0 (yuv420p) needs an even width and height; render at an even size, e.g. " +
              std::to_string(even_w) + "x" + std::to_string(even_h));
}

#ifdef MIPNERF_HAVE_FFMPEG
namespace {

// libav logs through a process-wide callback: ours prints nothing (the library never prints) and keeps the last
// error-level line of this thread, which the next Error quotes beside av_strerror's text.
thread_local std::string t_logged_line;   // the line being assembled
thread_local std::string t_logged_error;  // the last complete error line

void capture_log(void* object, int level, const char* format, va_list arguments) {
  if (level > AV_LOG_ERROR) return;
  char text[1024];
  va_list copy;
  va_copy(copy, arguments);
  std::vsnprintf(text, sizeof(text), format, copy);
  va_end(copy);
  if (t_logged_line.empty() && object != nullptr) {
    const AVClass* cls = *static_cast<const AVClass* const*>(object);
    if (cls != nullptr && cls->item_name != nullptr) t_logged_line = std::string(cls->item_name(object)) + ": ";
  }
  t_logged_line += text;
  if (!t_logged_line.empty() && t_logged_line.back() == '\n') {
    t_logged_line.pop_back();
    t_logged_error = t_logged_line;
    t_logged_line.clear();
  }
}

void quiet_libav() {
  static std::once_flag once;
  std::call_once(once, [] { av_log_set_callback(capture_log); });
  t_logged_line.clear();
  t_logged_error.clear();
}

std::string av_text(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  if (av_strerror(code, text, sizeof(text)) < 0) std::snprintf(text, sizeof(text), "libav error %d", code);
  return text;
}

// "PATH: WHAT failed: libav's message (the last line libav logged)".
[[noreturn]] void fail(const std::string& path, const std::string& what, int code) {
  std::string message = path + ": " + what + " failed: " + av_text(code);
  if (!t_logged_error.empty()) message += " (" + t_logged_error + ")";
  throw Error(message, {}, code);
}

void check(int code, const std::string& path, const std::string& what) {
  if (code < 0) fail(path, what, code);
}

// libswscale's coefficient table for a stream's matrix.
int sws_colorspace(AVColorSpace space) {
  switch (space) {
    case AVCOL_SPC_BT709:
      return SWS_CS_ITU709;
    case AVCOL_SPC_FCC:
      return SWS_CS_FCC;
    case AVCOL_SPC_SMPTE240M:
      return SWS_CS_SMPTE240M;
    case AVCOL_SPC_BT2020_NCL:
    case AVCOL_SPC_BT2020_CL:
      return SWS_CS_BT2020;
    default:
      return SWS_CS_DEFAULT;  // BT.601, what decoders assume of untagged video
  }
}

// SWS_ACCURATE_RND: exact rounding instead of the fast paths' approximations; SWS_FULL_CHR_H_INP/INT: the chroma is
// filtered at full horizontal resolution (RGB → YUV) and interpolated back (YUV → RGB) instead of taken from one
// pixel of each pair; bicubic for the 4:2:0 chroma's down- and upsampling.
constexpr int kScaleFlags = SWS_BICUBIC | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INP | SWS_FULL_CHR_H_INT;

}  // namespace

struct VideoWriter::State {
  std::string path;
  AtomicFile file;  // declared before the libav objects: destroyed after them, removing an unfinished temporary
  uint32_t width = 0, height = 0;
  AVFormatContext* format = nullptr;
  AVCodecContext* encoder = nullptr;
  AVStream* stream = nullptr;
  SwsContext* scaler = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  std::vector<uint8_t> rgb8;  // [height][width][3], the frame as the PNG writer quantises it
  int64_t frames = 0;
  bool finished = false;

  explicit State(std::string destination) : path(destination), file(std::move(destination)) {}
  ~State() {
    av_packet_free(&packet);
    av_frame_free(&frame);
    sws_freeContext(scaler);
    avcodec_free_context(&encoder);
    if (format != nullptr) {
      if (format->pb != nullptr) avio_closep(&format->pb);
      avformat_free_context(format);
    }
  }

  // Sends `next` (nullptr: the end) to the encoder and writes every packet it has ready.
  void encode(const AVFrame* next) {
    check(avcodec_send_frame(encoder, next), path, "encoding a frame with libx264");
    for (;;) {
      const int received = avcodec_receive_packet(encoder, packet);
      if (received == AVERROR(EAGAIN) || received == AVERROR_EOF) return;
      check(received, path, "encoding a frame with libx264");
      av_packet_rescale_ts(packet, encoder->time_base, stream->time_base);
      packet->stream_index = stream->index;
      const int written = av_interleaved_write_frame(format, packet);  // leaves the packet blank
      av_packet_unref(packet);
      check(written, path, "writing to the MP4 file");
    }
  }
};

VideoWriter::VideoWriter(std::string path, uint32_t width, uint32_t height, double fps, int crf) {
  check_video_settings(path, fps, crf);
  check_video_frame_size(path, width, height);
  quiet_libav();
  state_ = std::make_unique<State>(std::move(path));
  State& s = *state_;
  s.width = width;
  s.height = height;
  const std::string& p = s.path;
  const AVCodec* codec = avcodec_find_encoder_by_name("libx264");
  if (codec == nullptr) {
    throw Error(p +
                ": this FFmpeg has no libx264 encoder (Debian's libavcodec has it: install 'libavcodec-dev' "
                "from Debian's archive)");
  }
  // The MP4 muxer by name: the temporary's name ends in .tmp.
  check(avformat_alloc_output_context2(&s.format, nullptr, "mp4", s.file.temporary_path().c_str()), p,
        "opening the MP4 muxer");
  s.encoder = avcodec_alloc_context3(codec);
  if (s.encoder == nullptr) fail(p, "allocating the libx264 encoder", AVERROR(ENOMEM));
  const AVRational rate = av_d2q(fps, 1001000);  // 30 → 30/1, 29.97002997 → 30000/1001
  s.encoder->width = static_cast<int>(width);
  s.encoder->height = static_cast<int>(height);
  s.encoder->pix_fmt = AV_PIX_FMT_YUV420P;
  s.encoder->framerate = rate;
  s.encoder->time_base = av_inv_q(rate);
  s.encoder->sample_aspect_ratio = AVRational{1, 1};
  // What the pixels are: limited-range BT.709 YCbCr of sRGB-encoded BT.709 primaries (sRGB's own primaries).
  s.encoder->color_range = AVCOL_RANGE_MPEG;
  s.encoder->colorspace = AVCOL_SPC_BT709;
  s.encoder->color_primaries = AVCOL_PRI_BT709;
  s.encoder->color_trc = AVCOL_TRC_IEC61966_2_1;
  if (s.format->oformat->flags & AVFMT_GLOBALHEADER) s.encoder->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  check(av_opt_set(s.encoder->priv_data, "crf", std::to_string(crf).c_str(), 0), p, "setting libx264's crf");
  check(av_opt_set(s.encoder->priv_data, "preset", "medium", 0), p, "setting libx264's preset");
  check(avcodec_open2(s.encoder, codec, nullptr), p, "opening the libx264 encoder");

  s.stream = avformat_new_stream(s.format, nullptr);
  if (s.stream == nullptr) fail(p, "adding the video stream", AVERROR(ENOMEM));
  check(avcodec_parameters_from_context(s.stream->codecpar, s.encoder), p, "describing the video stream");
  s.stream->time_base = s.encoder->time_base;
  s.stream->avg_frame_rate = rate;
  check(avio_open(&s.format->pb, s.file.temporary_path().c_str(), AVIO_FLAG_WRITE), p,
        "creating the temporary '" + s.file.temporary_path() + "'");
  AVDictionary* options = nullptr;
  av_dict_set(&options, "movflags", "+faststart", 0);  // the index before the frames: plays while downloading
  const int header = avformat_write_header(s.format, &options);
  av_dict_free(&options);
  check(header, p, "writing the MP4 header");

  s.scaler = sws_getContext(s.encoder->width, s.encoder->height, AV_PIX_FMT_RGB24, s.encoder->width, s.encoder->height,
                            AV_PIX_FMT_YUV420P, kScaleFlags, nullptr, nullptr, nullptr);
  if (s.scaler == nullptr) fail(p, "setting up the RGB to YUV 4:2:0 conversion", AVERROR(EINVAL));
  // Source: full-range RGB; destination: BT.709 limited range, as tagged above.
  check(sws_setColorspaceDetails(s.scaler, sws_getCoefficients(SWS_CS_DEFAULT), 1, sws_getCoefficients(SWS_CS_ITU709),
                                 0, 0, 1 << 16, 1 << 16),
        p, "setting the BT.709 conversion");
  s.frame = av_frame_alloc();
  s.packet = av_packet_alloc();
  if (s.frame == nullptr || s.packet == nullptr) fail(p, "allocating a frame", AVERROR(ENOMEM));
  s.frame->format = AV_PIX_FMT_YUV420P;
  s.frame->width = s.encoder->width;
  s.frame->height = s.encoder->height;
  s.frame->color_range = s.encoder->color_range;
  s.frame->colorspace = s.encoder->colorspace;
  s.frame->color_primaries = s.encoder->color_primaries;
  s.frame->color_trc = s.encoder->color_trc;
  check(av_frame_get_buffer(s.frame, 0), p, "allocating a frame");
  s.rgb8.resize(static_cast<size_t>(width) * height * 3);
}

VideoWriter::~VideoWriter() = default;

void VideoWriter::add_frame(const float* rgb) {
  State& s = *state_;
  if (s.finished) throw Error(s.path + ": a frame added after the video was finished");
  t_logged_error.clear();
  // As io::write_png quantises: NaN → 0, clamped to [0, 1], rounded to the nearest code.
  for (size_t i = 0; i < s.rgb8.size(); ++i) {
    const double unit = std::isnan(rgb[i]) ? 0.0 : std::clamp(static_cast<double>(rgb[i]), 0.0, 1.0);
    s.rgb8[i] = static_cast<uint8_t>(std::lround(unit * 255.0));
  }
  // The encoder may still hold a reference to the previous frame's buffers: copy-on-write.
  check(av_frame_make_writable(s.frame), s.path, "preparing a frame");
  const uint8_t* source[1] = {s.rgb8.data()};
  const int stride[1] = {static_cast<int>(s.width * 3)};
  const int rows = sws_scale(s.scaler, source, stride, 0, static_cast<int>(s.height), s.frame->data, s.frame->linesize);
  if (rows != static_cast<int>(s.height)) fail(s.path, "converting a frame to YUV 4:2:0", rows < 0 ? rows : -1);
  s.frame->pts = s.frames;
  s.encode(s.frame);
  ++s.frames;
}

void VideoWriter::finish() {
  State& s = *state_;
  if (s.finished) throw Error(s.path + ": the video was already finished");
  if (s.frames == 0) throw Error(s.path + ": a video needs at least one frame");
  t_logged_error.clear();
  s.encode(nullptr);
  check(av_write_trailer(s.format), s.path, "writing the MP4 index");
  check(avio_closep(&s.format->pb), s.path, "closing the temporary '" + s.file.temporary_path() + "'");
  s.file.commit();
  s.finished = true;
}

const std::string& VideoWriter::path() const { return state_->path; }
size_t VideoWriter::frames() const { return static_cast<size_t>(state_->frames); }

namespace {

// The objects of one read, freed whatever happens.
struct Reading {
  AVFormatContext* format = nullptr;
  AVCodecContext* decoder = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* scaler = nullptr;
  ~Reading() {
    sws_freeContext(scaler);
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&decoder);
    avformat_close_input(&format);
  }
};

// Converts the decoded frame to RGB (as its tags say: matrix and range) and appends it to `video`.
void append_rgb(const std::string& path, Reading& r, VideoFrames& video) {
  const AVFrame& f = *r.frame;
  r.scaler = sws_getCachedContext(r.scaler, f.width, f.height, static_cast<AVPixelFormat>(f.format), f.width, f.height,
                                  AV_PIX_FMT_RGB24, kScaleFlags, nullptr, nullptr, nullptr);
  if (r.scaler == nullptr) fail(path, "setting up the conversion to RGB", AVERROR(EINVAL));
  check(sws_setColorspaceDetails(r.scaler, sws_getCoefficients(sws_colorspace(f.colorspace)),
                                 f.color_range == AVCOL_RANGE_JPEG ? 1 : 0, sws_getCoefficients(SWS_CS_DEFAULT), 1, 0,
                                 1 << 16, 1 << 16),
        path, "setting the conversion to RGB");
  std::vector<uint8_t> rgb8(static_cast<size_t>(f.width) * f.height * 3);
  uint8_t* destination[1] = {rgb8.data()};
  const int stride[1] = {f.width * 3};
  const int rows = sws_scale(r.scaler, f.data, f.linesize, 0, f.height, destination, stride);
  if (rows != f.height) fail(path, "converting a frame to RGB", rows < 0 ? rows : -1);
  std::vector<float> rgb(rgb8.size());
  for (size_t i = 0; i < rgb8.size(); ++i) rgb[i] = static_cast<float>(rgb8[i]) / 255.0f;
  if (video.pixel_format.empty()) {
    const char* name = av_get_pix_fmt_name(static_cast<AVPixelFormat>(f.format));
    video.pixel_format = name != nullptr ? name : "unknown";
  }
  video.frames.push_back(std::move(rgb));
}

// Sends `packet` (nullptr: the end) to the decoder and converts every frame it returns.
void decode(const std::string& path, Reading& r, const AVPacket* packet, VideoFrames& video) {
  check(avcodec_send_packet(r.decoder, packet), path, "decoding");
  for (;;) {
    const int received = avcodec_receive_frame(r.decoder, r.frame);
    if (received == AVERROR(EAGAIN) || received == AVERROR_EOF) return;
    check(received, path, "decoding");
    append_rgb(path, r, video);
    av_frame_unref(r.frame);
  }
}

}  // namespace

VideoFrames read_video_frames(const std::string& path) {
  quiet_libav();
  Reading r;
  check(avformat_open_input(&r.format, path.c_str(), nullptr, nullptr), path, "opening the video");
  check(avformat_find_stream_info(r.format, nullptr), path, "reading the video's streams");
  const AVCodec* codec = nullptr;
  const int index = av_find_best_stream(r.format, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
  check(index, path, "finding a video stream");
  const AVStream* stream = r.format->streams[index];
  r.decoder = avcodec_alloc_context3(codec);
  if (r.decoder == nullptr) fail(path, "allocating the decoder", AVERROR(ENOMEM));
  check(avcodec_parameters_to_context(r.decoder, stream->codecpar), path, "setting up the decoder");
  check(avcodec_open2(r.decoder, codec, nullptr), path, "opening the decoder");
  r.frame = av_frame_alloc();
  r.packet = av_packet_alloc();
  if (r.frame == nullptr || r.packet == nullptr) fail(path, "allocating a frame", AVERROR(ENOMEM));

  VideoFrames video;
  video.width = static_cast<uint32_t>(stream->codecpar->width);
  video.height = static_cast<uint32_t>(stream->codecpar->height);
  video.fps = stream->avg_frame_rate.den != 0 ? av_q2d(stream->avg_frame_rate) : 0.0;
  video.codec = avcodec_get_name(stream->codecpar->codec_id);
  for (;;) {
    const int read = av_read_frame(r.format, r.packet);
    if (read == AVERROR_EOF) break;
    check(read, path, "reading the video");
    if (r.packet->stream_index == index) {
      try {
        decode(path, r, r.packet, video);
      } catch (...) {
        av_packet_unref(r.packet);
        throw;
      }
    }
    av_packet_unref(r.packet);
  }
  decode(path, r, nullptr, video);
  return video;
}

#else  // without FFmpeg: every entry point says what to install

struct VideoWriter::State {
  std::string path;
};

VideoWriter::VideoWriter(std::string path, uint32_t, uint32_t, double, int) { throw_unsupported(path); }
VideoWriter::~VideoWriter() = default;
void VideoWriter::add_frame(const float*) { throw_unsupported(state_->path); }
void VideoWriter::finish() { throw_unsupported(state_->path); }
const std::string& VideoWriter::path() const { return state_->path; }
size_t VideoWriter::frames() const { return 0; }
VideoFrames read_video_frames(const std::string& path) { throw_unsupported(path); }

#endif  // MIPNERF_HAVE_FFMPEG

}  // namespace mipnerf::io
