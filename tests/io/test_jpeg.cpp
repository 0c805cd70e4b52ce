// JPEG reading (io/jpeg.hpp): a written image decodes within JPEG's loss, and damaged files are one line each.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/error.hpp"
#include "data/image.hpp"
#include "io/image_budget.hpp"
#include "io/jpeg.hpp"
#include "support/jpeg_writer.hpp"
#include "support/temp_scene.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

TEST_CASE("jpeg: a smooth image decodes within JPEG's loss, as RGB or as an RGBA image with alpha 1") {
  const auto dir = test::fresh_temp_dir("jpeg");
  fs::create_directories(dir);
  const unsigned width = 24, height = 16;
  std::vector<float> rgb(width * height * 3);
  for (unsigned y = 0; y < height; ++y) {
    for (unsigned x = 0; x < width; ++x) {
      float* p = rgb.data() + (y * width + x) * 3;
      p[0] = x / float(width);
      p[1] = y / float(height);
      p[2] = 0.5f;
    }
  }
  const std::string path = (dir / "smooth.jpg").string();
  test::write_jpeg(path, width, height, rgb, 98);
  const io::JpegImage image = io::read_jpeg(path);
  REQUIRE(image.width == width);
  REQUIRE(image.height == height);
  double worst = 0;
  for (size_t k = 0; k < rgb.size(); ++k) worst = std::max(worst, std::abs(double(image.rgb[k]) - rgb[k]));
  CHECK(worst < 0.05);
  const data::RgbaImage rgba = data::load_rgba_image(path);  // told apart from PNG by its first bytes
  CHECK(rgba.width == width);
  CHECK(rgba.rgba[3] == 1.0f);
  CHECK(rgba.rgba[0] == image.rgb[0]);

  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  auto decode = [](const std::string& b) {
    return io::decode_jpeg(reinterpret_cast<const unsigned char*>(b.data()), b.size(), "damaged.jpg");
  };
  CHECK_THROWS_WITH_AS(decode(bytes.substr(0, 40)), doctest::Contains("damaged.jpg: unreadable JPEG"), Error);
  CHECK_THROWS_WITH_AS(decode("GIF89a"), doctest::Contains("damaged.jpg: not a JPEG file"), Error);
  CHECK_THROWS_WITH_AS(decode(std::string("\xff\xd8\xff\xd9", 4)), doctest::Contains("unreadable JPEG"), Error);
  // Cut inside the scan data (the header and tables are the first ~600 bytes): libjpeg alone would fill the missing
  // rows with grey and only warn; a truncated photo must not train as a picture with a grey band.
  REQUIRE(bytes.size() > 700);
  CHECK_NOTHROW(decode(bytes));
  CHECK_THROWS_WITH_AS(decode(bytes.substr(0, bytes.size() - 40)),
                       doctest::Contains("damaged.jpg: unreadable JPEG (Premature end of JPEG file)"), Error);

  // The same file with the frame header (SOF0: FF C0, length, precision, height, width) claiming a huge image.
  const size_t sof = bytes.find("\xff\xc0");
  REQUIRE(sof != std::string::npos);
  auto claiming = [&](unsigned claimed_width, unsigned claimed_height) {
    std::string patched = bytes;
    patched[sof + 5] = static_cast<char>(claimed_height >> 8);
    patched[sof + 6] = static_cast<char>(claimed_height & 0xff);
    patched[sof + 7] = static_cast<char>(claimed_width >> 8);
    patched[sof + 8] = static_cast<char>(claimed_width & 0xff);
    return patched;
  };
  // Over the image budget (2 GiB; 37 bytes a pixel through the dataset reader): refused from the header, before
  // anything is decoded (tests/io/test_image_budget.cpp measures that nothing is allocated).
  CHECK_THROWS_WITH_AS(decode(claiming(20000, 20000)),
                       doctest::Contains("damaged.jpg: a 20000x20000 image needs 14115 MiB to decode"), Error);
  // Within a budget raised for it but far more than the data codes: stops where the scan's data ends at the
  // end-of-image marker (rows are allocated as they decode, so this costs nothing like the 9 GB the claimed size
  // would take).
  io::set_image_budget_bytes(uint64_t{16} << 30);
  CHECK_THROWS_WITH_AS(decode(claiming(16000, 16000)), doctest::Contains("premature end of data segment"), Error);
  io::set_image_budget_bytes(io::kDefaultImageBudgetBytes);
  fs::remove_all(dir);
}
