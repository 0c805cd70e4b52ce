// mipnerf::Error: its message is one line whatever text from outside it quotes.
#include <doctest/doctest.h>

#include "core/error.hpp"

using namespace mipnerf;

TEST_CASE("error: control characters in a quoted name are written out, so the message stays one line") {
  // Found by fuzzing: an .npy header key, a JSON file_path or a camera_model holding a newline made a message of
  // several lines (the CLI prints one line, and a terminal would act on an escape sequence).
  const Error e("data/poses_bounds.npy: unknown key 'a\nb\r\t\x1b[31m\x7f'", "the log\nkeeps its lines");
  CHECK(std::string(e.what()) == "data/poses_bounds.npy: unknown key 'a\\nb\\r\\t\\x1b[31m\\x7f'");
  CHECK(e.details() == "the log\nkeeps its lines");
  CHECK(std::string(Error("caf\xc3\xa9.png: no such file").what()) == "caf\xc3\xa9.png: no such file");  // UTF-8 as is
}
