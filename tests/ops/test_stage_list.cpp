// The stage list (host/ops/stage_list) that the specialisation test and the kernel benchmark share: well formed,
// and tied to the kernel files, so a kernel added to a listed file cannot ship untimed and unlisted.
#include <doctest/doctest.h>

#include <regex>
#include <set>
#include <string>

#include "cl/kernel_sources.hpp"
#include "ops/stage_list.hpp"

using namespace mipnerf;

namespace {

// The file a stage's program adds last (its own: "gaussian.cl + encode.cl" → "encode.cl").
std::string own_file(const ops::StageDescription& stage) {
  const size_t plus = stage.program.rfind(" + ");
  return plus == std::string::npos ? stage.program : stage.program.substr(plus + 3);
}

// Every `__kernel void name(` in a kernel file.
std::set<std::string> kernels_in(const std::string& file) {
  const std::string text(ocl::kernel_source(file));
  static const std::regex kernel(R"(__kernel\s+void\s+(\w+)\s*\()");
  std::set<std::string> names;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), kernel); it != std::sregex_iterator(); ++it) {
    names.insert((*it)[1]);
  }
  return names;
}

}  // namespace

TEST_CASE("stage list: seven stages, thirteen kernels, unique names, each with a specialisation") {
  const auto& stages = ops::ray_math_stages();
  std::set<std::string> stage_names, kernel_names, rows;
  size_t kernels = 0;
  for (const auto& stage : stages) {
    INFO("stage " << stage.name);
    CHECK(stage_names.insert(stage.name).second);
    CHECK_FALSE(stage.kernels.empty());
    CHECK_FALSE(stage.variants.empty());
    std::set<std::string> variant_names;
    for (const auto& variant : stage.variants) CHECK(variant_names.insert(variant.name).second);
    for (const auto& kernel : stage.kernels) {
      CHECK(kernel_names.insert(kernel.kernel).second);
      CHECK(rows.insert(kernel.row()).second);
      ++kernels;
    }
  }
  CHECK(stages.size() == 7);
  CHECK(kernels == 13);
  CHECK(stages.front().name == "rays");  // data-flow order: the rays first, resampling (next level) last
  CHECK(stages.back().name == "resample");
}

TEST_CASE("stage list: rows, units and item counts") {
  const ops::StageKernel render{ops::KernelId::render_fwd, "render_fwd", ops::ItemUnit::samples, "white"};
  CHECK(render.row() == "render_fwd (white)");
  CHECK(ops::StageKernel{ops::KernelId::activations_fwd, "activations_fwd", ops::ItemUnit::samples, ""}.row() ==
        "activations_fwd");
  // R = 5 rays × N = 3 intervals: 4 edges a ray.
  CHECK(ops::items(ops::ItemUnit::rays, 5, 3) == 5);
  CHECK(ops::items(ops::ItemUnit::edges, 5, 3) == 20);
  CHECK(ops::items(ops::ItemUnit::intervals, 5, 3) == 15);
  CHECK(ops::items(ops::ItemUnit::samples, 5, 3) == 15);
  CHECK(std::string(ops::unit_name(ops::ItemUnit::edges)) == "edges");
  CHECK(std::string(ops::unit_name(ops::ItemUnit::intervals)) == "intervals");
}

TEST_CASE("stage list: every listed kernel is in its stage's file, and every kernel of those files is listed") {
  // The NeRF baseline's kernels without specialisations of their own, the concatenated-PE variant's kernel, the
  // render's weights-only forward and backward and the encodings' per-(row, axis) kernels (see stage_list.hpp),
  // checked elsewhere.
  const std::set<std::string> unlisted = {"sample_merge_fwd",
                                          "gaussian_points_fwd",
                                          "gaussian_concat_pe_fwd",
                                          "render_raw_weights_fwd",
                                          "render_raw_weights_bwd",
                                          "gaussian_ipe_axis_fwd",
                                          "ipe_axis_fwd",
                                          "pe_axis_fwd"};
  std::set<std::string> listed;
  for (const auto& stage : ops::ray_math_stages()) {
    const auto in_file = kernels_in(own_file(stage));
    for (const auto& kernel : stage.kernels) {
      CHECK_MESSAGE(in_file.count(kernel.kernel) == 1, kernel.kernel << " not in " << own_file(stage));
      listed.insert(kernel.kernel);
    }
  }
  for (const auto& stage : ops::ray_math_stages()) {
    for (const auto& kernel : kernels_in(own_file(stage))) {
      CHECK_MESSAGE((listed.count(kernel) == 1 || unlisted.count(kernel) == 1), kernel << " is not in the list");
    }
  }
}

TEST_CASE("stage list: the benchmark's options are the paper's Blender configuration") {
  const ops::RayMathOptions o;
  CHECK(o.rays.ray_shape == RayShape::cone);
  CHECK(o.sample.randomized);
  CHECK_FALSE(o.sample.lindisp);
  CHECK(o.render.background == Background::white);
  CHECK(o.activation.density == DensityActivation::softplus);
  CHECK(o.ipe.ipe_width() == 96);
  CHECK(o.view.pe_width() == 27);
}
