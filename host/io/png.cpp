// PNG through libpng. libpng reports errors by longjmp to a setjmp point. To keep that safe in C++, every
// libpng call happens inside small functions that own no object with a destructor (decode_header,
// decode_rows, encode_rows): a longjmp back into them skips only libpng's own C frames. Buffers are
// created by the callers (outside those functions), and the png structs are released by a guard object
// that lives in the caller's frame, which a longjmp never crosses.
#include "io/png.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/image_budget.hpp"
#include "io/file.hpp"

namespace mipnerf::io {
namespace {

// Shared by the libpng callbacks: input bytes (reading) or output bytes (writing), and the error text.
struct PngIo {
  const unsigned char* input = nullptr;
  size_t input_size = 0;
  size_t input_pos = 0;
  std::vector<unsigned char>* output = nullptr;
  bool output_failed = false;
  char message[256] = {0};
};

void on_png_error(png_structp png, png_const_charp message) {
  auto* io = static_cast<PngIo*>(png_get_error_ptr(png));
  std::snprintf(io->message, sizeof(io->message), "%s", message ? message : "unknown libpng error");
  png_longjmp(png, 1);
}

// Warnings (e.g. an odd sRGB profile in a Blender render) do not affect the pixels: ignore them.
void on_png_warning(png_structp, png_const_charp) {}

void on_png_read(png_structp png, png_bytep out, size_t count) {
  auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
  if (count > io->input_size - io->input_pos) png_error(png, "the file is truncated");
  std::memcpy(out, io->input + io->input_pos, count);
  io->input_pos += count;
}

void on_png_write(png_structp png, png_bytep data, size_t count) {
  auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
  // No exception may cross libpng's frames: a failed append becomes a libpng error.
  try {
    io->output->insert(io->output->end(), data, data + count);
  } catch (...) {
    io->output_failed = true;
  }
  if (io->output_failed) png_error(png, "out of memory while encoding");
}

void on_png_flush(png_structp) {}

struct ReadGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~ReadGuard() {
    if (png) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
  }
};

struct WriteGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~WriteGuard() {
    if (png) png_destroy_write_struct(&png, info ? &info : nullptr);
  }
};

struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0;
  bool has_alpha = false;
  size_t row_bytes = 0;
  uint64_t stored_bytes = 0;  // the pixels as the file stores them, before expansion (without filter bytes)
};

// The ancillary chunks we never use (colour management, text, metadata; the pixels are taken as stored). libpng
// would read each into a buffer of the length its chunk header declares, up to 2 GiB from 12 bytes of input,
// before checking anything: they are skipped unread instead. Entries of 5 bytes: 4 letters and a NUL.
constexpr png_byte kSkippedChunks[] =
    "bKGD\0cHRM\0eXIf\0gAMA\0hIST\0iCCP\0iTXt\0oFFs\0pCAL\0pHYs\0sBIT\0sCAL\0sPLT\0sRGB\0sTER\0tEXt\0tIME\0zTXt";
constexpr int kSkippedChunkCount = sizeof(kSkippedChunks) / 5;
// What a chunk we do read (PLTE, tRNS) may allocate: both hold at most 256 entries.
constexpr png_alloc_size_t kChunkMallocMax = 1 << 16;

// Reads the header and sets the transformations that give 8- or 16-bit RGBA. False on a libpng error.
bool decode_header(png_structp png, png_infop info, PngHeader* header) {
  if (setjmp(png_jmpbuf(png))) return false;
  // Large but sane limits: a corrupt header must not make us allocate gigabytes.
  png_set_user_limits(png, 1u << 15, 1u << 15);
  png_set_chunk_malloc_max(png, kChunkMallocMax);
  png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, nullptr, 0);  // unknown chunks: skipped
  png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, kSkippedChunks, kSkippedChunkCount);
  png_read_info(png, info);
  const int color_type = png_get_color_type(png, info);
  const uint64_t bits_per_row = static_cast<uint64_t>(png_get_image_width(png, info)) *
                                png_get_channels(png, info) * png_get_bit_depth(png, info);
  header->stored_bytes = png_get_image_height(png, info) * ((bits_per_row + 7) / 8);
  header->bit_depth = png_get_bit_depth(png, info) == 16 ? 16 : 8;
  header->has_alpha = (color_type & PNG_COLOR_MASK_ALPHA) != 0 || png_get_valid(png, info, PNG_INFO_tRNS) != 0;
  png_set_expand(png);  // palette → RGB, grey < 8 bit → 8 bit, tRNS → alpha
  if (!(color_type & PNG_COLOR_MASK_COLOR)) png_set_gray_to_rgb(png);
  if (!header->has_alpha) png_set_add_alpha(png, header->bit_depth == 16 ? 0xFFFF : 0xFF, PNG_FILLER_AFTER);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  header->width = png_get_image_width(png, info);
  header->height = png_get_image_height(png, info);
  header->row_bytes = png_get_rowbytes(png, info);
  return true;
}

bool decode_rows(png_structp png, png_infop info, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  png_read_end(png, nullptr);
  return true;
}

bool encode_rows(png_structp png, png_infop info, png_uint_32 width, png_uint_32 height, int bit_depth,
                 int channels, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, width, height, bit_depth, channels == 4 ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  return true;
}

Error unreadable(const std::string& name, const std::string& why) {
  return Error(name + ": unreadable PNG (" + why + "); re-export it as an 8- or 16-bit PNG");
}

std::vector<unsigned char> encode(uint32_t width, uint32_t height, int channels, int bit_depth,
                                  const unsigned char* big_endian_samples) {
  if (channels != 3 && channels != 4) throw Error("PNG writer: channels must be 3 or 4, got " + std::to_string(channels));
  if (width == 0 || height == 0) throw Error("PNG writer: empty image");
  std::vector<unsigned char> out;
  PngIo io;
  io.output = &out;
  WriteGuard guard;
  guard.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &io, on_png_error, on_png_warning);
  if (guard.png) guard.info = png_create_info_struct(guard.png);
  if (!guard.png || !guard.info) throw Error("PNG writer: libpng could not allocate its state");
  png_set_write_fn(guard.png, &io, on_png_write, on_png_flush);
  const size_t row_bytes = static_cast<size_t>(width) * channels * (bit_depth / 8);
  std::vector<png_bytep> rows(height);
  for (uint32_t y = 0; y < height; ++y) rows[y] = const_cast<png_bytep>(big_endian_samples + y * row_bytes);
  if (!encode_rows(guard.png, guard.info, width, height, bit_depth, channels, rows.data())) {
    throw Error(std::string("PNG writer: ") + io.message);
  }
  return out;
}

}  // namespace

PngImage decode_png(const unsigned char* bytes, size_t size, const std::string& name) {
  if (size < 8 || png_sig_cmp(bytes, 0, 8) != 0) throw unreadable(name, "not a PNG file: the signature is missing");
  PngIo io;
  io.input = bytes;
  io.input_size = size;
  ReadGuard guard;
  guard.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, on_png_error, on_png_warning);
  if (guard.png) guard.info = png_create_info_struct(guard.png);
  if (!guard.png || !guard.info) throw unreadable(name, "libpng could not allocate its state");
  png_set_read_fn(guard.png, &io, on_png_read);

  PngHeader header;
  if (!decode_header(guard.png, guard.info, &header)) throw unreadable(name, io.message);
  // Deflate expands at most 1032:1 (zlib's FAQ), so a header whose pixels could not fit in the whole file compressed
  // belongs to a truncated or corrupt file: refused before allocating for them (up to 8 GiB at 32768x32768).
  if (header.stored_bytes > 1032 * static_cast<uint64_t>(size) + 1024) {
    throw unreadable(name, "the header's " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                               " pixels cannot be stored in " + std::to_string(size) +
                               " bytes: the file is truncated or corrupt");
  }
  const size_t bytes_per_sample = header.bit_depth / 8;
  if (header.row_bytes != static_cast<size_t>(header.width) * 4 * bytes_per_sample) {
    throw unreadable(name, "unexpected row size after expansion to RGBA");
  }
  // What the decode allocates below, whatever the file's size: the samples expanded to 8- or 16-bit RGBA, and their
  // float copy. A valid file can describe a huge image in a few KB (a 1-bit image of one colour).
  check_image_budget(name, header.width, header.height, 4 * bytes_per_sample + 4 * sizeof(float),
                     bytes_per_sample == 2 ? "16-bit RGBA and float RGBA" : "8-bit RGBA and float RGBA");
  std::vector<unsigned char> raw(header.row_bytes * header.height);
  std::vector<png_bytep> rows(header.height);
  for (png_uint_32 y = 0; y < header.height; ++y) rows[y] = raw.data() + y * header.row_bytes;
  if (!decode_rows(guard.png, guard.info, rows.data())) throw unreadable(name, io.message);

  PngImage image;
  image.width = header.width;
  image.height = header.height;
  image.bit_depth = header.bit_depth;
  image.has_alpha = header.has_alpha;
  const size_t samples = static_cast<size_t>(header.width) * header.height * 4;
  image.rgba.resize(samples);
  if (header.bit_depth == 16) {
    for (size_t i = 0; i < samples; ++i) {
      image.rgba[i] = static_cast<float>((raw[2 * i] << 8) | raw[2 * i + 1]) / 65535.0f;  // PNG is big-endian
    }
  } else {
    for (size_t i = 0; i < samples; ++i) image.rgba[i] = static_cast<float>(raw[i]) / 255.0f;
  }
  return image;
}

PngSize read_png_size(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": no such file");
  unsigned char head[24] = {0};
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(head), sizeof(head));
  if (in.gcount() < 8 || png_sig_cmp(head, 0, 8) != 0)
    throw unreadable(path, "not a PNG file: the signature is missing");
  // After the signature: the IHDR chunk's length (13) and type, then width and height, big-endian.
  if (in.gcount() < 24 || std::memcmp(head + 12, "IHDR", 4) != 0) throw unreadable(path, "no IHDR chunk first");
  auto big_endian = [&head](int at) {
    return (uint32_t{head[at]} << 24) | (uint32_t{head[at + 1]} << 16) | (uint32_t{head[at + 2]} << 8) | head[at + 3];
  };
  return {big_endian(16), big_endian(20)};
}

PngImage read_png(const std::string& path) {
  const auto bytes = read_file_bytes(path);
  return decode_png(bytes.data(), bytes.size(), path);
}

std::vector<unsigned char> encode_png8(uint32_t width, uint32_t height, int channels, const uint8_t* samples) {
  return encode(width, height, channels, 8, samples);
}

std::vector<unsigned char> encode_png16(uint32_t width, uint32_t height, int channels, const uint16_t* samples) {
  const size_t count = static_cast<size_t>(width) * height * channels;
  std::vector<unsigned char> big_endian(2 * count);
  for (size_t i = 0; i < count; ++i) {
    big_endian[2 * i] = static_cast<unsigned char>(samples[i] >> 8);
    big_endian[2 * i + 1] = static_cast<unsigned char>(samples[i] & 0xFF);
  }
  return encode(width, height, channels, 16, big_endian.data());
}

void write_png8(const std::string& path, uint32_t width, uint32_t height, int channels, const uint8_t* samples) {
  const auto bytes = encode_png8(width, height, channels, samples);
  write_bytes_atomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

void write_png16(const std::string& path, uint32_t width, uint32_t height, int channels, const uint16_t* samples) {
  const auto bytes = encode_png16(width, height, channels, samples);
  write_bytes_atomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

std::vector<uint8_t> quantize_8bit(const float* samples, size_t count) {
  std::vector<uint8_t> out(count);
  for (size_t i = 0; i < count; ++i) {
    // NaN becomes 0 (std::clamp would pass it through and the cast would be undefined).
    const double unit = std::isnan(samples[i]) ? 0.0 : std::clamp(static_cast<double>(samples[i]), 0.0, 1.0);
    out[i] = static_cast<uint8_t>(std::lround(unit * 255.0));
  }
  return out;
}

void write_png(const std::string& path, uint32_t width, uint32_t height, int channels, const float* samples,
               int bit_depth) {
  if (bit_depth != 8 && bit_depth != 16) throw Error(path + ": PNG bit depth must be 8 or 16");
  const size_t count = static_cast<size_t>(width) * height * channels;
  const double max_value = bit_depth == 16 ? 65535.0 : 255.0;
  // NaN becomes 0 (std::clamp would pass it through and the cast would be undefined).
  auto quantize = [max_value](float v) {
    const double unit = std::isnan(v) ? 0.0 : std::clamp(static_cast<double>(v), 0.0, 1.0);
    return std::lround(unit * max_value);
  };
  if (bit_depth == 8) {
    write_png8(path, width, height, channels, quantize_8bit(samples, count).data());
  } else {
    std::vector<uint16_t> out(count);
    for (size_t i = 0; i < count; ++i) out[i] = static_cast<uint16_t>(quantize(samples[i]));
    write_png16(path, width, height, channels, out.data());
  }
}

}  // namespace mipnerf::io
