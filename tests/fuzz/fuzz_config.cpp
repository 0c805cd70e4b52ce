// Fuzz target: a training config file (mipnerf-cl train --config FILE, TOML/INI), parsed by
// train::parse_config_text; what it accepts must resolve into a configuration or be refused with an Error.
#include <string>

#include "fuzz_support.hpp"
#include "train/config.hpp"
#include "train/config_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::expect_only_errors("fuzz.toml", [&] {
    const auto settings = train::parse_config_text(text, "fuzz.toml");
    try {
      train::resolve_config("tiny", "mipnerf", settings);  // a combination may still be invalid: an Error
    } catch (const Error& e) {
      fuzz::check(std::string(e.what()).find('\n') == std::string::npos, "a configuration error of several lines");
    }
  });
  return 0;
}
