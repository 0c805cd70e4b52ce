// "Did you mean" (core/suggest.hpp): edit distances, and which names are close enough to a mistyped one to name.
#include <doctest/doctest.h>

#include "core/suggest.hpp"

using namespace mipnerf;

TEST_CASE("suggest: the edit distance counts insertions, deletions, substitutions and swapped neighbours") {
  CHECK(edit_distance("", "") == 0);
  CHECK(edit_distance("", "abc") == 3);
  CHECK(edit_distance("steps", "steps") == 0);
  CHECK(edit_distance("stpes", "steps") == 1);  // two neighbours swapped
  CHECK(edit_distance("sprial", "spiral") == 1);
  CHECK(edit_distance("orbt", "orbit") == 1);      // one left out
  CHECK(edit_distance("floweer", "flower") == 1);  // one too many
  CHECK(edit_distance("Orbit", "orbit") == 0);     // case is no slip
  CHECK(edit_distance("kitten", "sitting") == 3);
  CHECK(edit_distance("ab", "ba") == 1);
  CHECK(edit_distance("abc", "ca") == 3);  // optimal string alignment: no edits of a swapped pair
  for (const auto& [a, b] : {std::pair<const char*, const char*>{"num_samples", "sampels"}, {"orbit", "spiral"}}) {
    CHECK(edit_distance(a, b) == edit_distance(b, a));
  }
}

TEST_CASE("suggest: a name's part after a separator counts, one edit more") {
  CHECK(name_distance("samples", "num_samples") == 1);
  CHECK(name_distance("sampels", "num_samples") == 2);
  CHECK(name_distance("steps", "lr_warmup_steps") == 1);
  CHECK(name_distance("json", "transforms.json") == 1);
  CHECK(name_distance("stpes", "steps") == 1);  // the whole name, when nearer
}

TEST_CASE("suggest: the closest names, or none when none is a slip") {
  const std::vector<std::string> settings = {"steps", "lr_warmup_steps", "num_samples",
                                             "seed",  "val_every",       "val_views"};
  CHECK(closest_names("stpes", settings) == std::vector<std::string>{"steps"});
  CHECK(closest_names("sampels", settings) == std::vector<std::string>{"num_samples"});
  CHECK(closest_names("val_evry", settings) == std::vector<std::string>{"val_every"});
  CHECK(closest_names("val_view", settings) == std::vector<std::string>{"val_views"});
  CHECK(closest_names("xyzzy", settings).empty());
  CHECK(closest_names("", settings).empty());
  // Ties are all named, in the order given.
  CHECK(closest_names("val_viewz", {"val_views", "val_viewy"}) == std::vector<std::string>{"val_views", "val_viewy"});
  // More than three as near as each other: none stands out.
  CHECK(closest_names("ab", {"ax", "ay", "az", "aw"}).empty());
  // A third of the word's length at most, and at least one edit: 4 letters allow 2, 3 letters 1.
  CHECK(closest_names("obit", {"orbits"}) == std::vector<std::string>{"orbits"});
  CHECK(closest_names("obi", {"orbits"}).empty());
  CHECK(closest_names("fr", {"far"}) == std::vector<std::string>{"far"});
  CHECK(closest_names("xyz", {"abc"}).empty());
}

TEST_CASE("suggest: did you mean, quoted, with 'or' between the names") {
  CHECK(did_you_mean("sprial", {"orbit", "spiral"}) == "did you mean 'spiral'?");
  CHECK(did_you_mean("val_viewz", {"val_views", "val_viewy"}, "") == "did you mean val_views or val_viewy?");
  CHECK(did_you_mean("x_viewz", {"a_views", "b_views", "c_views"}) ==
        "did you mean 'a_views', 'b_views' or 'c_views'?");
  CHECK(did_you_mean("nothing", {"orbit", "spiral"}).empty());
}
