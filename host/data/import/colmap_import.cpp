// COLMAP import: a sparse model and its images → OUT/transforms.json.
#include "data/import/colmap_import.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <unordered_map>

#include "core/error.hpp"
#include "core/lens_models.hpp"
#include "data/lens_tables.hpp"
#include "data/image.hpp"
#include "data/intrinsics.hpp"
#include "data/path_policy.hpp"
#include "io/file.hpp"
#include "io/json.hpp"
#include "io/npy.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;

namespace {

using Matrix33 = std::array<double, 9>;  // row-major

// R(q) for a unit quaternion (qw, qx, qy, qz), Hamilton convention (COLMAP's, Eigen's).
Matrix33 rotation_from_quaternion(const std::array<double, 4>& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

std::string num(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.4g", v);
  return text;
}

// q-quantile of sorted values, interpolating linearly between neighbours (numpy's default).
double quantile(const std::vector<double>& sorted, double q) {
  const double position = q * static_cast<double>(sorted.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(position));
  if (below + 1 >= sorted.size()) return sorted.back();
  const double fraction = position - static_cast<double>(below);
  return sorted[below] + fraction * (sorted[below + 1] - sorted[below]);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return quantile(values, 0.5);
}

struct Intrinsics {
  double fx, fy, cx, cy;
  uint64_t width, height;
  Lens lens;
};

// The intrinsics as a camera (no pose): what the lens check and the transforms writer take.
Camera as_camera(const Intrinsics& in) {
  Camera camera;
  camera.focal_x_px = in.fx;
  camera.focal_y_px = in.fy;
  camera.center_x_px = in.cx;
  camera.center_y_px = in.cy;
  camera.width_px = static_cast<uint32_t>(in.width);
  camera.height_px = static_cast<uint32_t>(in.height);
  camera.lens = in.lens;
  return camera;
}

// The intrinsics and lens of a camera the images use, read through its model's row (core/lens_models.hpp: COLMAP's
// parameter orders); a model without a row is refused with what to run.
Intrinsics camera_intrinsics(const ColmapModel& model, const ColmapCamera& camera) {
  const std::string at = model.where("cameras", camera.line, "camera", camera.id);
  const std::string name = camera.model->name;
  const LensRow* row = find_lens_row(name);
  if (!row) {
    throw Error(at + " is " + name + ", a model mipnerf-cl does not read (it reads " + lens_model_list() +
                "): run COLMAP's image_undistorter first and import the sparse model and images it writes (PINHOLE "
                "cameras)");
  }
  const ColmapIntrinsics read = read_colmap_params(*row, camera.params, at);
  Intrinsics in{read.fx, read.fy, read.cx, read.cy, camera.width, camera.height, read.lens};
  if (!(in.fx > 0.0) || !(in.fy > 0.0)) throw Error(at + ": the focal length must be positive");
  check_lens_over_image(as_camera(in), at);  // the lens must invert over the whole image, or no ray leaves some pixels
  return in;
}

// The image file a name stands for: the name itself when it is a PNG or JPEG, else the same name with a .png
// extension (an undistorted project converted to PNG).
enum class ImageFile { found, other_type, missing };
ImageFile find_image(const fs::path& given, fs::path& image) {
  std::error_code ec;
  if (has_image_extension(given)) {
    image = given;
    if (fs::is_regular_file(given, ec)) return ImageFile::found;
  }
  image = fs::path(given).replace_extension(".png");
  if (fs::is_regular_file(image, ec)) return ImageFile::found;
  return fs::is_regular_file(given, ec) ? ImageFile::other_type : ImageFile::missing;
}

// "a.png, b.png, c.png and 4 more".
std::string name_list(const std::vector<std::string>& names) {
  std::string text;
  const size_t shown = std::min<size_t>(names.size(), 5);
  for (size_t i = 0; i < shown; ++i) text += (i ? ", " : "") + names[i];
  if (names.size() > shown) text += " and " + std::to_string(names.size() - shown) + " more";
  return text;
}

// Relative from `from_dir` (existing) to `path` when there is such a path, else `path` made absolute.
std::string relative_path(const fs::path& path, const fs::path& from_dir) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(path, ec).lexically_normal();
  const fs::path relative = fs::relative(absolute, from_dir, ec);
  if (ec || relative.empty()) return absolute.generic_string();
  return relative.generic_string();
}

// The camera as a transforms file holds it (data/intrinsics.hpp's one writer).
io::Json intrinsics_json(const Intrinsics& in) { return data::intrinsics_json(as_camera(in)); }

}  // namespace

Matrix34 colmap_camera_to_world(const std::array<double, 4>& qvec, const std::array<double, 3>& tvec) {
  const Matrix33 r = rotation_from_quaternion(qvec);
  Matrix34 m{};
  for (int row = 0; row < 3; ++row) {
    // Row `row` of Rᵀ is column `row` of R. OpenCV → OpenGL camera axes: y and z flip (y down → up, z forward →
    // backward), i.e. the second and third columns of the camera-to-world rotation change sign.
    m[row * 4 + 0] = r[0 * 3 + row];
    m[row * 4 + 1] = -r[1 * 3 + row];
    m[row * 4 + 2] = -r[2 * 3 + row];
    m[row * 4 + 3] = -(r[0 * 3 + row] * tvec[0] + r[1 * 3 + row] * tvec[1] + r[2 * 3 + row] * tvec[2]);
  }
  return m;
}

double colmap_depth(const ColmapImage& image, const Vec3& p) {
  const Matrix33 r = rotation_from_quaternion(image.qvec);
  return r[6] * p[0] + r[7] * p[1] + r[8] * p[2] + image.tvec[2];
}

std::optional<DepthRange> near_far_from_depths(std::vector<std::vector<double>>& depths_per_image) {
  // Why percentiles: sparse models keep some badly triangulated points (wrong matches that passed the
  // reprojection test, points near the epipole) whose depth is far off; the smallest and largest depth would
  // follow them. Per image, because images see different depth ranges (a close-up among distant views) and a
  // pooled percentile would cut off the close-up's near surface. The margin keeps surfaces at the extremes inside
  // the sampled interval, where the stratified samples still reach them.
  std::optional<DepthRange> range;
  for (auto& depths : depths_per_image) {
    if (depths.empty()) continue;
    std::sort(depths.begin(), depths.end());
    const double low = quantile(depths, kDepthPercentileLow), high = quantile(depths, kDepthPercentileHigh);
    if (!range) {
      range = DepthRange{low, high, 0};
    } else {
      range->near = std::min(range->near, low);
      range->far = std::max(range->far, high);
    }
    ++range->images;
  }
  if (range) {
    range->near *= kNearMargin;
    range->far *= kFarMargin;
  }
  return range;
}

namespace {

// ---- The import's steps, in order ----

// The model's images in name order (the loader holds out every 8th of them as test), without those left out.
std::vector<const ColmapImage*> images_by_name(const ColmapModel& model, const std::vector<std::string>& leave_out) {
  std::vector<const ColmapImage*> images;
  for (const auto& image : model.images) {
    if (std::find(leave_out.begin(), leave_out.end(), image.name) == leave_out.end()) images.push_back(&image);
  }
  if (images.empty()) throw Error(model.file("images") + ": every image is left out; nothing to import");
  std::sort(images.begin(), images.end(), [](const auto* a, const auto* b) { return a->name < b->name; });
  return images;
}

const ColmapCamera& camera_of(const ColmapModel& model, uint32_t id) {
  for (const auto& camera : model.cameras) {
    if (camera.id == id) return camera;
  }
  throw Error(model.file("images") + ": an image uses camera " + std::to_string(id) + ", which " +
              model.file("cameras") + " does not list");
}

// The intrinsics and lenses of the cameras the images use, by camera id.
std::map<uint32_t, Intrinsics> used_intrinsics(const ColmapModel& model, const std::vector<const ColmapImage*>& images) {
  std::map<uint32_t, Intrinsics> intrinsics;
  for (const auto* image : images) {
    if (!intrinsics.count(image->camera_id)) {
      intrinsics.emplace(image->camera_id, camera_intrinsics(model, camera_of(model, image->camera_id)));
    }
  }
  return intrinsics;
}

// Every image's file in images_dir, PNG or JPEG, of its camera's size, checked before anything is written.
std::vector<fs::path> image_files(const ColmapModel& model, const std::vector<const ColmapImage*>& images,
                                  const std::string& images_dir, const std::map<uint32_t, Intrinsics>& intrinsics) {
  std::error_code ec;
  if (!fs::is_directory(images_dir, ec)) throw Error(images_dir + ": no such folder (expected the model's images)");
  std::vector<std::string> missing, other_type;
  std::vector<fs::path> paths(images.size());
  for (size_t i = 0; i < images.size(); ++i) {
    check_inside_folder(images_dir, images[i]->name, model.file("images"), "image " + std::to_string(images[i]->id) +
                                                                                "'s name");
    const ImageFile found = find_image(fs::path(images_dir) / images[i]->name, paths[i]);
    if (found == ImageFile::missing) missing.push_back(images[i]->name);
    if (found == ImageFile::other_type) other_type.push_back(images[i]->name);
  }
  if (!missing.empty()) {
    throw Error(images_dir + ": " + std::to_string(missing.size()) + " of the " + std::to_string(images.size()) +
                " images of " + model.file("images") + " are missing: " + name_list(missing));
  }
  if (!other_type.empty()) {
    throw Error(images_dir + ": " + name_list(other_type) +
                " are neither PNG nor JPEG and have no .png beside them: convert them (e.g. `mogrify -format png` in "
                "that folder) and import again");
  }
  for (size_t i = 0; i < images.size(); ++i) {
    const auto [width, height] = read_image_size(paths[i].string());
    const Intrinsics& in = intrinsics.at(images[i]->camera_id);
    if (width != in.width || height != in.height) {
      throw Error(paths[i].string() + ": the image is " + std::to_string(width) + "x" + std::to_string(height) +
                  " but its camera " + std::to_string(images[i]->camera_id) + " in " + model.file("cameras") +
                  " is " + std::to_string(in.width) + "x" + std::to_string(in.height) +
                  ": give the images the model was made from (after image_undistorter: its images folder)");
    }
  }
  return paths;
}

// Each image's camera-to-world pose (OpenGL axes), in COLMAP's world.
std::vector<Matrix34> camera_poses(const std::vector<const ColmapImage*>& images) {
  std::vector<Matrix34> poses;
  for (const auto* image : images) poses.push_back(colmap_camera_to_world(image->qvec, image->tvec));
  return poses;
}

std::vector<Camera> cameras_at(const std::vector<Matrix34>& poses) {
  std::vector<Camera> cameras(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) cameras[i].camera_to_world = poses[i];
  return cameras;
}

// Per image, the positive depths of the sparse points it sees (COLMAP units), in the order of `images`.
std::vector<std::vector<double>> point_depths(const ColmapModel& model, const std::vector<const ColmapImage*>& images) {
  std::unordered_map<uint32_t, size_t> index_of;
  for (size_t i = 0; i < images.size(); ++i) index_of[images[i]->id] = i;
  std::vector<std::vector<double>> depths(images.size());
  for (const auto& point : model.points) {
    for (uint32_t image_id : point.image_ids) {
      const auto found = index_of.find(image_id);
      if (found == index_of.end()) continue;  // an image left out
      const size_t i = found->second;
      const double depth = colmap_depth(*images[i], point.xyz);
      if (depth > 0.0) depths[i].push_back(depth);
    }
  }
  return depths;
}

}  // namespace

std::vector<size_t> points_in_front_counts(const ColmapModel& model) {
  std::vector<const ColmapImage*> images;
  for (const auto& image : model.images) images.push_back(&image);
  std::vector<size_t> counts;
  for (const auto& depths : point_depths(model, images)) counts.push_back(depths.size());
  return counts;
}

namespace {

// The near/far range of the points' depths (near_far_from_depths), in COLMAP units; refused when there is none and
// the options do not give both.
std::optional<DepthRange> point_depth_range(const ColmapModel& model, const std::vector<const ColmapImage*>& images,
                                            const ColmapImportOptions& options) {
  std::vector<std::vector<double>> depths = point_depths(model, images);  // sorted in place below
  const std::optional<DepthRange> range = near_far_from_depths(depths);
  if (!range && !(options.near && options.far)) {
    throw Error(model.file("points3D") +
                ": no point lies in front of an image that sees it, so near/far cannot be "
                "chosen from the points: give both (--near, --far)");
  }
  return range;
}

// The scene's origin and unit (see the header for why): the look-at point when it lies in front of every camera
// within near..far, else the points' per-axis median, else the mean camera centre; the median camera then sits
// kImportedCameraDistance from it. Fills result.centre, centre_rule and scale.
void choose_world_frame(const ColmapModel& model, const std::vector<Matrix34>& poses,
                        const std::optional<DepthRange>& range, ColmapImport& result) {
  const std::vector<Camera> cameras = cameras_at(poses);
  const std::optional<Vec3> look_at = closest_point_to_axes(cameras);
  bool look_at_inside = look_at.has_value();
  for (size_t i = 0; look_at && i < cameras.size(); ++i) {
    const double depth = dot(sub(*look_at, camera_center(cameras[i])), optical_axis(cameras[i]));
    const bool in_range = range ? depth >= range->near && depth <= range->far : depth > 0.0;
    look_at_inside = look_at_inside && in_range;
  }
  if (look_at_inside) {
    result.centre = *look_at;
    result.centre_rule = "look-at";
  } else if (!model.points.empty()) {
    std::vector<double> coordinate(model.points.size());
    for (int k = 0; k < 3; ++k) {
      for (size_t p = 0; p < model.points.size(); ++p) coordinate[p] = model.points[p].xyz[k];
      result.centre[k] = median(coordinate);
    }
    result.centre_rule = "points";
  } else {
    result.centre = {0, 0, 0};
    for (const auto& camera : cameras) {
      result.centre = add(result.centre, scale(camera_center(camera), 1.0 / static_cast<double>(cameras.size())));
    }
    result.centre_rule = "cameras";
  }
  std::vector<double> distances;
  for (const auto& camera : cameras) distances.push_back(length(sub(camera_center(camera), result.centre)));
  const double median_distance = median(distances);
  result.scale = median_distance > 0.0 ? kImportedCameraDistance / median_distance : 1.0;
}

// near/far in scene units: the options', else the points' range scaled. Fills result.near, far and
// near_far_from_points.
void choose_near_far(const std::optional<DepthRange>& range, const ColmapImportOptions& options,
                     ColmapImport& result) {
  result.near_far_from_points = !(options.near && options.far);
  result.near = options.near ? *options.near : range->near * result.scale;
  result.far = options.far ? *options.far : range->far * result.scale;
  if (!(result.near >= 0.0) || !(result.far > result.near)) {
    throw Error("near " + num(result.near) + ", far " + num(result.far) + " (scene units, the points give " +
                (range ? num(range->near * result.scale) + " .. " + num(range->far * result.scale) : "none") +
                "): need 0 <= near < far");
  }
}

// The file's `colmap` entry: where the model came from and how its world became the scene's.
io::Json provenance_json(const ColmapModel& model, const std::string& images_dir, const fs::path& out,
                         const std::optional<DepthRange>& range, const ColmapImport& result) {
  io::Json near_far = {
      {"rule",
       "per image, the 1st and 99th percentiles of the depths of the sparse points it sees (in front of it); "
       "near = 0.9 x the smallest, far = 1.1 x the largest"},
      {"from_points", result.near_far_from_points},
      {"percentiles", {100 * kDepthPercentileLow, 100 * kDepthPercentileHigh}},
      {"margins", {kNearMargin, kFarMargin}},
      {"images_with_points", range ? range->images : 0}};
  if (range) near_far["from_points_scene_units"] = {range->near * result.scale, range->far * result.scale};
  return {{"sparse_dir", relative_path(model.dir, out)},
          {"format", model.binary ? "binary" : "text"},
          {"images_dir", relative_path(images_dir, out)},
          {"points", model.points.size()},
          {"world",
           {{"transform",
             "x_scene = scale * (x_colmap - centre); rotations unchanged; camera axes OpenCV -> OpenGL (y and z "
             "negated)"},
            {"centre", {result.centre[0], result.centre[1], result.centre[2]}},
            {"centre_rule", result.centre_rule == "look-at"  ? "the point closest to every optical axis"
                            : result.centre_rule == "points" ? "the per-axis median of the sparse points"
                                                             : "the mean camera centre"},
            {"scale", result.scale},
            {"median_camera_distance", kImportedCameraDistance}}},
          {"near_far", near_far}};
}

// OUT/images/: a link to each registered photo, named so that name order is pose order (the LLFF loader lists the
// folder sorted); a copy where links are not possible. The dataset names only files inside its folder (a file_path
// out of it is refused when read: data/path_policy.hpp). Returns the links' names.
std::vector<std::string> link_images(const std::vector<fs::path>& image_paths, const fs::path& images_out) {
  std::error_code ec;
  fs::remove_all(images_out, ec);
  io::make_directories(images_out.string());
  std::vector<std::string> names;
  for (size_t i = 0; i < image_paths.size(); ++i) {
    char prefix[32];
    std::snprintf(prefix, sizeof(prefix), "%05zu_", i);
    const fs::path link = images_out / (prefix + image_paths[i].filename().string());
    const fs::path target = fs::absolute(image_paths[i]).lexically_normal();
    fs::create_symlink(fs::relative(target, images_out), link, ec);
    if (ec) fs::copy_file(target, link, fs::copy_options::overwrite_existing);
    names.push_back(link.filename().string());
  }
  return names;
}

// OUT/transforms.json: the intrinsics (global when one camera, else per frame), near/far, each frame's image (a link
// in OUT/images/) and pose in scene units, and the provenance.
void write_transforms(const ColmapModel& model, const std::vector<const ColmapImage*>& images,
                      const std::vector<fs::path>& image_paths, std::vector<Matrix34> poses,
                      const std::map<uint32_t, Intrinsics>& intrinsics, const std::string& images_dir,
                      const std::string& out_dir, const std::optional<DepthRange>& range, ColmapImport& result) {
  std::error_code ec;
  io::make_directories(out_dir);
  const fs::path out = fs::absolute(fs::path(out_dir), ec).lexically_normal();
  centre_and_scale(poses, result.centre, result.scale);
  io::Json root = io::Json::object();
  if (intrinsics.size() == 1) root.update(intrinsics_json(intrinsics.begin()->second));
  root["near"] = result.near;
  root["far"] = result.far;
  const std::vector<std::string> linked = link_images(image_paths, out / "images");
  io::Json frames = io::Json::array();
  for (size_t i = 0; i < images.size(); ++i) {
    io::Json frame = {{"file_path", "images/" + linked[i]},
                      {"transform_matrix", pose_to_json(poses[i])},
                      {"colmap_image_id", images[i]->id},
                      {"colmap_camera_id", images[i]->camera_id}};
    if (intrinsics.size() > 1) frame.update(intrinsics_json(intrinsics.at(images[i]->camera_id)));
    frames.push_back(std::move(frame));
  }
  root["frames"] = std::move(frames);
  root["colmap"] = provenance_json(model, images_dir, out, range, result);
  result.transforms_path = (out / "transforms.json").string();
  try {
    io::write_json(result.transforms_path, root);
  } catch (const io::Json::exception& e) {  // a folder name that is not UTF-8
    throw Error(result.transforms_path + ": cannot write it: " + e.what());
  }
}

// What the import used, for its report: the model's format and counts, and the cameras' models.
void describe_model(const ColmapModel& model, size_t images, const std::map<uint32_t, Intrinsics>& intrinsics,
                    ColmapImport& result) {
  result.binary = model.binary;
  result.images = images;
  result.cameras = intrinsics.size();
  result.points = model.points.size();
  for (const auto& entry : intrinsics) {
    const std::string name = camera_of(model, entry.first).model->name;
    if (std::find(result.camera_models.begin(), result.camera_models.end(), name) == result.camera_models.end()) {
      result.camera_models.push_back(name);
    }
  }
}

// ---- The LLFF layout (forward-facing captures) ----

// Why the cameras cannot be written as an LLFF capture (one camera, equal focal lengths, a centred principal point:
// poses_bounds.npy holds one focal length and the loader centres the principal point), or "" when they can.
std::string llff_misfit(const std::map<uint32_t, Intrinsics>& intrinsics) {
  if (intrinsics.size() != 1) return std::to_string(intrinsics.size()) + " cameras (LLFF holds one)";
  const Intrinsics& in = intrinsics.begin()->second;
  if (!in.lens.is_pinhole()) return std::string("a ") + lens_model_name(in.lens.model) + " lens (LLFF holds a pinhole)";
  if (std::abs(in.fx - in.fy) > 1e-6 * in.fx) return "focal lengths fx " + num(in.fx) + " and fy " + num(in.fy) + " differ";
  if (std::abs(in.cx - 0.5 * in.width) > 0.5 || std::abs(in.cy - 0.5 * in.height) > 0.5) {
    return "the principal point (" + num(in.cx) + ", " + num(in.cy) + ") is not the image centre";
  }
  return "";
}

// LLFF's bounds per image (its imgs2poses): the 0.1th and 99.9th percentile depth of the points the image sees.
std::vector<std::array<double, 2>> llff_bounds(const ColmapModel& model, const std::vector<const ColmapImage*>& images) {
  std::vector<std::vector<double>> depths = point_depths(model, images);  // sorted in place below
  std::vector<std::array<double, 2>> bounds;
  for (size_t i = 0; i < images.size(); ++i) {
    if (depths[i].size() < 2) {
      throw Error(model.file("points3D") + ": image " + images[i]->name + " sees " + std::to_string(depths[i].size()) +
                  " points in front of it; an LLFF capture needs its depth bounds from them (import with "
                  "--layout transforms and give --near/--far)");
    }
    std::sort(depths[i].begin(), depths[i].end());
    bounds.push_back({quantile(depths[i], 0.001), quantile(depths[i], 0.999)});
  }
  return bounds;
}

// OUT/poses_bounds.npy and OUT/images/ (see the header), poses in COLMAP's world (the LLFF loader recentres and
// rescales them itself).
void write_llff(const ColmapModel& model, const std::vector<const ColmapImage*>& images,
                const std::vector<fs::path>& image_paths, const std::vector<Matrix34>& poses,
                const Intrinsics& in, const std::string& out_dir, ColmapImport& result) {
  const auto bounds = llff_bounds(model, images);
  std::vector<double> rows;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Matrix34& m = poses[i];  // OpenGL axes: x right, y up, z backwards
    const double hwf[3] = {static_cast<double>(in.height), static_cast<double>(in.width), in.fx};
    // LLFF's columns: down (−y), right (x), backwards (z), position, (h, w, focal).
    for (int r = 0; r < 3; ++r) {
      for (double value : {-m[4 * r + 1], m[4 * r + 0], m[4 * r + 2], m[4 * r + 3], hwf[r]}) rows.push_back(value);
    }
    rows.push_back(bounds[i][0]);
    rows.push_back(bounds[i][1]);
  }
  io::make_directories(out_dir);
  link_images(image_paths, fs::path(out_dir) / "images");
  io::write_npy((fs::path(out_dir) / "poses_bounds.npy").string(), rows, {poses.size(), 17});
  result.dataset_path = out_dir;
  result.near = bounds[0][0];
  result.far = bounds[0][1];
  for (const auto& b : bounds) {
    result.near = std::min(result.near, b[0]);
    result.far = std::max(result.far, b[1]);
  }
  result.near_far_from_points = true;
}

// The layout the cameras call for, or the one asked for when it fits. Fills result.layout and layout_reason.
void choose_layout(const ColmapImportOptions& options, const std::vector<Matrix34>& poses,
                   const std::map<uint32_t, Intrinsics>& intrinsics, ColmapImport& result) {
  const bool forward = looks_forward(poses);
  const std::string misfit = llff_misfit(intrinsics);
  if (options.layout == ImportLayout::llff) {
    if (!misfit.empty()) throw Error("--layout llff: the cameras do not fit the LLFF layout: " + misfit);
    if (options.near || options.far) {
      throw Error("--near/--far apply to the transforms.json layout; an LLFF capture's bounds come from each image's "
                  "points (use --layout transforms to give them)");
    }
    result.layout = ImportLayout::llff;
    result.layout_reason = "asked for (--layout llff)";
  } else if (options.layout == ImportLayout::transforms_json) {
    result.layout = ImportLayout::transforms_json;
    result.layout_reason = "asked for (--layout transforms)";
  } else if (forward && misfit.empty() && !options.near && !options.far) {
    result.layout = ImportLayout::llff;
    result.layout_reason = "forward-facing cameras (every optical axis within 45 degrees of their mean): an LLFF "
                           "capture, trained in NDC with cylinders";
  } else {
    result.layout = ImportLayout::transforms_json;
    result.layout_reason = !forward ? "cameras looking from around the scene (a 360-degree capture)"
                           : !misfit.empty() ? "forward-facing, but " + misfit +
                                                   " (train takes it in NDC all the same when its cameras share one "
                                                   "projection)"
                                             : "forward-facing, but --near/--far given (they apply to transforms.json)";
  }
}

}  // namespace

ColmapImport import_colmap(const std::string& sparse_dir, const std::string& images_dir, const std::string& out_dir,
                           const ColmapImportOptions& options) {
  const ColmapModel model = read_colmap_model(sparse_dir);
  const std::vector<const ColmapImage*> images = images_by_name(model, options.leave_out);
  const std::map<uint32_t, Intrinsics> intrinsics = used_intrinsics(model, images);
  const std::vector<fs::path> image_paths = image_files(model, images, images_dir, intrinsics);
  const std::vector<Matrix34> poses = camera_poses(images);
  ColmapImport result;
  choose_layout(options, poses, intrinsics, result);
  if (result.layout == ImportLayout::llff) {
    write_llff(model, images, image_paths, poses, intrinsics.begin()->second, out_dir, result);
  } else {
    const std::optional<DepthRange> range = point_depth_range(model, images, options);
    choose_world_frame(model, poses, range, result);
    choose_near_far(range, options, result);
    write_transforms(model, images, image_paths, poses, intrinsics, images_dir, out_dir, range, result);
    result.dataset_path = result.transforms_path;
  }
  describe_model(model, images.size(), intrinsics, result);
  return result;
}

}  // namespace mipnerf::data
