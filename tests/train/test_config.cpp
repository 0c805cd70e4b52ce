// Training configuration: presets and variants as data, parsing, validation, JSON round trip.
#include <doctest/doctest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "core/error.hpp"
#include "support/train_fixtures.hpp"
#include "train/config.hpp"
#include "train/model.hpp"

using namespace mipnerf;

TEST_CASE("config: the paper preset is exactly the paper's settings") {
  const auto c = train::resolve_config("paper", "mipnerf", {});
  CHECK(c.num_samples == 128);
  CHECK(c.num_levels == 2);
  CHECK(c.resample_padding == 0.01);
  CHECK(c.coarse_loss_mult == 0.1);
  CHECK(c.pos_min_deg == 0);
  CHECK(c.pos_max_deg == 16);  // L = 16 → 96 IPE features
  CHECK(c.view_max_deg == 4);  // degrees 0..3 + identity → 27 features
  CHECK(c.mlp_depth == 8);
  CHECK(c.mlp_width == 256);
  CHECK(c.mlp_skip == 4);
  CHECK(c.view_branch_width == 128);
  CHECK(c.density_activation == DensityActivation::softplus);
  CHECK(c.density_bias == -1.0);
  CHECK(c.rgb_padding == 0.001);
  CHECK(c.batch_size == 4096);
  CHECK(c.lr_init == 5e-4);
  CHECK(c.lr_final == 5e-6);
  CHECK(c.lr_warmup_steps == 2500);
  CHECK(c.lr_warmup_mult == 0.01);
  CHECK(c.background == Background::white);
  CHECK(c.pixel_center == 0.5);
  CHECK(c.single_mlp);
  CHECK(c.integrated_encoding);
}

TEST_CASE("config: order is defaults, preset, variant, explicit settings") {
  const auto c = train::resolve_config("tiny", "nerf", {{"pos_max_deg", "8"}, {"steps", "7"}});
  CHECK(c.num_samples == 16);                    // from the preset
  CHECK(c.variant == train::ModelFamily::nerf);  // from the variant
  CHECK(!c.single_mlp);
  CHECK(c.pos_identity);
  CHECK(c.pos_max_deg == 8);  // explicit beats the variant's 10
  CHECK(c.steps == 7);        // explicit beats the preset's 300
  for (const auto& [name, bundle] : train::presets()) {
    for (const auto& [variant, v] : train::variants()) {
      // A preset made for another family is refused by name (the fast preset is Zip-NeRF's).
      if (train::preset_variant(name) == "zipnerf" && variant != "zipnerf") {
        CHECK_THROWS_WITH_AS(train::resolve_config(name, variant, {}), doctest::Contains("--model zipnerf"), Error);
      } else if (name == "mipnerf360" && variant != "mipnerf") {
        // mip-NeRF 360's sampler takes the IPE of frustums: the rows without it (NeRF's, w/o IPE, the concatenated
        // PE, Zip-NeRF) are refused naming both; the others (w/o misc., two MLPs, no area loss) train.
        try {
          train::resolve_config(name, variant, {});
        } catch (const Error& e) {
          CHECK(std::string(e.what()).find("the mipnerf360 preset") != std::string::npos);
          CHECK(std::string(e.what()).find("--variant " + variant) != std::string::npos);
        }
      } else {
        CHECK_NOTHROW(train::resolve_config(name, variant, {}));
      }
    }
  }
}

TEST_CASE("config: Table 3's NeRF rows add one change each, and the concatenated PE is supplement section 7's") {
  const auto nerf = train::resolve_config("paper", "nerf", {});
  const auto area = train::resolve_config("paper", "nerf-area", {});
  const auto center = train::resolve_config("paper", "nerf-area-center", {});
  const auto misc = train::resolve_config("paper", "nerf-area-center-misc", {});
  // Each row differs from the one before in exactly its change.
  CHECK(train::differences(nerf, area) == std::vector<std::string>{"area_loss: false -> true"});
  CHECK(train::differences(area, center) == std::vector<std::string>{"pixel_center: 0 -> 0.5"});
  CHECK(train::differences(center, misc) == std::vector<std::string>{"density_activation: relu -> softplus",
                                                                     "density_bias: 0 -> -1",
                                                                     "rgb_padding: 0 -> 0.001"});
  // Still the NeRF baseline in everything else: points with PE, two networks, no blur or padding in resampling.
  CHECK(misc.variant == train::ModelFamily::nerf);
  CHECK(!misc.single_mlp);
  CHECK(misc.resample_padding == 0.0);
  const auto concat = train::resolve_config("paper", "mipnerf-concat-pe", {});
  CHECK(train::differences(train::resolve_config("paper", "mipnerf", {}), concat) ==
        std::vector<std::string>{"integrated_encoding: true -> false", "pos_max_deg: 16 -> 12", "cov_max_deg: 0 -> 2"});
  const auto spec = train::make_graph_spec(concat, false);
  CHECK(spec.levels.at(0).encoding == graph::Encoding::concat_pe);
  CHECK(spec.mlps.at(0).input_width == 96u);  // 72 + 24: IPE's width, as the paper pairs them
  // Covariance degrees without the concatenated PE are refused, naming what they need.
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"cov_max_deg", "2"}}),
                       doctest::Contains("cov_max_deg (the concatenated PE of the covariance) needs"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "nerf", {{"cov_max_deg", "2"}}),
                       doctest::Contains("needs integrated_encoding = false and the mipnerf model family"), Error);
}

TEST_CASE("config: unknown names and bad values are refused with what is accepted") {
  CHECK_THROWS_WITH_AS(train::resolve_config("nosuch", "mipnerf", {}), doctest::Contains("paper"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "nosuch", {}), doctest::Contains("nerf"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"nosuch", "1"}}),
                       doctest::Contains("unknown setting 'nosuch'"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"background", "green"}}),
                       doctest::Contains("white | black | none"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"batch_size", "12x"}}),
                       doctest::Contains("an integer"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"lr_init", "nan"}}), doctest::Contains("finite"),
                       Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"randomized", "maybe"}}),
                       doctest::Contains("true or false"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"batch_size", "0"}}),
                       doctest::Contains("batch_size"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "nerf", {{"num_samples", "7"}}), doctest::Contains("even"),
                       Error);
}

TEST_CASE("config: unit_viewdirs and density_noise default to the paper's Blender setup, parse and round-trip") {
  const auto paper = train::resolve_config("paper", "mipnerf", {});
  CHECK(paper.unit_viewdirs);
  CHECK(paper.density_noise == 0.0);
  const auto spec = train::make_graph_spec(paper, false);
  CHECK(spec.rays.unit_viewdirs);
  CHECK(spec.render.density_noise == 0.0f);
  const auto llff = train::resolve_config("tiny", "mipnerf", {{"unit_viewdirs", "false"}, {"density_noise", "1"}});
  CHECK_FALSE(llff.unit_viewdirs);
  CHECK(llff.density_noise == 1.0);
  const auto llff_spec = train::make_graph_spec(llff, false);  // carried into the ray and render options
  CHECK_FALSE(llff_spec.rays.unit_viewdirs);
  CHECK(llff_spec.render.density_noise == 1.0f);
  const auto back = train::from_json(train::to_json(llff), "llff.json");  // what render and eval read back
  CHECK(train::differences(llff, back).empty());
  CHECK_FALSE(back.unit_viewdirs);
  CHECK(back.density_noise == 1.0);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"density_noise", "-0.5"}}),
                       doctest::Contains("density_noise must be >= 0"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"unit_viewdirs", "maybe"}}),
                       doctest::Contains("unit_viewdirs"), Error);
  CHECK(train::find_setting("density_noise").group == "model");
  CHECK(train::find_setting("unit_viewdirs").group == "scene");
}

TEST_CASE("config: JSON round trip keeps every setting, and differences are listed") {
  auto c = train::resolve_config("quick", "mipnerf-no-ipe", {{"seed", "18446744073709551615"}, {"near", "0.25"}});
  const auto text = train::to_json(c);
  const auto back = train::from_json(text, "test.json");
  CHECK(train::differences(c, back).empty());
  CHECK(back.seed == 18446744073709551615ull);
  CHECK(back.near == 0.25);
  auto other = back;
  other.batch_size = 17;
  const auto diff = train::differences(c, other);
  REQUIRE(diff.size() == 1);
  CHECK(diff[0] == "batch_size: 512 -> 17");
  CHECK_THROWS_WITH_AS(train::from_json("{\"bogus\": 1}", "cfg.json"), doctest::Contains("cfg.json"), Error);
  CHECK_THROWS_WITH_AS(train::from_json("{oops", "cfg.json"), doctest::Contains("malformed"), Error);
}

namespace {

// parse(name(x)) == x for every value of E's name table, and no two values share a name.
template <typename E>
void check_names_round_trip() {
  std::set<std::string> seen;
  for (const auto& row : enum_names(E{})) {
    INFO("name " << row.name);
    CHECK(std::string(enum_name(row.value)) == row.name);
    const std::optional<E> back = enum_from_name<E>(enum_name(row.value));
    REQUIRE(back.has_value());
    CHECK(*back == row.value);
    CHECK(seen.insert(row.name).second);
  }
  CHECK(!enum_from_name<E>("bogus").has_value());
}

// Every enum-valued setting with the allowed values its errors and help must list.
const std::vector<std::pair<std::string, std::string>> kEnumSettings = {
    {"background", "white | black | none"},    {"ray_shape", "cone | cylinder"},
    {"batching", "all_images | single_image"}, {"variant", "mipnerf | nerf | zipnerf"},
    {"density_activation", "softplus | relu"}, {"sampler", "resample | proposal"},
};

}  // namespace

TEST_CASE("config: each enum's names round-trip, by type and through the settings table") {
  check_names_round_trip<Background>();
  check_names_round_trip<RayShape>();
  check_names_round_trip<DensityActivation>();
  check_names_round_trip<ops::Batching>();
  check_names_round_trip<train::ModelFamily>();
  check_names_round_trip<train::Variant>();
  check_names_round_trip<train::Sampler>();
  for (const auto& [setting_name, choices] : kEnumSettings) {
    const std::string name = setting_name, allowed = choices;  // INFO cannot capture a structured binding (C++17)
    for (size_t start = 0; start < allowed.size();) {
      const size_t end = std::min(allowed.find(" | ", start), allowed.size());
      const std::string value = allowed.substr(start, end - start);
      INFO("setting " << name << " = " << value);
      train::TrainConfig c;
      train::set_value(c, name, value);
      CHECK(train::get_value(c, name) == value);
      start = end + 3;
    }
  }
}

TEST_CASE("config: an unknown value of an enum setting is refused with the setting, the value and the allowed ones") {
  for (const auto& [name, choices] : kEnumSettings) {
    train::TrainConfig c;
    const std::string expected = "setting '" + name + "' = 'bogus': expected " + choices;
    CHECK_THROWS_WITH_AS(train::set_value(c, name, "bogus"), expected.c_str(), Error);
    CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{name, "bogus"}}), expected.c_str(), Error);
    // Names are exact: no case folding, no surrounding spaces.
    CHECK_THROWS_AS(train::set_value(c, name, " " + train::get_value(c, name)), Error);
    // The help line lists the same values, from the same table.
    CHECK(train::find_setting(name).help.rfind(choices + ": ", 0) == 0);
  }
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "nosuch", {}),
                       "unknown variant 'nosuch'; the variants are: mipnerf, mipnerf-concat-pe, mipnerf-no-area-loss, "
                       "mipnerf-no-ipe, mipnerf-no-misc, mipnerf-two-mlps, nerf, nerf-area, nerf-area-center, "
                       "nerf-area-center-misc, zipnerf",
                       Error);
  CHECK_THROWS_WITH_AS(train::find_setting("nosuch"), doctest::Contains("unknown setting 'nosuch'"), Error);
}

TEST_CASE("config: an unknown setting names the closest, not all of them, and where the list is") {
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"stpes", "10"}}),
                       "unknown setting 'stpes'; did you mean 'steps'? (mipnerf-cl train --help lists every setting)",
                       Error);
  // Since proposal sampling's settings, three names are as near to this slip.
  CHECK_THROWS_WITH_AS(train::find_setting("sampels"),
                       "unknown setting 'sampels'; did you mean 'num_samples', 'sampler' or 'proposal_samples'? "
                       "(mipnerf-cl train --help lists every setting)",
                       Error);
  CHECK_THROWS_WITH_AS(train::find_setting("xyzzy"),
                       "unknown setting 'xyzzy' (mipnerf-cl train --help lists every setting)", Error);
}

TEST_CASE("config: each setting's type for --help follows its member") {
  CHECK(train::find_setting("factor").type == "INT");
  CHECK(train::find_setting("steps").type == "INT");
  CHECK(train::find_setting("seed").type == "INT");
  CHECK(train::find_setting("lr_init").type == "FLOAT");
  CHECK(train::find_setting("spherify").type == "BOOL");
  CHECK(train::find_setting("background").type == "NAME");
  for (const auto& s : train::settings()) {
    INFO(s.name);
    CHECK((s.type == "INT" || s.type == "FLOAT" || s.type == "BOOL" || s.type == "NAME"));
  }
}

TEST_CASE("config: JSON spells enums as before, and records the --variant bundle beside the model family") {
  const auto c = train::resolve_config("tiny", "mipnerf-no-ipe", {});
  REQUIRE(c.variant_bundle.has_value());
  CHECK(*c.variant_bundle == train::Variant::mipnerf_no_ipe);
  const auto j = nlohmann::json::parse(train::to_json(c));
  CHECK(j.at("variant_bundle") == "mipnerf-no-ipe");
  CHECK(j.at("variant") == "mipnerf");  // the model family, as config.json has always said
  CHECK(j.at("background") == "white");
  CHECK(j.at("ray_shape") == "cone");
  CHECK(j.at("batching") == "all_images");
  CHECK(j.at("density_activation") == "softplus");
  CHECK(train::from_json(j.dump(), "config.json").variant_bundle == c.variant_bundle);
  for (const auto& entry : train::variants()) {
    const std::string& name = entry.first;  // INFO cannot capture a structured binding (C++17)
    INFO("variant " << name);
    const auto resolved = train::resolve_config("tiny", name, {});
    REQUIRE(resolved.variant_bundle.has_value());
    CHECK(enum_name(*resolved.variant_bundle) == name);
  }
  CHECK(train::resolve_config("tiny", "nerf", {}).variant == train::ModelFamily::nerf);
  // A record, not a setting: nothing but --variant sets it, and runs that differ only in it do not differ.
  CHECK_THROWS_WITH_AS(train::resolve_config("paper", "mipnerf", {{"variant_bundle", "nerf"}}),
                       doctest::Contains("unknown setting 'variant_bundle'"), Error);
  auto same_settings = c;
  same_settings.variant_bundle = train::Variant::mipnerf;
  CHECK(train::differences(c, same_settings).empty());
  auto bad = j;
  bad["variant_bundle"] = "mipnerf-no-everything";
  CHECK_THROWS_WITH_AS(train::from_json(bad.dump(), "cfg.json"),
                       "cfg.json: 'variant_bundle' = 'mipnerf-no-everything': expected mipnerf | mipnerf-concat-pe | "
                       "mipnerf-no-area-loss | mipnerf-no-ipe | mipnerf-no-misc | mipnerf-two-mlps | nerf | nerf-area "
                       "| nerf-area-center | nerf-area-center-misc | zipnerf",
                       Error);
}

// config.json of a tiny-preset mipnerf run exactly as commit 357d2e4 (before variant_bundle) wrote it.
const char* const kConfigBeforeVariantBundle = R"json({
  "background": "white",
  "factor": 1,
  "multiscale": false,
  "area_loss": true,
  "near": 0.0,
  "far": 0.0,
  "ray_shape": "cone",
  "lindisp": false,
  "batching": "all_images",
  "pixel_center": 0.5,
  "jitter_pixels": false,
  "variant": "mipnerf",
  "num_samples": 16,
  "num_levels": 2,
  "single_mlp": true,
  "integrated_encoding": true,
  "pos_min_deg": 0,
  "pos_max_deg": 10,
  "pos_identity": false,
  "view_dependence": true,
  "view_max_deg": 4,
  "density_activation": "softplus",
  "density_bias": -1.0,
  "rgb_padding": 0.001,
  "resample_padding": 0.01,
  "resample_blur": true,
  "mlp_depth": 4,
  "mlp_width": 64,
  "mlp_skip": 2,
  "view_branch_width": 32,
  "batch_size": 256,
  "steps": 300,
  "lr_init": 0.002,
  "lr_final": 0.0002,
  "lr_warmup_steps": 20,
  "lr_warmup_mult": 0.01,
  "grad_max_norm": 0.0,
  "coarse_loss_mult": 0.1,
  "randomized": true,
  "seed": 20200823,
  "chunk_rays": 0,
  "render_chunk_rays": 4096,
  "log_every": 25,
  "checkpoint_every": 100,
  "keep_checkpoints": 3,
  "max_bad_steps": 5,
  "val_views": 2
})json";

TEST_CASE("config: a configuration written before the variant was recorded loads, with the variant unknown") {
  const auto old = train::from_json(kConfigBeforeVariantBundle, "old/config.json");
  CHECK(!old.variant_bundle.has_value());
  const auto today = train::resolve_config("tiny", "mipnerf", {});
  CHECK(train::differences(old, today).empty());
  // Today's file is the old one plus the record, byte for byte: every other key and value is spelled as before.
  auto written = nlohmann::ordered_json::parse(train::to_json(today));
  CHECK(written.at("variant_bundle") == "mipnerf");
  written.erase("variant_bundle");
  // gemm_backend came later still (an execution setting); a configuration without it loads with its default, auto.
  CHECK(written.at("gemm_backend") == "auto");
  CHECK(old.gemm_backend == gemm::GemmBackend::automatic);
  written.erase("gemm_backend");
  // spherify (a scene setting for LLFF captures) too; without it a configuration loads with its default, false.
  CHECK(written.at("spherify") == false);
  CHECK(!old.spherify);
  written.erase("spherify");
  // cov_max_deg (the concatenated-PE variant's) too; without it a configuration loads with its default, 0 (off).
  CHECK(written.at("cov_max_deg") == 0);
  CHECK(old.cov_max_deg == 0);
  written.erase("cov_max_deg");
  // val_every (val scores during training) too; without it a configuration loads with its default, 0 (off).
  CHECK(written.at("val_every") == 0);
  CHECK(old.val_every == 0);
  written.erase("val_every");
  // multiscale_scales too; without it a configuration loads with the paper's 4.
  CHECK(written.at("multiscale_scales") == 4);
  CHECK(old.multiscale_scales == 4);
  written.erase("multiscale_scales");
  // unit_viewdirs and density_noise (the official forward-facing LLFF conventions) too; without them a configuration
  // loads with what every run before them trained with: unit view directions, no density noise.
  CHECK(written.at("unit_viewdirs") == true);
  CHECK(old.unit_viewdirs);
  written.erase("unit_viewdirs");
  CHECK(written.at("density_noise") == 0.0);
  CHECK(old.density_noise == 0.0);
  written.erase("density_noise");
  // Zip-NeRF's grid and Adam's β2 and ε too; without them a configuration loads with the defaults every earlier run
  // trained with (Adam's flax defaults; the grid settings play no part outside the zipnerf family; grid_multisample's
  // default, true, is what every Zip-NeRF run before it trained with).
  for (const char* name : {"grid_min", "grid_max", "grid_supersample", "grid_hash_log2", "grid_features", "grid_bound",
                           "grid_multisample", "grid_downweight", "grid_append_scale", "grid_weight_decay",
                           "grid_scale_mult", "adam_beta2", "adam_epsilon"}) {
    CHECK(written.contains(name));
    written.erase(name);
  }
  CHECK(old.adam_beta2 == 0.999);
  CHECK(old.adam_epsilon == 1e-8);
  // Zip-NeRF's proposal sampling too; without it a configuration loads with sampler = resample, what every earlier run
  // trained with (the proposal_* settings play no part then).
  CHECK(written.at("sampler") == "resample");
  CHECK(old.sampler == train::Sampler::resample);
  for (const char* name :
       {"sampler", "proposal_rounds", "proposal_samples", "proposal_grid_max", "anneal_slope", "interlevel_mult",
        "distortion_mult", "proposal_mlp_depth", "proposal_mlp_width", "dilation_bias", "dilation_mult"}) {
    CHECK(written.contains(name));
    written.erase(name);
  }
  // unbounded (a scene without bounds: contraction and the power ladder) too; without it a configuration loads with
  // false, what every earlier run trained with.
  CHECK(written.at("unbounded") == false);
  CHECK(!old.unbounded);
  written.erase("unbounded");
  // basis_subdivisions (the contracted IPE's directions, unbounded mipnerf only) loads as the official 2.
  CHECK(written.at("basis_subdivisions") == 2);
  CHECK(old.basis_subdivisions == 2);
  written.erase("basis_subdivisions");
  // mip-NeRF 360's training pieces (the mipnerf360 preset's) load as mip-NeRF's: no opaque background, the trunk's
  // width for the bottleneck, the squared error summed over channels.
  CHECK(written.at("opaque_background") == false);
  CHECK(written.at("bottleneck_width") == 0);
  CHECK(written.at("data_loss") == "mse");
  CHECK(written.at("charb_padding") == 0.001);
  CHECK(written.at("loss_channel_mean") == false);
  CHECK(!old.opaque_background);
  CHECK(old.bottleneck_width == 0);
  CHECK(old.data_loss == train::DataLoss::mse);
  CHECK(!old.loss_channel_mean);
  for (const char* key : {"opaque_background", "bottleneck_width", "data_loss", "charb_padding", "loss_channel_mean"}) {
    written.erase(key);
  }
  // The networks' initialisation and the shared proposal network (mip-NeRF 360 exactly) load as before: Glorot's
  // weights, a network per proposal round.
  CHECK(written.at("weight_init") == "glorot_uniform");
  CHECK(written.at("proposal_mlp_shared") == false);
  CHECK(old.weight_init == mlp::WeightInit::glorot_uniform);
  CHECK(!old.proposal_mlp_shared);
  written.erase("weight_init");
  written.erase("proposal_mlp_shared");
  CHECK(written.dump(2) == kConfigBeforeVariantBundle);
  // Written back, an old configuration stays without the key rather than claiming a variant it never recorded.
  CHECK(!nlohmann::json::parse(train::to_json(old)).contains("variant_bundle"));
}

// Proposal sampling (camp_zipnerf configs/zipnerf/360.gin; multinerf's mip-NeRF 360 for --model mipnerf): refused for
// the NeRF baseline and for mip-NeRF without IPE, with the setting and what to do; its settings checked; the spec it
// builds is the official Zip-NeRF pipeline's shape.
TEST_CASE("config: sampler=proposal is Zip-NeRF's and mip-NeRF 360's: refused elsewhere, its settings checked") {
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "nerf", {{"sampler", "proposal"}}),
                       doctest::Contains("keep sampler=resample, or train --model mipnerf or zipnerf"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"sampler", "proposal"}, {"integrated_encoding", "false"}}),
                       doctest::Contains("leave integrated_encoding=true"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"sampler", "proposal"}, {"proposal_mlp_width", "0"}}),
                       doctest::Contains("proposal_mlp_depth and _width must be positive"), Error);
  const auto config = train::resolve_config("tiny", "zipnerf", {{"sampler", "proposal"}});
  CHECK(config.proposal_rounds == 2);
  CHECK(config.proposal_samples == 64);
  CHECK(config.proposal_grid_max == 2048);
  CHECK(config.anneal_slope == 10.0);
  CHECK(config.interlevel_mult < 0);  // the model's official (below: 0.01 for Zip-NeRF)
  CHECK(config.distortion_mult == 0.0);  // off unless asked: the default runs are unchanged
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"proposal_rounds", "0"}, {"proposal_samples", "1"}, {"proposal_grid_max", "1000"}, {"distortion_mult", "-0.1"}};
  for (const auto& entry : refused) {
    const std::string name = entry.first, value = entry.second;  // INFO cannot capture a structured binding
    INFO(name << " = " << value);
    CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "zipnerf", {{"sampler", "proposal"}, {name, value}}),
                         doctest::Contains(name.c_str()), Error);
  }

  const auto spec = train::make_graph_spec(config, false);
  REQUIRE(spec.levels.size() == 3);
  REQUIRE(spec.grids.size() == 3);
  REQUIRE(spec.mlps.size() == 3);
  const int grid_max[3] = {512, 2048, config.grid_max};
  const float blur[2] = {0.03f, 0.003f};
  for (size_t l = 0; l < 3; ++l) {
    INFO("level " << l);
    const auto& level = spec.levels[l];
    CHECK(level.sampling == graph::Sampling::proposal);
    CHECK(level.grid_index == l);
    CHECK(level.mlp_index == l);
    CHECK(spec.grids[l].max_grid_size == grid_max[l]);
    CHECK(spec.grids[l].hash_table_size == spec.grids[2].hash_table_size);
    CHECK(spec.grids[l].features == (l < 2 ? 1 : config.grid_features));
    CHECK(spec.mlps[l].view_dependence == (l == 2));
    CHECK(spec.mlps[l].depth == static_cast<size_t>(config.mlp_depth));
    CHECK(spec.mlps[l].width == static_cast<size_t>(config.mlp_width));
    if (l < 2) {
      CHECK(level.role == graph::LevelRole::proposal);
      CHECK(level.new_samples == 64u);
      CHECK(level.interlevel.blur_halfwidth == blur[l]);
      CHECK(level.interlevel.kind == ops::InterlevelKind::spline);
      CHECK(level.interlevel.mult == 0.01f);
    } else {
      CHECK(level.role == graph::LevelRole::nerf);
      CHECK(level.new_samples == static_cast<size_t>(config.num_samples));
    }
  }
  CHECK(spec.sample_intervals.resample_padding == 0.0f);
  CHECK(spec.anneal_slope == 10.0f);
  // The resampled Zip-NeRF is unchanged: two levels through one network and one grid.
  const auto resampled = train::make_graph_spec(train::resolve_config("tiny", "zipnerf", {}), false);
  CHECK(resampled.levels.size() == 2);
  CHECK(resampled.grids.size() == 1);
  CHECK(resampled.mlps.size() == 1);
  CHECK(!resampled.has_proposal_levels());
  for (const auto& level : spec.levels) CHECK(level.distortion_mult == 0.0f);
  for (const auto& level : spec.levels) CHECK(level.dilation == 0.0f);  // camp_zipnerf dilates no histogram
}

// The distortion loss (mip-NeRF 360 eq. 15) is taken over the s-edges proposal sampling draws: asked for without it
// (any family, or Zip-NeRF's coarse/fine), one line says what to add; with it, only the NeRF level carries the weight.
TEST_CASE("config: distortion_mult needs sampler=proposal, and weights the NeRF level alone") {
  for (const char* family : {"mipnerf", "nerf", "zipnerf"}) {
    INFO("variant " << family);
    CHECK_THROWS_WITH_AS(train::resolve_config("tiny", family, {{"distortion_mult", "0.01"}}),
                         doctest::Contains("distortion_mult needs sampler=proposal"), Error);
  }
  const auto config = train::resolve_config("tiny", "zipnerf", {{"sampler", "proposal"}, {"distortion_mult", "0.01"}});
  const auto spec = train::make_graph_spec(config, false);
  REQUIRE(spec.levels.size() == 3);
  CHECK(spec.levels[0].distortion_mult == 0.0f);
  CHECK(spec.levels[1].distortion_mult == 0.0f);
  CHECK(spec.levels[2].distortion_mult == 0.01f);
  CHECK(spec.describe().find("distortion loss mult 0.01") != std::string::npos);
  // The graph's own rule, for specs built by hand: a proposal round, or a resampled last level, is refused.
  graph::GraphSpec on_round = spec;
  on_round.levels[0].distortion_mult = 0.01f;
  CHECK_THROWS_WITH_AS(on_round.validate(), doctest::Contains("only the last level takes the distortion loss"), Error);
}

// `unbounded` (a 360° capture's background): Zip-NeRF with proposal sampling and cones only, each refusal one line
// saying what to add; with it the grids contract into [−2, 2]³ (an explicit grid_bound wins), proposal sampling's s
// is spaced by the power ladder, and the data is loaded from near 0 to far 1e6 (explicit near and far win). Off, the
// spec and the load options are what they were.
TEST_CASE("config: unbounded contracts Zip-NeRF's grids, spaces proposal samples by the power ladder, from 0 to 1e6") {
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "nerf", {{"unbounded", "true"}}),
                       doctest::Contains("the nerf baseline has neither"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"unbounded", "true"}}),
                       doctest::Contains("unbounded needs sampler=proposal"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "zipnerf", {{"unbounded", "true"}}),
                       doctest::Contains("unbounded needs sampler=proposal"), Error);
  CHECK_THROWS_WITH_AS(
      train::resolve_config("tiny", "zipnerf", {{"unbounded", "true"}, {"sampler", "proposal"}, {"ray_shape", "cylinder"}}),
      doctest::Contains("unbounded needs ray_shape=cone"), Error);
  const auto off = train::resolve_config("tiny", "zipnerf", {{"sampler", "proposal"}});
  CHECK(!off.unbounded);
  const auto off_spec = train::make_graph_spec(off, false);
  CHECK(off_spec.ray_distance == RayDistance::linear);
  CHECK(!off_spec.zip.contract);
  CHECK(off_spec.zip.box_size == 3.0f);
  const auto off_load = train::load_options(off, test::small_scene(), {"train"}, 1);
  CHECK(!off_load.near.has_value());
  CHECK(!off_load.far.has_value());

  const auto on = train::resolve_config("tiny", "zipnerf", {{"sampler", "proposal"}, {"unbounded", "true"}});
  const auto spec = train::make_graph_spec(on, false);
  CHECK(spec.ray_distance == RayDistance::power_ladder);
  CHECK(spec.zip.contract);
  CHECK(spec.zip.box_min[0] == -2.0f);
  CHECK(spec.zip.box_size == 4.0f);
  CHECK(spec.describe().find("(power ladder s→t)") != std::string::npos);
  CHECK(spec.describe().find("points contracted (unbounded)") != std::string::npos);
  CHECK(off_spec.describe().find("power ladder") == std::string::npos);
  CHECK(off_spec.describe().find("contracted") == std::string::npos);
  const auto load = train::load_options(on, test::small_scene(), {"train"}, 1);
  REQUIRE(load.near.has_value());
  REQUIRE(load.far.has_value());
  CHECK(*load.near == 0.0);
  CHECK(*load.far == 1e6);
  const auto given = train::resolve_config(
      "tiny", "zipnerf",
      {{"sampler", "proposal"}, {"unbounded", "true"}, {"near", "0.1"}, {"far", "500"}, {"grid_bound", "2.5"}});
  const auto given_load = train::load_options(given, test::small_scene(), {"train"}, 1);
  CHECK(*given_load.near == 0.1);
  CHECK(*given_load.far == 500.0);
  CHECK(train::make_graph_spec(given, false).zip.box_size == 5.0f);
}

// `unbounded` with the mip-NeRF family is mip-NeRF 360's model (multinerf configs/360.gin): every level encodes its
// contracted frustums on the icosahedron's 21 directions, proposal sampling's s is spaced by the reciprocal, and the
// data is loaded from near 0.2 (the reciprocal needs one > 0) to far 1e6 (explicit near and far win); `far` past 1e18
// is refused (a frustum's variances overflow float32 there). Off, mip-NeRF's proposal spec is the IPE's.
TEST_CASE("config: unbounded mip-NeRF is mip-NeRF 360's contracted IPE, reciprocal spacing, from 0.2 to 1e6") {
  const auto off = train::resolve_config("tiny", "mipnerf", {{"sampler", "proposal"}});
  const auto off_spec = train::make_graph_spec(off, false);
  CHECK(off_spec.ray_distance == RayDistance::linear);
  for (const auto& level : off_spec.levels) CHECK(level.encoding == graph::Encoding::integrated);
  const auto on = train::resolve_config("tiny", "mipnerf", {{"sampler", "proposal"}, {"unbounded", "true"},
                                                           {"pos_max_deg", "12"}});
  const auto spec = train::make_graph_spec(on, false);
  CHECK(spec.ray_distance == RayDistance::reciprocal);
  for (const auto& level : spec.levels) CHECK(level.encoding == graph::Encoding::contracted_ipe);
  for (const auto& mlp : spec.mlps) CHECK(mlp.input_width == 504);
  CHECK(spec.describe().find("(reciprocal s→t)") != std::string::npos);
  CHECK(spec.describe().find("IPE of contracted frustums degrees 0..11 on 21 directions") != std::string::npos);
  CHECK(off_spec.describe().find("contracted") == std::string::npos);
  const auto load = train::load_options(on, test::small_scene(), {"train"}, 1);
  REQUIRE(load.near.has_value());
  REQUIRE(load.far.has_value());
  CHECK(*load.near == 0.2);
  CHECK(*load.far == 1e6);
  CHECK(load.world_around_cameras);
  const auto given = train::resolve_config(
      "tiny", "mipnerf", {{"sampler", "proposal"}, {"unbounded", "true"}, {"near", "0.5"}, {"far", "500"}});
  const auto given_load = train::load_options(given, test::small_scene(), {"train"}, 1);
  CHECK(*given_load.near == 0.5);
  CHECK(*given_load.far == 500.0);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"far", "1e19"}}),
                       doctest::Contains("beyond 1e18"), Error);
  // basis_subdivisions 1: the icosahedron's 6 directions, 2·12·6 = 144 features for every level's network.
  const auto six = train::resolve_config(
      "tiny", "mipnerf", {{"sampler", "proposal"}, {"unbounded", "true"}, {"pos_max_deg", "12"}, {"basis_subdivisions", "1"}});
  const auto six_spec = train::make_graph_spec(six, false);
  for (const auto& mlp : six_spec.mlps) CHECK(mlp.input_width == 144);
  CHECK(six_spec.describe().find("on 6 directions") != std::string::npos);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"basis_subdivisions", "0"}}),
                       doctest::Contains("basis_subdivisions must be 1 to 8"), Error);
}

TEST_CASE("config: the mipnerf360 preset is multinerf's configs/360.gin, and its new settings reach the graph") {
  const auto c = train::resolve_config("mipnerf360", "mipnerf", {});
  CHECK(c.sampler == train::Sampler::proposal);
  CHECK(c.unbounded);
  CHECK(c.opaque_background);
  CHECK(c.num_samples == 32);
  CHECK(c.proposal_rounds == 2);
  CHECK(c.proposal_samples == 64);
  CHECK(c.batch_size == 16384);
  CHECK(c.steps == 250000);
  CHECK(c.lr_init == 2e-3);
  CHECK(c.lr_final == 2e-5);
  CHECK(c.lr_warmup_steps == 512);
  CHECK(c.adam_epsilon == 1e-6);
  CHECK(c.grad_max_norm == 1e-3);
  CHECK(c.distortion_mult == 0.01);
  const auto spec = train::make_graph_spec(c, false);
  // multinerf's Model builds one PropMLP and calls it in both rounds: two networks, the rounds' the first.
  REQUIRE(spec.mlps.size() == 2);
  REQUIRE(spec.levels.size() == 3);
  CHECK(spec.levels[0].mlp_index == 0);
  CHECK(spec.levels[1].mlp_index == 0);
  CHECK(spec.levels[2].mlp_index == 1);
  CHECK(spec.mlps[0].depth == 4);
  CHECK(spec.mlps[0].width == 256);
  CHECK(!spec.mlps[0].view_dependence);
  // MLP.weight_init = 'he_uniform' in multinerf, for every network.
  for (const auto& m : spec.mlps) CHECK(m.weight_init == mlp::WeightInit::he_uniform);
  const auto& nerf = spec.mlps[1];
  CHECK(nerf.depth == 8);
  CHECK(nerf.width == 1024);
  CHECK(nerf.skip_layer == 4);
  CHECK(nerf.bottleneck_width == 256);
  CHECK(nerf.view_branch_width == 128);
  CHECK(nerf.input_width == 504);
  CHECK(spec.render.opaque_background);
  CHECK(spec.loss.charbonnier_padding == 0.001f);
  CHECK(spec.loss.channel_mean);
  // The other presets keep mip-NeRF's loss, background and bottleneck: the paper path is unchanged.
  for (const char* preset : {"paper", "quick", "small", "tiny"}) {
    CAPTURE(preset);
    const auto other = train::make_graph_spec(train::resolve_config(preset, "mipnerf", {}), false);
    CHECK(!other.render.opaque_background);
    CHECK(other.loss.charbonnier_padding == 0.0f);
    CHECK(!other.loss.channel_mean);
    CHECK(other.mlps[0].bottleneck_width == other.mlps[0].width);
    CHECK(other.mlps[0].weight_init == mlp::WeightInit::glorot_uniform);
  }
  // The scene-chosen mip-NeRF 360 of the quick preset keeps a network per round (measured so) unless told.
  const auto quick_360 = train::make_graph_spec(
      train::resolve_config("quick", "mipnerf", {{"sampler", "proposal"}, {"unbounded", "true"}}), false);
  CHECK(quick_360.mlps.size() == 3);
  CHECK_THROWS_WITH_AS(
      train::resolve_config("tiny", "zipnerf", {{"sampler", "proposal"}, {"proposal_mlp_shared", "true"}}),
      doctest::Contains("proposal_mlp_shared is mip-NeRF 360's"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"data_loss", "charbonnier"}, {"charb_padding", "0"}}),
                       doctest::Contains("charb_padding > 0"), Error);
  CHECK_THROWS_WITH_AS(train::resolve_config("tiny", "mipnerf", {{"bottleneck_width", "-1"}}),
                       doctest::Contains("bottleneck_width must be >= 0"), Error);
}
