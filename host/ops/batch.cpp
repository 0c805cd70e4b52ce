// Training-batch sampling: the one place batch_sample's arguments are set.
#include "ops/batch.hpp"

#include "cl/launch.hpp"

namespace mipnerf::ops {

BatchArrays::BatchArrays(ocl::Context& ctx, size_t rays)
    : rays(rays),
      camera_ids(ctx, rays, "camera_ids [R]"),
      pixel_ids(ctx, rays, "pixel_ids [R]"),
      target_rgb(ctx, 3 * rays, "target_rgb [R][3]"),
      lossmult(ctx, rays, "lossmult [R]") {}

size_t BatchArrays::bytes_for(size_t rays) {
  return 2 * rays * sizeof(uint32_t) + 4 * rays * sizeof(float);  // ids; target_rgb [R][3] and lossmult [R]
}

void batch_sample(ocl::Context& ctx, const data::DeviceDataset& dataset, const BatchOptions& options, uint32_t step,
                  BatchArrays& batch) {
  const char* name = "batch_sample";
  batch.camera_ids.require_size(batch.rays, name);
  batch.pixel_ids.require_size(batch.rays, name);
  batch.target_rgb.require_size(3 * batch.rays, name);
  batch.lossmult.require_size(batch.rays, name);
  ocl::BuildOptions build;
  build.define("BATCH_SINGLE_IMAGE", options.batching == Batching::single_image ? 1 : 0);
  auto& kernel = ctx.program({"common.cl", "batch.cl"}, build).kernel(name);
  ocl::set_args(kernel, name, cl_ulong{options.seed}, cl_uint{step}, dataset.pixel_offsets(),
                cl_uint{dataset.num_cameras()}, dataset.pixels_rgb(), dataset.cameras().packed(), batch.camera_ids,
                batch.pixel_ids, batch.target_rgb, batch.lossmult, static_cast<cl_uint>(batch.rays));
  ocl::launch_1d(ctx, kernel, batch.rays, name);
}

}  // namespace mipnerf::ops
