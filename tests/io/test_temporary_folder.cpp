// Scratch folders (host/io/temporary_folder): unique, empty, and gone with everything in them afterwards.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "io/temporary_folder.hpp"
#include "support/temp_scene.hpp"

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

// The test mains sweep a passing process's "mipnerf-<name>-<pid>" entries at exit (support/test_main.cpp): the sweep
// must take this process's entries, files and folders, and nothing of another process, even one whose pid ends in ours.
TEST_CASE("temporary folder: the tests' sweep takes this process's entries and no other's") {
  const std::string pid = std::to_string(::getpid());
  const fs::path temp = fs::temp_directory_path();
  const fs::path own_folder = test::temp_path("sweep-folder");
  const fs::path own_file = temp / ("mipnerf-sweep-file-" + pid);
  const fs::path other_pid = temp / ("mipnerf-sweep-other-9" + pid);  // another process, its pid ending in ours
  const fs::path not_ours = temp / ("other-sweep-" + pid);            // not a mipnerf name
  fs::create_directories(own_folder / "inner");
  std::ofstream(own_folder / "inner" / "a.txt") << "x";
  std::ofstream(own_file) << "x";
  fs::create_directories(other_pid);
  fs::create_directories(not_ours);

  const auto entries = test::process_temp_entries();
  auto listed = [&](const fs::path& p) { return std::find(entries.begin(), entries.end(), p) != entries.end(); };
  CHECK(listed(own_folder));
  CHECK(listed(own_file));
  CHECK_FALSE(listed(other_pid));
  CHECK_FALSE(listed(not_ours));

  test::remove_process_temp_entries();
  CHECK_FALSE(fs::exists(own_folder));
  CHECK_FALSE(fs::exists(own_file));
  CHECK(fs::exists(other_pid));
  CHECK(fs::exists(not_ours));
  fs::remove_all(other_pid);
  fs::remove_all(not_ours);
}
