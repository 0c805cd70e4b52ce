// OpenEXR output (host/io/exr): exact float round trip, channel names, optional channels, atomic writes,
// errors naming the file.
#include <doctest/doctest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <half.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/exr.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

struct ExrScratch {
  fs::path path;
  explicit ExrScratch(const std::string& name)
      : path(fs::temp_directory_path() / ("mipnerf-exr-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~ExrScratch() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

// Random floats over many magnitudes and both signs, with the special values a render can hold.
std::vector<float> wide_floats(size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-30, 30);
  std::vector<float> values(count);
  for (auto& v : values) v = std::ldexp(mantissa(rng), exponent(rng));
  if (count >= 6) {
    values[0] = 0.0f;
    values[1] = -0.0f;
    values[2] = std::numeric_limits<float>::infinity();
    values[3] = std::numeric_limits<float>::denorm_min();
    values[4] = std::numeric_limits<float>::max();
    values[5] = 1.0f / 3.0f;
  }
  return values;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("exr: R, G, B, Z and acc round-trip bit for bit, with the header attributes") {
  ExrScratch scratch("roundtrip");
  io::ExrImage image;
  image.width = 37;
  image.height = 23;
  image.rgb = wide_floats(3 * 37 * 23, 1);
  image.depth = wide_floats(37 * 23, 2);
  image.acc = wide_floats(37 * 23, 3);
  image.attributes = {{"mipnerf:step", "12000"}, {"mipnerf:camera", "val/r_0"}};
  const std::string path = scratch.file("render.exr");
  io::write_exr(path, image);

  const io::ExrImage back = io::read_exr(path);
  CHECK(back.width == 37);
  CHECK(back.height == 23);
  CHECK(same_bits(back.rgb, image.rgb));
  CHECK(same_bits(back.depth, image.depth));
  CHECK(same_bits(back.acc, image.acc));
  CHECK(back.attributes == image.attributes);

  // What other readers see: float channels named B, G, R, Z, acc (OpenEXR lists them sorted), and the
  // description of each channel in the header.
  Imf::InputFile file(path.c_str());
  std::vector<std::string> names;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
    names.push_back(it.name());
    CHECK(it.channel().type == Imf::FLOAT);
  }
  CHECK(names == std::vector<std::string>{"B", "G", "R", "Z", "acc"});
  const auto* description = file.header().findTypedAttribute<Imf::StringAttribute>("mipnerf:channels");
  REQUIRE(description);
  CHECK(description->value().find("Z: expected ray depth") != std::string::npos);
  // A NaN stays a NaN.
  image.rgb[10] = std::numeric_limits<float>::quiet_NaN();
  io::write_exr(path, image);
  CHECK(std::isnan(io::read_exr(path).rgb[10]));
}

TEST_CASE("exr: depth and acc are optional") {
  ExrScratch scratch("optional");
  io::ExrImage image;
  image.width = 4;
  image.height = 3;
  image.rgb = wide_floats(36, 4);
  image.acc.assign(12, 0.5f);
  io::write_exr(scratch.file("a.exr"), image);
  const auto back = io::read_exr(scratch.file("a.exr"));
  CHECK(back.depth.empty());
  CHECK(back.acc == image.acc);
  CHECK(same_bits(back.rgb, image.rgb));
}

TEST_CASE("exr: writes are atomic, and a bad image leaves the old file intact") {
  ExrScratch scratch("atomic");
  const std::string path = scratch.file("out.exr");
  io::ExrImage good;
  good.width = good.height = 8;
  good.rgb.assign(3 * 64, 0.25f);
  io::write_exr(path, good);
  io::ExrImage bad = good;
  bad.depth.assign(63, 1.0f);  // one short
  CHECK_THROWS_WITH_AS(io::write_exr(path, bad), doctest::Contains("depth holds 63 values"), Error);
  bad = good;
  bad.attributes["compression"] = "none";  // would clash with a standard attribute
  CHECK_THROWS_WITH_AS(io::write_exr(path, bad), doctest::Contains("standard header attribute"), Error);
  CHECK(io::read_exr(path).rgb == good.rgb);
  CHECK(std::distance(fs::directory_iterator(scratch.path), {}) == 1);  // no temporary left
  io::ExrImage empty;
  CHECK_THROWS_WITH_AS(io::write_exr(path, empty), doctest::Contains("empty"), Error);
}

TEST_CASE("exr: the reader converts half channels and names the file in its errors") {
  ExrScratch scratch("reader");
  // A half-float RGB file as another tool would write it; values exact in half come back exactly.
  const std::string half_path = scratch.file("half.exr");
  {
    Imf::Header header(3, 2);
    for (const char* name : {"R", "G", "B"}) header.channels().insert(name, Imf::Channel(Imf::HALF));
    std::vector<half> pixels(18);
    for (size_t i = 0; i < 18; ++i) pixels[i] = half(static_cast<float>(i) * 0.125f);
    Imf::FrameBuffer frame;
    const char* names[3] = {"R", "G", "B"};
    for (size_t c = 0; c < 3; ++c) {
      frame.insert(names[c], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(pixels.data() + c), 3 * sizeof(half),
                                        9 * sizeof(half)));
    }
    Imf::OutputFile out(half_path.c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(2);
  }
  const auto back = io::read_exr(half_path);
  REQUIRE(back.rgb.size() == 18);
  for (size_t i = 0; i < 18; ++i) CHECK(back.rgb[i] == static_cast<float>(i) * 0.125f);

  // A file without R, G, B; a file that is not an EXR; no file at all.
  const std::string grey_path = scratch.file("grey.exr");
  {
    Imf::Header header(2, 2);
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    std::vector<float> y(4, 0.5f);
    Imf::FrameBuffer frame;
    frame.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(y.data()), sizeof(float), 2 * sizeof(float)));
    Imf::OutputFile out(grey_path.c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(2);
  }
  CHECK_THROWS_WITH_AS(io::read_exr(grey_path), doctest::Contains("no 'R' channel"), Error);
  const std::string text_path = scratch.file("not.exr");
  io::write_bytes_atomically(text_path, "this is not an image");
  CHECK_THROWS_WITH_AS(io::read_exr(text_path), doctest::Contains(text_path.c_str()), Error);
  const std::string missing = scratch.file("missing.exr");
  CHECK_THROWS_WITH_AS(io::read_exr(missing), doctest::Contains(missing.c_str()), Error);
}
