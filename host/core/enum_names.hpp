// Name tables of enum-valued settings: each enum has one list of (value, name) pairs, found by argument-dependent
// lookup as `enum_names(E{})` beside the enum's definition, and everything that turns the enum into text or back
// (settings, JSON, help, error messages) goes through the functions here, so the four can never disagree.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "core/error.hpp"

namespace mipnerf {

// One row of an enum's name table.
template <typename E>
struct EnumName {
  E value;
  const char* name;
};

// True for enums that have a name table (an `enum_names(E)` function beside them).
template <typename T, typename = void>
struct has_enum_names : std::false_type {};
template <typename T>
struct has_enum_names<T, std::void_t<decltype(enum_names(std::declval<T>()))>> : std::is_enum<T> {};
template <typename T>
inline constexpr bool has_enum_names_v = has_enum_names<T>::value;

// The value's name. A value outside the table can only come from a cast, never from parsing: that is a bug.
template <typename E>
const char* enum_name(E value) {
  for (const auto& row : enum_names(E{})) {
    if (row.value == value) return row.name;
  }
  throw Error("internal error: value " + std::to_string(static_cast<long long>(value)) + " of an enum has no name");
}

// The value named `name` exactly, or nothing.
template <typename E>
std::optional<E> enum_from_name(std::string_view name) {
  for (const auto& row : enum_names(E{})) {
    if (name == row.name) return row.value;
  }
  return std::nullopt;
}

// Every name, in table order: "white | black | none" (help and error messages).
template <typename E>
std::string enum_choices(const char* separator = " | ") {
  std::string out;
  for (const auto& row : enum_names(E{})) out += (out.empty() ? "" : separator) + std::string(row.name);
  return out;
}

}  // namespace mipnerf
