// The photos of a `dataset from-photos` folder: its PNG and JPEG files in name order, each one's size from its header,
// and the one size COLMAP's single camera is given (cli/cmd_from_photos.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mipnerf::cli {

struct Photo {
  std::string name;  // the file's name in the folder
  uint32_t width_px = 0, height_px = 0;
};

// What from-photos hands to COLMAP: the photos of the capture's size, and those left out for having another.
struct PhotoSelection {
  std::vector<std::string> names;  // the photos of the chosen size, in name order
  uint32_t width_px = 0, height_px = 0;
  std::vector<Photo> other_size;  // left out: not width_px x height_px
  size_t total() const { return names.size() + other_size.size(); }
};

// The PNG and JPEG files (by extension) directly in `folder`, in name order, with their sizes from their headers
// (nothing is decoded). Throws mipnerf::Error naming the folder when it is missing, or a photo whose header cannot
// be read.
std::vector<Photo> list_photos(const std::string& folder);

// The size more than half of `photos` have, and the others named. COLMAP estimates one camera for all the photos,
// and its feature extractor drops a photo of another size with only a line in its log; a dataset of one camera has
// one size too. Throws mipnerf::Error (naming `folder`) when no size is held by more than half: which photos are the
// capture is then the user's call.
PhotoSelection select_photo_size(const std::vector<Photo>& photos, const std::string& folder);

// One line naming every photo left out and its size, and how to include them ("" when none is).
std::string describe_left_out(const PhotoSelection& selection);

}  // namespace mipnerf::cli
