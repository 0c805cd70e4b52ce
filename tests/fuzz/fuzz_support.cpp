// The fuzz targets' scratch folder and their error contract.
#include "fuzz_support.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <vector>

#include "core/error.hpp"
#include "io/file.hpp"
#include "io/png.hpp"
#include "io/temporary_folder.hpp"

namespace mipnerf::fuzz {
namespace fs = std::filesystem;
namespace {

fs::path scratch_parent() {
  if (const char* tmpdir = std::getenv("TMPDIR"); tmpdir != nullptr && *tmpdir != '\0') return tmpdir;
  std::error_code error;
  if (fs::is_directory("/dev/shm", error)) return "/dev/shm";  // memory: the targets rewrite a file per input
  return "/tmp";
}

// A side x side RGBA image of 8-bit samples, a gradient with partial alpha.
void write_rgba8(const fs::path& path, uint32_t side) {
  std::vector<uint8_t> rgba(side * side * 4);
  for (size_t i = 0; i < rgba.size(); ++i) rgba[i] = static_cast<uint8_t>(37 * i + 11);
  io::make_directories(path.parent_path().string());
  io::write_png8(path.string(), side, side, 4, rgba.data());
}

void write_images(const fs::path& root) {
  for (const char* file : {"train/r_0.png", "train/r_1.png", "val/r_0.png", "test/r_0.png", "images/0.png"}) {
    write_rgba8(root / file, 4);
  }
  std::vector<uint16_t> rgb16(8 * 8 * 3);
  for (size_t i = 0; i < rgb16.size(); ++i) rgb16[i] = static_cast<uint16_t>(4099 * i);
  io::write_png16((root / "images/16bit.png").string(), 8, 8, 3, rgb16.data());
  for (const char* file : {"llff/images/000.png", "llff/images/001.png", "llff/images/002.png"}) write_rgba8(root / file, 4);
  for (const char* file : {"llff/images_2/000.png", "llff/images_2/001.png", "llff/images_2/002.png"}) {
    write_rgba8(root / file, 2);
  }
  for (const char* split : {"train", "val", "test"}) {
    for (int view = 0; view < 2; ++view) {
      for (int level = 0; level < 3; ++level) {
        char name[64];
        std::snprintf(name, sizeof(name), "images_%s/%03d_d%d.png", split, view, level);
        write_rgba8(root / name, 4u >> level);
      }
    }
  }
}

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz target: contract broken: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

}  // namespace

const fs::path& scratch_folder() {
  // Never destroyed before exit (static): the folder goes with the process, unless a crash stops it first.
  static const std::unique_ptr<io::TemporaryFolder> folder = [] {
    auto made = std::make_unique<io::TemporaryFolder>(scratch_parent(), "mipnerf-fuzz-");
    write_images(made->path());
    return made;
  }();
  return folder->path();
}

const fs::path& nested_folder() {
  static const fs::path nested = [] {
    const fs::path folder = scratch_folder() / "nested";
    write_images(folder);
    return folder;
  }();
  return nested;
}

bool lies_inside(const fs::path& file, const fs::path& folder) {
  const fs::path relative = file.lexically_normal().lexically_relative(folder.lexically_normal());
  return !relative.empty() && *relative.begin() != "..";
}

void write_input(const fs::path& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) fail("cannot write the input to " + path.string());
}

void expect_only_errors(const std::string& name, const std::function<void()>& read) {
  try {
    read();
  } catch (const Error& e) {
    const std::string message = e.what();
    if (message.empty()) fail("an empty error message");
    if (message.find('\n') != std::string::npos) fail("an error message of several lines: " + message);
    if (message.find(name) == std::string::npos && message.front() != '/') {
      fail("an error message that does not name the file (" + name + "): " + message);
    }
  }
}

void check(bool condition, const char* what) {
  if (!condition) fail(what);
}

}  // namespace mipnerf::fuzz
