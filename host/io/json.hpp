// JSON files through nlohmann/json: reading with errors that give the file and the position, atomic
// writing, and typed access to fields with messages that say which key of which file is wrong.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace mipnerf::io {

using Json = nlohmann::json;

// Parses `path`. Throws mipnerf::Error "<path>: no such file" or
// "<path>: malformed JSON at line L, column C: <reason>".
Json read_json(const std::string& path);
// Same for text already in memory; `name` is used in messages.
Json parse_json(const std::string& text, const std::string& name);

// Writes `value` (indented) atomically.
void write_json(const std::string& path, const Json& value, int indent = 2);

// Typed field access. `where` names the object for messages, e.g. "lego/transforms_train.json: frames[3]".
// Missing keys and wrong types throw mipnerf::Error "<where>: missing key 'k'" / "<where>: 'k' must be a
// number, got string".
const Json& require_key(const Json& object, const std::string& key, const std::string& where);
const Json& require_object(const Json& value, const std::string& where);
double require_number(const Json& object, const std::string& key, const std::string& where);
std::optional<double> optional_number(const Json& object, const std::string& key, const std::string& where);
std::string require_string(const Json& object, const std::string& key, const std::string& where);
const Json& require_array(const Json& object, const std::string& key, const std::string& where);
// A JSON value's type for messages: "string", "number", "array", ...
std::string json_type_name(const Json& value);

}  // namespace mipnerf::io
