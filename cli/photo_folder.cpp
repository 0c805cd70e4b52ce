// The photos of a `dataset from-photos` folder and the size given to COLMAP's one camera.
#include "photo_folder.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <utility>

#include "core/error.hpp"
#include "data/image.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

std::string size_text(uint32_t width_px, uint32_t height_px) {
  return std::to_string(width_px) + "x" + std::to_string(height_px);
}

}  // namespace

std::vector<Photo> list_photos(const std::string& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw Error(folder + ": no such folder (expected the photos)");
  std::vector<Photo> photos;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (entry.is_regular_file() && data::has_image_extension(entry.path())) photos.push_back({entry.path().filename().string()});
  }
  std::sort(photos.begin(), photos.end(), [](const Photo& a, const Photo& b) { return a.name < b.name; });
  for (Photo& photo : photos) {
    const data::ImageSize size = data::read_image_size((fs::path(folder) / photo.name).string());
    photo.width_px = size.width;
    photo.height_px = size.height;
  }
  return photos;
}

PhotoSelection select_photo_size(const std::vector<Photo>& photos, const std::string& folder) {
  std::map<std::pair<uint32_t, uint32_t>, size_t> count_by_size;
  for (const Photo& photo : photos) ++count_by_size[{photo.width_px, photo.height_px}];
  PhotoSelection selection;
  if (count_by_size.empty()) return selection;
  const auto most = std::max_element(count_by_size.begin(), count_by_size.end(),
                                     [](const auto& a, const auto& b) { return a.second < b.second; });
  if (2 * most->second <= photos.size()) {
    std::string sizes;
    for (const auto& [size, count] : count_by_size) {
      sizes += (sizes.empty() ? "" : ", ") + std::to_string(count) + " at " + size_text(size.first, size.second);
    }
    throw Error(folder + ": photos of " + std::to_string(count_by_size.size()) + " sizes and none held by more than "
                "half (" + sizes + "); COLMAP estimates one camera for all photos, so they need one size: resize them "
                "to one, or move the others out");
  }
  selection.width_px = most->first.first;
  selection.height_px = most->first.second;
  for (const Photo& photo : photos) {
    if (photo.width_px == selection.width_px && photo.height_px == selection.height_px) {
      selection.names.push_back(photo.name);
    } else {
      selection.other_size.push_back(photo);
    }
  }
  return selection;
}

std::string describe_left_out(const PhotoSelection& selection) {
  if (selection.other_size.empty()) return "";
  const std::string size = size_text(selection.width_px, selection.height_px);
  std::string names;
  for (const Photo& photo : selection.other_size) {
    names += (names.empty() ? "" : ", ") + photo.name + " (" + size_text(photo.width_px, photo.height_px) + ")";
  }
  const size_t n = selection.other_size.size();
  return std::to_string(n) + " of " + std::to_string(selection.total()) + " photos " + (n == 1 ? "is" : "are") +
         " not " + size + " like the others and " + (n == 1 ? "is" : "are") + " left out (COLMAP estimates one " +
         "camera for all photos): " + names + "; resize " + (n == 1 ? "it" : "them") + " to " + size + " to include " +
         (n == 1 ? "it" : "them");
}

}  // namespace mipnerf::cli
