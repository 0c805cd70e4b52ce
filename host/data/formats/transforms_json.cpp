// A single transforms.json with every frame (instant-ngp and nerfstudio write them; so does `dataset import-colmap`):
// intrinsics fl_x, fl_y, cx, cy, w, h globally or per frame; every 8th frame held out (detail::parse_transforms_json).
#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "data/formats/formats.hpp"
#include "data/formats/llff_capture.hpp"
#include "data/image.hpp"

namespace mipnerf::data {
namespace {

bool detect(const std::filesystem::path& path, bool is_file) {
  if (is_file) return path.extension() == ".json" && path.filename() != "metadata.json";
  return std::filesystem::is_regular_file(path / "transforms.json");
}

std::vector<detail::SplitSpec> parse(const std::string& path, const LoadOptions& options) {
  return detail::parse_transforms_json(format_file(path, "transforms.json"), options);
}

bool same_projection(const IntrinsicsSpec& a, const IntrinsicsSpec& b) {
  return a.focal_x_px == b.focal_x_px && a.focal_y_px == b.focal_y_px && a.center_x_px == b.center_x_px &&
         a.center_y_px == b.center_y_px && a.width_px == b.width_px && a.height_px == b.height_px &&
         a.camera_angle_x == b.camera_angle_x && a.camera_angle_y == b.camera_angle_y;
}

// Photos taken all around (what `dataset from-photos` writes here for a capture that is not forward-facing) or
// forward: the poses alone tell, from every frame of the file. A forward-facing capture trains in NDC when the file
// gives its depths and one projection (a lens may differ: it bends rays within one frustum).
void add_traits(const std::string& path, const LoadOptions& options, SceneTraits& traits) {
  LoadOptions every_frame = options;
  every_frame.splits = {};
  every_frame.holdout_every = 0;
  every_frame.world_around_cameras = false;
  every_frame.forward_facing_ndc = false;
  every_frame.log = nullptr;
  std::vector<Matrix34> poses;
  bool one_projection = true, positive_near = true;
  const IntrinsicsSpec* first = nullptr;
  const auto splits = parse(path, every_frame);
  for (const auto& split : splits) {
    for (const auto& frame : split.frames) {
      poses.push_back(frame.camera_to_world);
      positive_near = positive_near && frame.near > 0.0;
      if (first == nullptr) first = &frame.intrinsics;
      one_projection = one_projection && same_projection(*first, frame.intrinsics);
    }
  }
  traits.all_around = !poses.empty() && !looks_forward(poses);
  traits.forward_facing = !poses.empty() && !traits.all_around;
  if (!detail::has_near_far(io::read_json(format_file(path, "transforms.json")))) {
    traits.ndc_blocker = "the file gives no near/far";
  } else if (!positive_near) {
    traits.ndc_blocker = "its near is not a positive depth (near 0: NDC bounds, as a render of an NDC run writes?)";
  } else if (!one_projection) {
    traits.ndc_blocker = "its frames differ in focal length, principal point or image size";
  }
}

SceneEffects effects(const SceneTraits& traits) { return object_or_photo_effects(traits, "transforms.json"); }

// A forward-facing capture trained in NDC: the official spiral around its cameras in the NDC world, through a pinhole
// camera of the first frame's projection (a lens bends rays within that frustum; the video is the undistorted view).
FormatRenderPath render_path(const std::string& path, const LoadOptions& options, int frames) {
  const std::string file = format_file(path, "transforms.json");
  if (!options.forward_facing_ndc) {
    throw Error(file + ": --path spiral follows a forward-facing capture trained in NDC (ray_shape = cylinder), as "
                       "an LLFF capture's; this run casts world rays: use --path orbit, or --path FILE for a camera path");
  }
  if (frames < 1) throw Error("the render path needs at least one frame");
  const detail::NdcFrames ndc = detail::ndc_frames(io::read_json(file), file, options);
  std::vector<Matrix34> poses;
  for (const auto& frame : ndc.frames) poses.push_back(frame.camera_to_world);
  const detail::FrameSpec& first = ndc.frames.front();
  const ImageSize size = read_image_size(first.image_path);
  Camera camera;
  resolve_intrinsics(first.intrinsics, size.width, size.height, camera, first.where);
  const bool had_lens = !camera.lens.is_pinhole();
  camera.lens = Lens{};
  // The size the loader trains at.
  const uint32_t factor = std::max<uint32_t>(1, options.factor);
  if (camera.width_px < factor || camera.height_px < factor) {
    throw Error(first.image_path + ": smaller than factor " + std::to_string(factor) + "; use a smaller factor");
  }
  camera = camera_at_factor(camera, factor);
  camera.near = first.near;
  camera.far = first.far;
  camera.lossmult = 1.0;
  FormatRenderPath out;
  for (const Matrix34& pose : spiral_poses(poses, ndc.near_depth, ndc.far_depth, frames)) {
    for (double v : pose) {
      if (!std::isfinite(v)) {
        throw Error(file + ": no spiral for this capture: its cameras' positions or up vectors are degenerate (a "
                           "zero-length axis); render its views with --split instead");
      }
    }
    camera.camera_to_world = pose;
    out.cameras.push_back(camera);
  }
  out.description = "the spiral of " + file + (had_lens ? " (through a pinhole of its focal length: undistorted)" : "");
  out.kind = "transforms.json spiral";
  return out;
}

}  // namespace

const FormatReader kTransformsJsonFormat = {
    DatasetFormat::transforms_json, "transforms.json", detect, parse, add_traits, effects, render_path,
    /*scales_on_disk=*/false, /*pyramid_source=*/true, /*ndc_bounds=*/false};

}  // namespace mipnerf::data
