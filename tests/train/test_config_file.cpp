// Training config files (train/config_file): TOML/INI text → settings, every name and value checked by the table,
// errors naming the file.
#include <doctest/doctest.h>

#include "support/data_fixtures.hpp"
#include "train/config_file.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

TEST_CASE("config file: top-level settings and a [train] table, comments, arrays joined by commas") {
  const auto settings = train::parse_config_text(
      "# a comment\nsteps = 4\n; another\n[train]\nbackground = \"black\"\nbatch_size = [64]\n", "my.toml");
  CHECK(settings.size() == 3);
  CHECK(settings.at("steps") == "4");
  CHECK(settings.at("background") == "black");
  CHECK(settings.at("batch_size") == "64");
}

TEST_CASE("config file: unknown names, bad values and other tables are refused, naming the file") {
  CHECK(contains(error_of([] { train::parse_config_text("bogus_key = 1\n", "--config a.toml"); }),
                 "--config a.toml: unknown setting 'bogus_key'"));
  CHECK(contains(error_of([] { train::parse_config_text("num_samples = 12x\n", "b.toml"); }),
                 "b.toml: setting 'num_samples' = '12x': expected an integer"));
  CHECK(contains(error_of([] { train::parse_config_text("[model]\nnum_samples = 8\n", "c.toml"); }),
                 "c.toml: 'model.num_samples' is outside a [train] table"));
  CHECK(contains(error_of([] { train::read_config_file("nowhere.toml", "--config nowhere.toml"); }),
                 "nowhere.toml: no such file"));
}
