// The fixed part of a training memory plan: summed from each owner's bytes_for, which must match what the owner
// allocates (the camera stride of the device layout included).
#include <doctest/doctest.h>

#include "core/camera.hpp"
#include "data/device_dataset.hpp"
#include "mlp/adam.hpp"
#include "mlp/network.hpp"
#include "ops/batch.hpp"
#include "support/test_context.hpp"
#include "support/train_fixtures.hpp"
#include "train/config.hpp"
#include "train/memory_plan.hpp"
#include "train/model.hpp"

using namespace mipnerf;

TEST_CASE("memory plan: each owner's bytes_for is what it allocates, and the fixed bytes are their sum") {
  auto& ctx = test::test_context();
  const auto dataset = data::load_dataset(test::small_scene(), {});
  const data::Split& split = dataset.split("train");
  const data::DeviceDataset device_data(ctx, split);
  CHECK(device_data.cameras().packed().size() == split.num_images() * camera_layout::stride);  // 24 floats a camera, not 32
  CHECK(data::DeviceDataset::bytes_for(split) ==
        device_data.cameras().packed().bytes() + device_data.pixels_rgb().bytes() + device_data.pixel_offsets().bytes());

  const size_t batch_rays = 96;
  const ops::BatchArrays batch(ctx, batch_rays);
  CHECK(ops::BatchArrays::bytes_for(batch_rays) ==
        batch.camera_ids.bytes() + batch.pixel_ids.bytes() + batch.target_rgb.bytes() + batch.lossmult.bytes());

  const auto config = train::resolve_config("tiny", "nerf", {});  // two networks
  const auto spec = train::make_graph_spec(config, false);
  REQUIRE(spec.mlps.size() == 2);
  size_t networks = 0;
  for (const auto& network_config : spec.mlps) {
    const auto network_owner = mlp::make_network(ctx, network_config, gemm::GemmBackend::automatic);
    const mlp::Network& network = *network_owner;
    CHECK(mlp::Network::bytes_for(network_config) == network.params().bytes() + network.grads().bytes());
    const size_t n = network.parameter_count();
    // Two moments, plus the norm reduction's partial sums and non-finite counts (at most 1024 slices each).
    CHECK(mlp::Adam::bytes_for(n) == 2 * n * sizeof(float) + 1024 * (sizeof(float) + sizeof(cl_uint)));
    networks += mlp::Network::bytes_for(network_config) + mlp::Adam::bytes_for(n);
  }
  CHECK(mlp::Adam::bytes_for(10) == 2 * 10 * sizeof(float) + 10 * (sizeof(float) + sizeof(cl_uint)));
  const train::FixedBytes fixed = train::training_fixed_bytes(split, spec, batch_rays);
  CHECK(fixed.data == data::DeviceDataset::bytes_for(split));
  CHECK(fixed.batch == ops::BatchArrays::bytes_for(batch_rays));
  CHECK(fixed.networks == networks);
  CHECK(fixed.largest_buffer == device_data.pixels_rgb().bytes());  // the split's pixels: its biggest buffer
  CHECK(data::DeviceDataset::largest_buffer_for(split) == device_data.pixels_rgb().bytes());
}
