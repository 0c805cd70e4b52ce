// Enum name tables (core/enum_names.hpp) and the stage enums' numbering, which the kernels receive as -D defines.
#include <doctest/doctest.h>

#include "core/error.hpp"
#include "core/stage_options.hpp"

using namespace mipnerf;

TEST_CASE("enum names: the stage enums keep the kernels' numbering") {
  // common.cl / render.cl: BACKGROUND 0 none, 1 black, 2 white; RAY_SHAPE 0 cone, 1 cylinder;
  // DENSITY_ACTIVATION 0 softplus, 1 relu. The host passes static_cast<int>(value) as the define.
  CHECK(static_cast<int>(Background::none) == 0);
  CHECK(static_cast<int>(Background::black) == 1);
  CHECK(static_cast<int>(Background::white) == 2);
  CHECK(static_cast<int>(RayShape::cone) == 0);
  CHECK(static_cast<int>(RayShape::cylinder) == 1);
  CHECK(static_cast<int>(DensityActivation::softplus) == 0);
  CHECK(static_cast<int>(DensityActivation::relu) == 1);
}

TEST_CASE("enum names: parse, print and the list of choices come from one table") {
  for (const auto& row : enum_names(Background{})) {
    const std::optional<Background> back = enum_from_name<Background>(enum_name(row.value));
    REQUIRE(back.has_value());
    CHECK(*back == row.value);
  }
  CHECK(enum_choices<Background>() == "white | black | none");
  CHECK(enum_choices<RayShape>(", ") == "cone, cylinder");
  CHECK(std::string(enum_name(DensityActivation::relu)) == "relu");
  CHECK(!enum_from_name<Background>("White").has_value());  // exact names only
  CHECK(!enum_from_name<RayShape>("").has_value());
  CHECK(has_enum_names_v<Background>);
  CHECK(!has_enum_names_v<int>);
  // A value outside the table can only come from a cast: printing it is refused rather than guessed.
  CHECK_THROWS_WITH_AS(enum_name(static_cast<Background>(7)), doctest::Contains("value 7"), Error);
}
