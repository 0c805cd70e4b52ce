// JPEG reading (io/jpeg.hpp): a written image decodes within JPEG's loss, and damaged files are one line each.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/error.hpp"
#include "data/image.hpp"
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
  fs::remove_all(dir);
}
