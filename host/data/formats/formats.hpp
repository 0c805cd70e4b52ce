// The dataset formats as one table (google/mipnerf's dataset_dict, nerfstudio's DataParser registry): each row owns
// its detection, its parsing into frames, what its metadata says about the scene, the effects its scenes call for
// and its render path. load_dataset, scene_traits, `dataset inspect` and `render --path spiral` only iterate the
// table. A new format is a file of its own in this folder (its row) and one line in formats.cpp; a DatasetFormat
// value without its row, or rows out of order, fail to compile there.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "data/dataset.hpp"
#include "data/frames.hpp"

namespace mipnerf::data {

// What a dataset is, from its metadata and first image without loading it: the facts that decide the effects a
// scene calls for.
struct SceneTraits {
  DatasetFormat format = DatasetFormat::blender;
  bool has_alpha = false;   // the first image has an alpha channel (rendered objects, not photos)
  bool all_around = false;  // LLFF or transforms.json: the cameras look inward from all around (360°), not forward
  bool multiscale = false;  // images at several scales on disk (multiscale Blender)
  // transforms.json: the cameras look forward (not all around). NDC holds such a capture when `ndc_blocker` is empty;
  // else it says why not ("the file gives no near/far", "its frames differ in focal length or image size").
  bool forward_facing = false;
  std::string ndc_blocker;
};

// The effects a scene calls for: settings (by name, as train's settings table spells them) and one line for people.
// Settings given explicitly still win (train/scene_effects.hpp).
struct SceneEffects {
  std::map<std::string, std::string> settings;  // setting name → value the data calls for
  std::string summary;                          // "forward-facing LLFF → NDC rays, cylinders, black background"
  // What the scene calls for from one model family (a 360° capture: proposal sampling and the unbounded contraction,
  // each family its own way), added to `settings` when training that family: as a group, all or none
  // (train/scene_effects.hpp), and said by the summary ("unbounded (contraction, …)"). The NeRF baseline has none.
  std::map<std::string, std::string> zipnerf_settings;
  std::string zipnerf_summary;
  std::map<std::string, std::string> mipnerf_settings;
  std::string mipnerf_summary;
};

// A render path a format defines for its captures (LLFF's official spiral or spherical circle).
struct FormatRenderPath {
  std::vector<Camera> cameras;
  std::string description;  // "the spiral of DIR"
  std::string kind;         // "llff spiral", recorded in render.json
};

struct FormatReader {
  DatasetFormat format;
  const char* name;  // for people: "Blender (transforms_<split>.json)"
  // Whether `path` (a folder, or a file when is_file) holds this format. The table is tried in order.
  bool (*detect)(const std::filesystem::path& path, bool is_file);
  // Every requested split's frames, without reading an image. Throws mipnerf::Error naming the file.
  std::vector<detail::SplitSpec> (*parse)(const std::string& path, const LoadOptions& options);
  // What the format's metadata adds to the traits (the first image's alpha is read by scene_traits).
  void (*add_traits)(const std::string& path, const LoadOptions& options, SceneTraits& traits);
  // The effects a scene of this format calls for, from its traits.
  SceneEffects (*effects)(const SceneTraits& traits);
  // The format's own render path of `frames` views, or nullptr when it has none.
  FormatRenderPath (*render_path)(const std::string& path, const LoadOptions& options, int frames);
  // Its images are already a scale pyramid on disk (train builds none on top; make-multiscale refuses it).
  bool scales_on_disk;
  // make-multiscale can build the paper's pyramid from it (a Blender folder or a transforms.json).
  bool pyramid_source;
  // Its splits' near 0, far 1 are NDC bounds (LLFF), not depths a look-at centre could be compared with.
  bool ndc_bounds;
};

// The row of `format`.
const FormatReader& format_reader(DatasetFormat format);

// The row whose format `path` holds (the first that detects it). Throws saying what was expected when none does,
// and when the path does not exist.
const FormatReader& detect_reader(const std::string& path);

// Throws the one-line error for a path that holds no dataset, saying what to do: a missing path (with the name
// meant, when one is close), a COLMAP model (`dataset import-colmap`), photos without poses (`dataset from-photos`), an
// empty folder (`make-scene`), datasets in its subfolders, or what a dataset folder holds (formats/no_dataset.cpp).
[[noreturn]] void throw_no_dataset(const std::string& path);

// The rows, in detection order.
const std::vector<const FormatReader*>& format_readers();

// What the dataset at `path` is (the format's traits, and the first training image's alpha). Throws mipnerf::Error
// naming the file when the metadata or the first image cannot be read.
SceneTraits scene_traits(const std::string& path, const LoadOptions& options);

// The effects the dataset at `path` calls for (its format's rule applied to scene_traits).
SceneEffects scene_effects(const std::string& path, const LoadOptions& options);

// The rows (one file each in this folder).
extern const FormatReader kBlenderFormat;
extern const FormatReader kMultiscaleBlenderFormat;
extern const FormatReader kTransformsJsonFormat;
extern const FormatReader kLlffFormat;

// Shared by the rows: the file a format reads inside a folder, or the path itself when it is that file.
std::string format_file(const std::string& path, const char* file_name);

// The Blender-family effects: cones; a white background for rendered objects with alpha, black for photos; photos
// taken all around (traits.all_around, set by transforms.json) are an unbounded scene for Zip-NeRF, as a 360° LLFF
// capture is.
SceneEffects object_or_photo_effects(const SceneTraits& traits, const std::string& kind);

// What a forward-facing capture of photos calls for (the official LLFF conventions, configs/llff.gin): NDC rays as
// cylinders, a black background, the world directions as view directions, density noise 1; `kind` opens the summary.
SceneEffects forward_facing_ndc_effects(const std::string& kind);

// What a capture all around calls for from each family, as one group a family with its summary: Zip-NeRF proposal
// sampling, the contraction of its grid points and the power ladder (SceneEffects::zipnerf_settings); mip-NeRF
// mip-NeRF 360's model, its frustums contracted and IPE'd on 21 directions at the official degrees 0..11, proposal
// sampling spaced in disparity (SceneEffects::mipnerf_settings).
void add_unbounded(SceneEffects& effects);

}  // namespace mipnerf::data
