// "Did you mean …": the names closest to a mistyped one (settings, path kinds, a folder's entries), by edit
// distance, so a one-letter slip or two swapped letters names what was meant instead of listing every choice.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace mipnerf {

// Optimal-string-alignment distance, ignoring ASCII case: insertions, deletions, substitutions and swaps of two
// neighbouring characters each cost 1 ("stpes" → "steps" is 1, "sprial" → "spiral" is 1).
size_t edit_distance(const std::string& a, const std::string& b);

// How far `word` is from `name`: their edit distance, or 1 more than its distance to a part of `name` after a '_',
// '-' or '.' (so "samples" is 1 from "num_samples"), whichever is less.
size_t name_distance(const std::string& word, const std::string& name);

// The names nearest to `word`, all of them at the least distance, in the order given; none when even the nearest is
// too far to be a slip (more than a third of the word's length: at least 1 edit, 2 from four letters on), or when
// more than three are as near as each other (then none of them stands out as the one meant).
std::vector<std::string> closest_names(const std::string& word, const std::vector<std::string>& names);

// "did you mean 'steps'?" or "did you mean 'a' or 'b'?" for closest_names (quoted with `quote`); empty when none is
// close.
std::string did_you_mean(const std::string& word, const std::vector<std::string>& names,
                         const std::string& quote = "'");

}  // namespace mipnerf
