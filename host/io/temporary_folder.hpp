// A scratch folder that cleans up after itself: created empty and unique, removed with everything in it when
// its owner goes (std::filesystem, no shell). Used by `mipnerf-cl bench` (scene and training runs) and
// `mipnerf-cl tune` (each step's spec, result and log).
#pragma once

#include <filesystem>
#include <string>
#include <system_error>

namespace mipnerf::io {

class TemporaryFolder {
 public:
  // Creates <parent>/<prefix>XXXXXX (mkdtemp). Throws mipnerf::Error naming `parent` and why, e.g.
  // "cannot create a temporary folder in /tmp (Permission denied)", with "; set TMPDIR to a writable folder"
  // when `parent` is the system's temporary folder.
  TemporaryFolder(const std::filesystem::path& parent, const std::string& prefix);
  // Removes the folder unless remove() did; a failure is ignored (a destructor has no one to tell).
  ~TemporaryFolder();
  // Removes the folder now; `error` says why it could not be (then the caller may tell a person).
  void remove(std::error_code& error);
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  bool removed_ = false;
};

}  // namespace mipnerf::io
