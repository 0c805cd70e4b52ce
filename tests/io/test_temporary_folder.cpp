// Scratch folders (host/io/temporary_folder): unique, empty, and gone with everything in them afterwards.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "io/temporary_folder.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

TEST_CASE("temporary folder: unique and empty, removed with its contents when its owner goes") {
  fs::path kept;
  {
    io::TemporaryFolder first(fs::temp_directory_path(), "mipnerf-folder-test-");
    io::TemporaryFolder second(fs::temp_directory_path(), "mipnerf-folder-test-");
    kept = first.path();
    CHECK(first.path() != second.path());
    REQUIRE(fs::is_directory(first.path()));
    CHECK(fs::is_empty(first.path()));
    CHECK(first.path().filename().string().rfind("mipnerf-folder-test-", 0) == 0);
    fs::create_directories(first.path() / "nested" / "deeper");
    std::ofstream(first.path() / "nested" / "deeper" / "file.txt") << "contents";
  }
  CHECK_FALSE(fs::exists(kept));
}

TEST_CASE("temporary folder: remove() says when it succeeded, and the destructor does not try again") {
  io::TemporaryFolder folder(fs::temp_directory_path(), "mipnerf-folder-test-");
  std::error_code error;
  folder.remove(error);
  CHECK_FALSE(error);
  CHECK_FALSE(fs::exists(folder.path()));
  fs::create_directory(folder.path());  // someone else's now: the destructor must leave it
  folder.remove(error);
  CHECK_FALSE(error);
  CHECK(fs::exists(folder.path()));
  fs::remove(folder.path());
}

TEST_CASE("temporary folder: a parent that does not exist is named in the error") {
  CHECK_THROWS_WITH_AS(io::TemporaryFolder("/nonexistent-mipnerf-parent", "x-"),
                       doctest::Contains("cannot create a temporary folder in /nonexistent-mipnerf-parent"), Error);
}
