// Training settings from a TOML/INI file (`mipnerf-cl train --config FILE`): `name = value` lines at the top level
// or in a [train] table, every name and value checked by the settings table (train::set_value) as it is read.
#pragma once

#include <map>
#include <string>

namespace mipnerf::train {

// The settings `text` gives, name → value as set_value takes it (a TOML array becomes its items joined by commas).
// `name` says where the text came from in messages ("--config my.toml"). Throws mipnerf::Error "<name>: ..." for
// anything it cannot use: an unknown setting, a bad value, a key outside a [train] table, text CLI11's parser refuses.
std::map<std::string, std::string> parse_config_text(const std::string& text, const std::string& name);

// The same for the file at `path`; messages start with `name` (e.g. "--config PATH"), or the path when it is empty.
std::map<std::string, std::string> read_config_file(const std::string& path, const std::string& name = {});

}  // namespace mipnerf::train
