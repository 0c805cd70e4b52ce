// A scratch folder removed with its contents when destroyed.
#include "io/temporary_folder.hpp"

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <system_error>

#include "core/error.hpp"

namespace mipnerf::io {

TemporaryFolder::TemporaryFolder(const std::filesystem::path& parent, const std::string& prefix) {
  std::string pattern = (parent / (prefix + "XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    const std::string reason = std::strerror(errno);
    std::error_code error;
    const bool system_folder = parent == std::filesystem::temp_directory_path(error) && !error;
    throw Error("cannot create a temporary folder in " + parent.string() + " (" + reason + ")" +
                (system_folder ? "; set TMPDIR to a writable folder" : ""));
  }
  path_ = pattern;
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code error;
  remove(error);
}

void TemporaryFolder::remove(std::error_code& error) {
  error.clear();
  if (removed_) return;
  std::filesystem::remove_all(path_, error);
  removed_ = !error;
}

}  // namespace mipnerf::io
