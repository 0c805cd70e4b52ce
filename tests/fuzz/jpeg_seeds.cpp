// Writes the JPEG fuzz target's seeds into a folder (tests/fuzz/corpus/jpeg was made with it), one per coding path
// libjpeg takes, each a small gradient image:
//   baseline_rgb_8x8.jpg           baseline Huffman, YCbCr 4:2:0, quality 90
//   baseline_444_17x9.jpg          baseline, no chroma subsampling, a size that is not a multiple of the block
//   grey_16x8.jpg                  one component
//   progressive_rgb_12x10.jpg      progressive (spectral selection and successive approximation scans)
//   restart_rgb_16x16.jpg          baseline with a restart marker after every MCU
//   arithmetic_rgb_8x8.jpg         arithmetic coding (libjpeg-turbo decodes it)
//   optimized_huffman_9x7.jpg      baseline with optimised Huffman tables
//   cmyk_8x8.jpg                   Adobe CMYK (the reader refuses it; the refusal path is fuzzed too)
//   fuzz_jpeg_seeds DIR
#include <cstddef>
#include <cstdio>  // before jpeglib.h, which uses size_t and FILE without including their headers
#include <jpeglib.h>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Options {
  unsigned width = 8, height = 8;
  int components = 3;
  J_COLOR_SPACE colour = JCS_RGB;
  bool progressive = false, arithmetic = false, optimize = false, full_chroma = false;
  int restart_mcus = 0;
};

void write_seed(const std::string& path, const Options& o) {
  std::FILE* out = std::fopen(path.c_str(), "wb");
  if (!out) throw std::runtime_error("cannot write " + path);
  jpeg_compress_struct info;
  jpeg_error_mgr errors;
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  jpeg_stdio_dest(&info, out);
  info.image_width = o.width;
  info.image_height = o.height;
  info.input_components = o.components;
  info.in_color_space = o.colour;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, 90, TRUE);
  if (o.progressive) jpeg_simple_progression(&info);
  info.arith_code = o.arithmetic ? TRUE : FALSE;
  info.optimize_coding = o.optimize ? TRUE : FALSE;
  info.restart_in_rows = 0;
  info.restart_interval = static_cast<unsigned>(o.restart_mcus);
  if (o.full_chroma) {
    for (int c = 0; c < info.num_components; ++c) info.comp_info[c].h_samp_factor = info.comp_info[c].v_samp_factor = 1;
  }
  jpeg_start_compress(&info, TRUE);
  std::vector<unsigned char> row(static_cast<size_t>(o.width) * o.components);
  while (info.next_scanline < o.height) {
    for (unsigned x = 0; x < o.width; ++x) {
      for (int c = 0; c < o.components; ++c) {
        row[x * o.components + c] = static_cast<unsigned char>((37 * c + 255 * x / o.width + 97 * info.next_scanline / o.height) % 256);
      }
    }
    JSAMPROW rows[1] = {row.data()};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::fclose(out);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_jpeg_seeds DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  auto sized = [](unsigned width, unsigned height) {
    Options o;
    o.width = width;
    o.height = height;
    return o;
  };
  write_seed(dir + "/baseline_rgb_8x8.jpg", sized(8, 8));
  Options full_chroma = sized(17, 9);
  full_chroma.full_chroma = true;
  write_seed(dir + "/baseline_444_17x9.jpg", full_chroma);
  Options grey = sized(16, 8);
  grey.components = 1;
  grey.colour = JCS_GRAYSCALE;
  write_seed(dir + "/grey_16x8.jpg", grey);
  Options progressive = sized(12, 10);
  progressive.progressive = true;
  write_seed(dir + "/progressive_rgb_12x10.jpg", progressive);
  Options restart = sized(16, 16);
  restart.restart_mcus = 1;
  write_seed(dir + "/restart_rgb_16x16.jpg", restart);
  Options arithmetic = sized(8, 8);
  arithmetic.arithmetic = true;
  write_seed(dir + "/arithmetic_rgb_8x8.jpg", arithmetic);
  Options optimized = sized(9, 7);
  optimized.optimize = true;
  write_seed(dir + "/optimized_huffman_9x7.jpg", optimized);
  Options cmyk = sized(8, 8);
  cmyk.components = 4;
  cmyk.colour = JCS_CMYK;
  write_seed(dir + "/cmyk_8x8.jpg", cmyk);
  return 0;
}
