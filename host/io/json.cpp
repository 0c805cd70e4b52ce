// JSON reading and writing with messages that name the file, the position and the key.
#include "io/json.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/file.hpp"

namespace mipnerf::io {
namespace {

// nlohmann's message without its "[json.exception.parse_error.101] " prefix and without the "parse error at
// line 1, column 2: " it repeats (we give the position ourselves), on one line.
std::string parse_reason(const std::string& what) {
  std::string reason = what;
  const auto bracket = reason.find("] ");
  if (reason.rfind("[json.exception.", 0) == 0 && bracket != std::string::npos) reason = reason.substr(bracket + 2);
  const auto colon = reason.find(": ");
  if (reason.rfind("parse error", 0) == 0 && colon != std::string::npos) reason = reason.substr(colon + 2);
  std::replace(reason.begin(), reason.end(), '\n', ' ');
  return reason;
}

// Line and column (1-based) of byte offset `byte` (nlohmann counts bytes read, so the offending byte is
// byte − 1).
std::pair<size_t, size_t> line_column(const std::string& text, size_t byte) {
  size_t line = 1, column = 1;
  const size_t end = std::min(byte > 0 ? byte - 1 : 0, text.size());
  for (size_t i = 0; i < end; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

}  // namespace

Json parse_json(const std::string& text, const std::string& name) {
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    const auto [line, column] = line_column(text, e.byte);
    std::string hint = "fix the file (a JSON validator shows the spot)";
    // Python's json.dump writes NaN/Infinity, which JSON does not allow: a broken pose or intrinsic.
    const size_t from = e.byte > 0 ? e.byte - 1 : 0;
    const std::string around = from < text.size() ? text.substr(from, 9) : "";
    if (around.rfind("NaN", 0) == 0 || around.rfind("Infinity", 0) == 0 || around.rfind("-Infinity", 0) == 0) {
      hint = "NaN/Infinity is not JSON and means a non-finite value: regenerate the file with finite poses";
    }
    throw Error(name + ": malformed JSON at line " + std::to_string(line) + ", column " + std::to_string(column) +
                ": " + parse_reason(e.what()) + "; " + hint);
  } catch (const Json::out_of_range& e) {
    // A number too large for a double (e.g. 1e999) would be infinite. nlohmann gives no position, only the
    // text ("number overflow parsing '1e999'"): find it in the file to give one.
    const std::string what = e.what();
    const auto open = what.find('\''), close = what.rfind('\'');
    std::string where_text;
    if (open != std::string::npos && close > open) {
      const auto at = text.find(what.substr(open + 1, close - open - 1));
      if (at != std::string::npos) {
        const auto [line, column] = line_column(text, at + 1);
        where_text = " at line " + std::to_string(line) + ", column " + std::to_string(column);
      }
    }
    throw Error(name + ": malformed JSON" + where_text + ": " + parse_reason(what) +
                "; the number is not finite as a double: regenerate the file with finite values");
  } catch (const Json::exception& e) {
    throw Error(name + ": malformed JSON: " + parse_reason(e.what()));
  }
}

Json read_json(const std::string& path) { return parse_json(read_file_text(path), path); }

void write_json(const std::string& path, const Json& value, int indent) {
  write_bytes_atomically(path, value.dump(indent) + "\n");
}

std::string json_type_name(const Json& value) {
  if (value.is_number()) return "number";
  return value.type_name();
}

const Json& require_object(const Json& value, const std::string& where) {
  if (!value.is_object()) throw Error(where + ": expected a JSON object, got " + json_type_name(value));
  return value;
}

const Json& require_key(const Json& object, const std::string& key, const std::string& where) {
  require_object(object, where);
  const auto it = object.find(key);
  if (it == object.end()) throw Error(where + ": missing key '" + key + "'");
  return *it;
}

double require_number(const Json& object, const std::string& key, const std::string& where) {
  const Json& value = require_key(object, key, where);
  if (!value.is_number()) {
    throw Error(where + ": '" + key + "' must be a number, got " + json_type_name(value));
  }
  const double number = value.get<double>();
  if (!std::isfinite(number)) throw Error(where + ": '" + key + "' is not finite");
  return number;
}

std::optional<double> optional_number(const Json& object, const std::string& key, const std::string& where) {
  require_object(object, where);
  if (!object.contains(key) || object.at(key).is_null()) return std::nullopt;
  return require_number(object, key, where);
}

std::string require_string(const Json& object, const std::string& key, const std::string& where) {
  const Json& value = require_key(object, key, where);
  if (!value.is_string()) throw Error(where + ": '" + key + "' must be a string, got " + json_type_name(value));
  return value.get<std::string>();
}

const Json& require_array(const Json& object, const std::string& key, const std::string& where) {
  const Json& value = require_key(object, key, where);
  if (!value.is_array()) throw Error(where + ": '" + key + "' must be an array, got " + json_type_name(value));
  return value;
}

}  // namespace mipnerf::io
