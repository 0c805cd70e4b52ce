// JSON files: malformed text reports the file, line and column; missing keys and wrong types name the key.
#include <doctest/doctest.h>

#include "support/data_fixtures.hpp"
#include "io/json.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

TEST_CASE("json: malformed JSON gives the file, line and column on one line") {
  const std::string text = "{\n  \"camera_angle_x\": 0.69,\n  \"frames\": [,]\n}\n";
  const std::string message = error_of([&] { io::parse_json(text, "scene/transforms_train.json"); });
  CHECK(contains(message, "scene/transforms_train.json: malformed JSON at line 3, column 14: "));
  CHECK(message.find('\n') == std::string::npos);
}

TEST_CASE("json: NaN written by Python is called out as a non-finite value") {
  const std::string message = error_of([] { io::parse_json("{\"m\": [1.0, NaN]}", "t.json"); });
  CHECK(contains(message, "t.json: malformed JSON at line 1, column 13"));
  CHECK(contains(message, "non-finite"));
}

TEST_CASE("json: missing keys and wrong types name the key and where it is") {
  const io::Json object = io::parse_json(R"({"a": "text", "b": 2.5, "c": [1]})", "f.json");
  CHECK(error_of([&] { io::require_key(object, "z", "f.json: frames[2]"); }) == "f.json: frames[2]: missing key 'z'");
  CHECK(error_of([&] { io::require_number(object, "a", "f.json"); }) == "f.json: 'a' must be a number, got string");
  CHECK(error_of([&] { io::require_string(object, "b", "f.json"); }) == "f.json: 'b' must be a string, got number");
  CHECK(error_of([&] { io::require_array(object, "a", "f.json"); }) == "f.json: 'a' must be an array, got string");
  CHECK(io::require_number(object, "b", "f.json") == 2.5);
  CHECK_FALSE(io::optional_number(object, "zz", "f.json").has_value());
}

TEST_CASE("json: write then read round trips, and a missing file is named") {
  test::TempDir dir;
  const io::Json value = {{"near", 2.0}, {"frames", {1, 2, 3}}};
  io::write_json(dir / "sub/out.json", value);
  CHECK(io::read_json(dir / "sub/out.json") == value);
  CHECK(error_of([&] { io::read_json(dir / "missing.json"); }) == dir / "missing.json" + ": no such file");
}
