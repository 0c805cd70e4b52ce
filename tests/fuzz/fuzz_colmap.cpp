// Fuzz target: the COLMAP sparse-model readers (data/import/colmap_model.hpp), then the importer (data/import/colmap_import.hpp) and the
// loader of what it wrote. The input's first byte picks the file it stands for (its value mod 6: cameras.txt,
// images.txt, points3D.txt, cameras.bin, images.bin, points3D.bin); the other two files of the model are the
// committed test fixture's (tests/data/fixtures/colmap/sparse or sparse_bin: three 8x6 PINHOLE views of 27
// points), so a mutation of one file meets consistent others and reaches the checks that span files.
//
// The three files are parsed from memory and checked (check_colmap_model), as read_colmap_model does after reading
// them; a model that passes is written to the scratch folder and imported for real, against the fixture's images,
// and the transforms.json written is loaded: the import's arithmetic (centre, scale, near/far from point depths)
// sees the fuzzed numbers, and every camera that comes out must be finite.
#include <array>
#include <cmath>
#include <string>

#include "data/import/colmap_model.hpp"
#include "data/import/colmap_import.hpp"
#include "data/dataset.hpp"
#include "fuzz_support.hpp"
#include "io/file.hpp"

namespace {
using namespace mipnerf;
namespace fs = std::filesystem;

constexpr const char* kStems[3] = {"cameras", "images", "points3D"};

// The fixture's files: [binary][stem].
const std::array<std::array<std::string, 3>, 2>& fixture_files() {
  static const auto files = [] {
    std::array<std::array<std::string, 3>, 2> read;
    for (int binary = 0; binary < 2; ++binary) {
      for (int stem = 0; stem < 3; ++stem) {
        const std::string path = std::string(MIPNERF_FUZZ_COLMAP_FIXTURE) + (binary ? "/sparse_bin/" : "/sparse/") +
                                 kStems[stem] + (binary ? ".bin" : ".txt");
        const std::vector<unsigned char> bytes = io::read_file_bytes(path);
        read[binary][stem].assign(bytes.begin(), bytes.end());
      }
    }
    return read;
  }();
  return files;
}

bool finite_camera(const Camera& camera) {
  for (double v : camera.camera_to_world) {
    if (!std::isfinite(v)) return false;
  }
  return std::isfinite(camera.focal_x_px) && std::isfinite(camera.focal_y_px) && std::isfinite(camera.near) &&
         std::isfinite(camera.far) && camera.far > camera.near;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const int selected = data[0] % 6;
  const bool binary = selected >= 3;
  const int fuzzed_stem = selected % 3;
  const std::string_view fuzzed(reinterpret_cast<const char*>(data) + 1, size - 1);

  data::ColmapModel model;
  model.dir = (fuzz::scratch_folder() / (binary ? "colmap/sparse_bin" : "colmap/sparse")).string();
  model.binary = binary;
  std::array<std::string_view, 3> contents;
  for (int stem = 0; stem < 3; ++stem) contents[stem] = stem == fuzzed_stem ? fuzzed : fixture_files()[binary][stem];

  fuzz::expect_only_errors(model.dir, [&] {
    if (binary) {
      model.cameras = data::parse_colmap_cameras_binary(contents[0], model.file(kStems[0]));
      model.images = data::parse_colmap_images_binary(contents[1], model.file(kStems[1]));
      model.points = data::parse_colmap_points_binary(contents[2], model.file(kStems[2]));
    } else {
      model.cameras = data::parse_colmap_cameras_text(contents[0], model.file(kStems[0]));
      model.images = data::parse_colmap_images_text(contents[1], model.file(kStems[1]));
      model.points = data::parse_colmap_points_text(contents[2], model.file(kStems[2]));
    }
    data::check_colmap_model(model);

    io::make_directories(model.dir);
    for (int stem = 0; stem < 3; ++stem) {
      fuzz::write_input(model.file(kStems[stem]), reinterpret_cast<const uint8_t*>(contents[stem].data()),
                        contents[stem].size());
    }
    const std::string out = (fuzz::scratch_folder() / "colmap/out").string();
    const data::ColmapImport imported =
        data::import_colmap(model.dir, std::string(MIPNERF_FUZZ_COLMAP_FIXTURE) + "/images", out);
    fuzz::check(std::isfinite(imported.near) && std::isfinite(imported.far) && imported.far > imported.near,
                "an imported near/far is not a finite, ordered pair");
    fuzz::check(std::isfinite(imported.scale) && imported.scale > 0, "an imported scale is not finite and positive");
    const data::Dataset dataset = data::load_dataset(out);
    for (const auto& split : dataset.splits) {
      for (const auto& camera : split.cameras) fuzz::check(finite_camera(camera), "an imported camera is not finite");
    }
  });
  return 0;
}
