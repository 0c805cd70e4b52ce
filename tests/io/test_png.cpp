// PNG reading and writing through libpng: exact round trips at 8 and 16 bits, expansion of grey/RGB to RGBA,
// and one-line errors (never a crash) for missing, non-PNG, truncated and corrupted files.
#include <doctest/doctest.h>

#include <fstream>

#include <png.h>

#include "support/data_fixtures.hpp"
#include "io/file.hpp"
#include "io/png.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

TEST_CASE("png: 8-bit RGBA and RGB round trip exactly, RGB reads with alpha 1") {
  test::TempDir dir;
  const uint32_t w = 7, h = 5;  // odd sizes: rows are not a multiple of 4 bytes
  const auto rgba = test::test_rgba8(3, w, h);
  io::write_png8(dir / "rgba.png", w, h, 4, rgba.data());
  const auto back = io::read_png(dir / "rgba.png");
  CHECK(back.width == w);
  CHECK(back.height == h);
  CHECK(back.bit_depth == 8);
  CHECK(back.has_alpha);
  REQUIRE(back.rgba.size() == rgba.size());
  // Decoding gives code / 255 exactly as float division does (the official loader's value / 255).
  for (size_t i = 0; i < rgba.size(); ++i) REQUIRE(back.rgba[i] == static_cast<float>(rgba[i]) / 255.0f);

  std::vector<uint8_t> rgb;
  for (size_t i = 0; i < rgba.size(); ++i) {
    if (i % 4 != 3) rgb.push_back(rgba[i]);
  }
  io::write_png8(dir / "rgb.png", w, h, 3, rgb.data());
  const auto back_rgb = io::read_png(dir / "rgb.png");
  CHECK_FALSE(back_rgb.has_alpha);
  for (size_t p = 0; p < size_t{w} * h; ++p) {
    for (int c = 0; c < 3; ++c) REQUIRE(back_rgb.rgba[4 * p + c] == static_cast<float>(rgb[3 * p + c]) / 255.0f);
    REQUIRE(back_rgb.rgba[4 * p + 3] == 1.0f);
  }
}

TEST_CASE("png: 16-bit input keeps its precision") {
  test::TempDir dir;
  const uint32_t w = 4, h = 3;
  std::vector<uint16_t> samples(w * h * 4);
  for (size_t i = 0; i < samples.size(); ++i) samples[i] = static_cast<uint16_t>(i * 4099 + 1);  // spans 0..65535
  io::write_png16(dir / "deep.png", w, h, 4, samples.data());
  const auto back = io::read_png(dir / "deep.png");
  CHECK(back.bit_depth == 16);
  for (size_t i = 0; i < samples.size(); ++i) REQUIRE(back.rgba[i] == static_cast<float>(samples[i]) / 65535.0f);
}

TEST_CASE("png: float writer clamps, rounds to nearest and maps NaN to 0") {
  test::TempDir dir;
  const float samples[6] = {-0.5f, 0.5f, 1.5f, 0.2f / 255.0f, 0.6f / 255.0f, std::nanf("")};
  io::write_png(dir / "f.png", 2, 1, 3, samples, 8);
  const auto back = io::read_png(dir / "f.png");
  const float expected[6] = {0.0f, 128.0f / 255.0f, 1.0f, 0.0f, 1.0f / 255.0f, 0.0f};  // 127.5 rounds up
  for (int i = 0; i < 6; ++i) CHECK(back.rgba[(i / 3) * 4 + i % 3] == expected[i]);
}

TEST_CASE("png: missing, empty, non-PNG and truncated files give one-line errors naming the file") {
  test::TempDir dir;
  CHECK(error_of([&] { io::read_png(dir / "nope.png"); }) == dir / "nope.png" + ": no such file");
  { std::ofstream(dir / "empty.png"); }
  CHECK(contains(error_of([&] { io::read_png(dir / "empty.png"); }), "empty.png: unreadable PNG (not a PNG file"));
  { std::ofstream(dir / "text.png") << "this is not an image at all"; }
  CHECK(contains(error_of([&] { io::read_png(dir / "text.png"); }), "text.png: unreadable PNG (not a PNG file"));

  const auto rgba = test::test_rgba8(1, 16, 16);
  const auto bytes = io::encode_png8(16, 16, 4, rgba.data());
  for (size_t keep : {size_t{8}, size_t{20}, size_t{40}, bytes.size() / 2, bytes.size() - 13}) {
    const std::string message = error_of([&] { io::decode_png(bytes.data(), keep, "cut.png"); });
    CAPTURE(keep);
    CHECK(contains(message, "cut.png: unreadable PNG ("));
    CHECK(message.find('\n') == std::string::npos);
  }
}

TEST_CASE("png: corrupted bytes anywhere either decode or throw mipnerf::Error, never crash") {
  const auto rgba = test::test_rgba8(2, 12, 9);
  const auto good = io::encode_png8(12, 9, 4, rgba.data());
  int errors = 0;
  for (size_t position = 8; position < good.size(); ++position) {
    for (unsigned char flip : {0x01, 0x80, 0xFF}) {
      auto bad = good;
      bad[position] ^= flip;
      try {
        const auto image = io::decode_png(bad.data(), bad.size(), "bad.png");
        CHECK(image.rgba.size() == size_t{image.width} * image.height * 4);
      } catch (const Error& e) {
        ++errors;
        REQUIRE(contains(e.what(), "bad.png: unreadable PNG ("));
      }
    }
  }
  // CRCs catch nearly every flip: most of these must have been reported, not silently accepted.
  CHECK(errors > static_cast<int>(good.size()));
}

TEST_CASE("png: grey, grey+alpha and palette files are expanded to RGBA") {
  // Written with libpng's simplified API (8-bit formats are stored as given, no gamma change).
  auto encode = [](uint32_t format, const std::vector<uint8_t>& pixels, uint32_t w, uint32_t h,
                   const std::vector<uint8_t>* colormap = nullptr) {
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    image.width = w;
    image.height = h;
    image.format = format;
    if (colormap) image.colormap_entries = static_cast<png_uint_32>(colormap->size() / 4);
    png_alloc_size_t size = 0;
    REQUIRE(png_image_write_to_memory(&image, nullptr, &size, 0, pixels.data(), 0,
                                      colormap ? colormap->data() : nullptr));
    std::vector<unsigned char> bytes(size);
    REQUIRE(png_image_write_to_memory(&image, bytes.data(), &size, 0, pixels.data(), 0,
                                      colormap ? colormap->data() : nullptr));
    bytes.resize(size);
    return bytes;
  };
  const std::vector<uint8_t> grey = {0, 17, 128, 255, 3, 250};
  auto bytes = encode(PNG_FORMAT_GRAY, grey, 3, 2);
  auto image = io::decode_png(bytes.data(), bytes.size(), "grey.png");
  CHECK_FALSE(image.has_alpha);
  for (size_t p = 0; p < 6; ++p) {
    for (int c = 0; c < 3; ++c) CHECK(image.rgba[4 * p + c] == grey[p] / 255.0f);
    CHECK(image.rgba[4 * p + 3] == 1.0f);
  }
  const std::vector<uint8_t> grey_alpha = {10, 0, 20, 128, 30, 255, 40, 7};
  bytes = encode(PNG_FORMAT_GA, grey_alpha, 2, 2);
  image = io::decode_png(bytes.data(), bytes.size(), "ga.png");
  CHECK(image.has_alpha);
  for (size_t p = 0; p < 4; ++p) {
    for (int c = 0; c < 3; ++c) CHECK(image.rgba[4 * p + c] == grey_alpha[2 * p] / 255.0f);
    CHECK(image.rgba[4 * p + 3] == grey_alpha[2 * p + 1] / 255.0f);
  }
  const std::vector<uint8_t> colormap = {255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0};  // RGBA entries
  const std::vector<uint8_t> indices = {0, 1, 2, 1};
  bytes = encode(PNG_FORMAT_RGBA_COLORMAP, indices, 2, 2, &colormap);
  image = io::decode_png(bytes.data(), bytes.size(), "palette.png");
  CHECK(image.has_alpha);
  for (size_t p = 0; p < 4; ++p) {
    for (int c = 0; c < 4; ++c) CHECK(image.rgba[4 * p + c] == colormap[4 * indices[p] + c] / 255.0f);
  }
}
