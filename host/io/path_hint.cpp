// Hints for paths that do not exist.
#include "io/path_hint.hpp"

#include <algorithm>
#include <filesystem>
#include <vector>

#include "core/suggest.hpp"

namespace mipnerf::io {
namespace fs = std::filesystem;

std::string missing_path_hint(const std::string& path) {
  std::vector<fs::path> parts;
  for (const auto& part : fs::path(path)) {
    if (!part.empty()) parts.push_back(part);
  }
  fs::path folder;  // the longest prefix that exists ("" for the working folder)
  size_t missing = 0;
  std::error_code ec;
  for (; missing < parts.size(); ++missing) {
    const fs::path next = folder / parts[missing];
    if (!fs::exists(next, ec)) break;
    if (ec) return "";
    folder = next;
  }
  if (missing == parts.size() || ec) return "";  // it exists, or a folder on the way cannot be read

  std::vector<std::string> names;
  constexpr size_t kMaxEntries = 10000;  // a hint is not worth reading a huge folder
  for (fs::directory_iterator it(folder.empty() ? fs::path(".") : folder, ec), end; !ec && it != end;
       it.increment(ec)) {
    if (names.size() == kMaxEntries) return "";
    names.push_back(it->path().filename().string());
  }
  if (ec) return "";
  std::sort(names.begin(), names.end());  // the folder's order is the file system's; the hint's is stable
  std::vector<std::string> found;
  for (const auto& name : closest_names(parts[missing].string(), names)) {
    fs::path candidate = folder / name;
    for (size_t i = missing + 1; i < parts.size(); ++i) candidate /= parts[i];
    if (fs::exists(candidate, ec)) found.push_back(candidate.string());
  }
  if (!found.empty()) {
    std::string text = "did you mean ";
    for (size_t i = 0; i < found.size(); ++i) text += (i == 0 ? "" : " or ") + ("'" + found[i] + "'");
    return text + "?";
  }
  if (missing + 1 == parts.size()) return "";
  return "no '" + parts[missing].string() + "' in " +
         (folder.empty() ? std::string("the working folder") : folder.string());
}

}  // namespace mipnerf::io
