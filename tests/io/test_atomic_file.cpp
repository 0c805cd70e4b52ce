// Atomic file output (host/io/atomic_file): complete files only, old file intact on failure, no leftovers.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

// A fresh empty folder under the system's temporary folder, removed at the end of the test.
struct ScratchFolder {
  fs::path path;
  explicit ScratchFolder(const std::string& name)
      : path(fs::temp_directory_path() / ("mipnerf-atomic-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  size_t entries() const { return static_cast<size_t>(std::distance(fs::directory_iterator(path), {})); }
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("atomic file: writes a new file and replaces an old one, leaving nothing else behind") {
  ScratchFolder folder("write");
  const std::string target = (folder.path / "out.bin").string();
  const std::string bytes("first\0with a zero byte", 22);
  io::write_bytes_atomically(target, bytes);
  CHECK(read_text(target) == bytes);
  CHECK(folder.entries() == 1);
  io::write_bytes_atomically(target, "second");
  CHECK(read_text(target) == "second");
  CHECK(folder.entries() == 1);
  io::write_bytes_atomically(target, "");
  CHECK(fs::file_size(target) == 0);
}

TEST_CASE("atomic file: while the producer writes, the destination still holds the old file") {
  ScratchFolder folder("during");
  const std::string target = (folder.path / "image.exr").string();
  io::write_bytes_atomically(target, "old");
  io::write_atomically(target, [&](const std::string& temporary) {
    CHECK(fs::path(temporary).parent_path() == folder.path);  // same folder: rename is atomic
    CHECK(fs::path(temporary).filename().string().front() == '.');
    std::ofstream(temporary) << "new, half";
    CHECK(read_text(target) == "old");
    std::ofstream(temporary, std::ios::app) << " and whole";
  });
  CHECK(read_text(target) == "new, half and whole");
  CHECK(folder.entries() == 1);
}

TEST_CASE("atomic file: a failing producer leaves the old file intact and removes its temporary") {
  ScratchFolder folder("fail");
  const std::string target = (folder.path / "checkpoint.bin").string();
  io::write_bytes_atomically(target, "good checkpoint");
  CHECK_THROWS_WITH_AS(io::write_atomically(target,
                                            [](const std::string& temporary) {
                                              std::ofstream(temporary) << "partial";
                                              throw std::runtime_error("interrupted");
                                            }),
                       "interrupted", std::runtime_error);
  CHECK(read_text(target) == "good checkpoint");
  CHECK(folder.entries() == 1);
  // A producer that writes nothing is an error naming the destination, not an empty file.
  CHECK_THROWS_WITH_AS(io::write_atomically(target, [](const std::string&) {}),
                       doctest::Contains("produced no file"), Error);
  CHECK(read_text(target) == "good checkpoint");
}

TEST_CASE("atomic file: creates missing folders, and says which path it cannot write") {
  ScratchFolder folder("folders");
  const std::string nested = (folder.path / "a" / "b" / "c.txt").string();
  io::write_bytes_atomically(nested, "deep");
  CHECK(read_text(nested) == "deep");
  // A file where a folder should be.
  io::write_bytes_atomically((folder.path / "plain").string(), "x");
  const std::string blocked = (folder.path / "plain" / "out.txt").string();
  CHECK_THROWS_WITH_AS(io::write_bytes_atomically(blocked, "y"), doctest::Contains(blocked.c_str()), Error);
  // A folder where the file should be: the rename fails and names the path.
  fs::create_directories(folder.path / "dir");
  CHECK_THROWS_WITH_AS(io::write_bytes_atomically((folder.path / "dir").string(), "z"),
                       doctest::Contains("cannot replace"), Error);
  CHECK(fs::is_directory(folder.path / "dir"));
}
