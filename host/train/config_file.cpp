// Training config files through CLI11's TOML/INI reader, checked by the settings table.
#include "train/config_file.hpp"

#include <sstream>

#include <CLI/CLI.hpp>

#include "core/error.hpp"
#include "io/file.hpp"
#include "train/config.hpp"

namespace mipnerf::train {

std::map<std::string, std::string> parse_config_text(const std::string& text, const std::string& name) {
  std::vector<CLI::ConfigItem> items;
  try {
    std::istringstream input(text);
    items = CLI::ConfigTOML().from_config(input);
  } catch (const CLI::Error& e) {
    throw Error(name + ": " + e.what());
  }
  std::map<std::string, std::string> out;
  for (const auto& item : items) {
    if (item.name == "++" || item.name == "--") continue;  // CLI11's section markers
    const bool in_train = item.parents.size() == 1 && item.parents[0] == "train";
    if (!item.parents.empty() && !in_train) {
      throw Error(name + ": '" + item.fullname() + "' is outside a [train] table");
    }
    std::string value;
    for (const auto& input : item.inputs) value += (value.empty() ? "" : ",") + input;
    try {
      TrainConfig probe;
      set_value(probe, item.name, value);  // unknown names and bad values are refused here, by file
    } catch (const Error& e) {
      throw Error(name + ": " + e.what());
    }
    out[item.name] = value;
  }
  return out;
}

std::map<std::string, std::string> read_config_file(const std::string& path, const std::string& name) {
  return parse_config_text(io::read_file_text(path), name.empty() ? path : name);
}

}  // namespace mipnerf::train
