// Edit distances and the closest names.
#include "core/suggest.hpp"

#include <algorithm>
#include <cctype>

namespace mipnerf {

size_t edit_distance(const std::string& a, const std::string& b) {
  const auto same = [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
  };
  // d[i][j]: distance between a's first i and b's first j characters; three rows suffice for the swap.
  const size_t n = b.size();
  std::vector<size_t> before_previous(n + 1), previous(n + 1), current(n + 1);
  for (size_t j = 0; j <= n; ++j) previous[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (size_t j = 1; j <= n; ++j) {
      const size_t substitution = previous[j - 1] + (same(a[i - 1], b[j - 1]) ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
      if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1])) {
        current[j] = std::min(current[j], before_previous[j - 2] + 1);
      }
    }
    before_previous.swap(previous);
    previous.swap(current);
  }
  return previous[n];
}

size_t name_distance(const std::string& word, const std::string& name) {
  size_t best = edit_distance(word, name);
  for (size_t i = 0; i < name.size(); ++i) {
    if (name[i] == '_' || name[i] == '-' || name[i] == '.')
      best = std::min(best, 1 + edit_distance(word, name.substr(i + 1)));
  }
  return best;
}

std::vector<std::string> closest_names(const std::string& word, const std::vector<std::string>& names) {
  // A slip changes a few letters; more than a third of the word is another word.
  const size_t allowed = std::max<size_t>(1, (word.size() + 2) / 3);
  size_t best = allowed;
  std::vector<std::string> out;
  for (const auto& name : names) {
    const size_t d = name_distance(word, name);
    if (d > allowed) continue;
    if (d < best || out.empty()) {
      best = d;
      out.clear();
    }
    if (d == best && std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  }
  if (out.size() > 3) out.clear();  // many names as near as each other: none of them is what was meant
  return out;
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& names, const std::string& quote) {
  const std::vector<std::string> close = closest_names(word, names);
  if (close.empty()) return "";
  std::string text = "did you mean ";
  for (size_t i = 0; i < close.size(); ++i) {
    text += (i == 0 ? "" : i + 1 == close.size() ? " or " : ", ") + quote + close[i] + quote;
  }
  return text + "?";
}

}  // namespace mipnerf
