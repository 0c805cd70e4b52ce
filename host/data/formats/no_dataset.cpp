// What to say when a path holds no dataset: a path that does not exist (with the name meant, when one is close), a
// COLMAP model (import-colmap makes a dataset of it), a folder of photos without poses (from-photos does), an empty
// folder (make-scene can fill it), a folder whose subfolders hold datasets, or a folder of something else.
#include <algorithm>
#include <optional>

#include "core/error.hpp"
#include "data/formats/formats.hpp"
#include "data/image.hpp"
#include "io/path_hint.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;
namespace {

// What a dataset folder holds, one of (the rows' detections).
constexpr const char* kDatasetFiles =
    "transforms_train.json (Blender), metadata.json (multiscale Blender), transforms.json or "
    "poses_bounds.npy with images/ (an LLFF capture)";

// The photos (PNG or JPEG files) directly in `folder`.
size_t count_photos(const fs::path& folder) {
  size_t count = 0;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec) && has_image_extension(it->path())) ++count;
  }
  return count;
}

bool holds_dataset(const fs::path& folder) {
  for (const FormatReader* reader : format_readers()) {
    if (reader->detect(folder, false)) return true;
  }
  return false;
}

// A COLMAP sparse model in `folder` itself, or where COLMAP's workspace keeps it (sparse/0, sparse).
std::optional<fs::path> colmap_model_in(const fs::path& folder) {
  std::error_code ec;
  for (const fs::path& model : {folder / "sparse" / "0", folder / "sparse", folder}) {
    for (const char* file : {"cameras.bin", "cameras.txt"}) {
      if (fs::is_regular_file(model / file, ec)) return model;
    }
  }
  return std::nullopt;
}

struct FolderContents {
  bool empty = true;
  std::vector<std::string> dataset_subfolders;  // sorted names
};

FolderContents look_into(const fs::path& folder) {
  FolderContents contents;
  std::error_code ec;
  size_t seen = 0;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end && seen < 1000; it.increment(ec), ++seen) {
    contents.empty = false;
    if (it->is_directory(ec) && holds_dataset(it->path()))
      contents.dataset_subfolders.push_back(it->path().filename().string());
  }
  std::sort(contents.dataset_subfolders.begin(), contents.dataset_subfolders.end());
  return contents;
}

std::string from_photos_hint(const std::string& photos) {
  return "make a dataset of them with `mipnerf-cl dataset from-photos " + photos + " OUT` (COLMAP), then train on OUT";
}

}  // namespace

void throw_no_dataset(const std::string& path) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) {
    const std::string hint = io::missing_path_hint(path);
    throw Error(path + ": no such file or folder" + (hint.empty() ? "" : "; " + hint));
  }
  if (!fs::is_directory(status)) {
    throw Error(path + ": not a dataset file: give a folder, a transforms.json or a metadata.json");
  }
  // A COLMAP workspace or model: its poses are there, in COLMAP's form.
  if (const auto model = colmap_model_in(path)) {
    std::error_code ignored;
    const fs::path images = fs::path(path) / "images";
    const std::string images_arg = fs::is_directory(images, ignored) ? images.string() : "IMAGES_DIR";
    const std::string command = "mipnerf-cl dataset import-colmap " + model->string() + " " + images_arg + " OUT";
    throw Error(path + ": a COLMAP model (" + model->string() + ") but no dataset; import it with `" + command +
                "`, then train on OUT");
  }
  // Photos without poses: the usual first try with one's own capture.
  if (const size_t photos = count_photos(path); photos > 0) {
    throw Error(path + ": " + std::to_string(photos) + (photos == 1 ? " photo" : " photos") +
                " (PNG or JPEG) but no camera poses; " + from_photos_hint(path));
  }
  const fs::path images = fs::path(path) / "images";
  if (const size_t photos = count_photos(images); photos > 0) {
    const std::string count = std::to_string(photos) + (photos == 1 ? " photo" : " photos");
    throw Error(path + ": " + count + " in images/ but no camera poses (no poses_bounds.npy or transforms.json); " +
                from_photos_hint(images.string()));
  }
  const FolderContents contents = look_into(path);
  if (contents.empty) {
    throw Error(path +
                ": an empty folder; put a dataset there, or write the built-in procedural scene into it with "
                "`mipnerf-cl make-scene " +
                path + "`");
  }
  if (!contents.dataset_subfolders.empty()) {
    const auto& names = contents.dataset_subfolders;
    std::string list;
    const size_t shown = std::min<size_t>(names.size(), 4);
    for (size_t i = 0; i < shown; ++i) list += (i == 0 ? "" : ", ") + names[i];
    if (names.size() > shown) list += " and " + std::to_string(names.size() - shown) + " more";
    throw Error(path + ": no dataset here, but " + (names.size() == 1 ? "its subfolder " : "its subfolders ") + list +
                (names.size() == 1 ? " holds one: give " : " hold one each: give one of them, e.g. ") +
                (fs::path(path) / names.front()).string());
  }
  throw Error(path + ": no dataset here: expected " + std::string(kDatasetFiles) +
              "; for photos without poses, see `mipnerf-cl dataset "
              "from-photos`");
}

}  // namespace mipnerf::data
