// Atomic file output: a file is produced under a temporary name beside its destination, flushed to disk,
// then renamed over the destination, so readers (and a run interrupted mid-write) only ever see the old
// file or the complete new one. Used for every output file the library writes (EXR, checkpoints, ...).
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "core/log.hpp"

namespace mipnerf::io {

// The temporary beside `path` that becomes `path` on commit(). Destroyed uncommitted (an exception in
// the producer), it removes the temporary and leaves `path` as it was.
//
// The temporary is "<folder>/.<name>.<pid>.<n>.tmp": hidden, unique per process and call, and in the
// destination's folder so the rename stays on one file system (where rename is atomic). A process
// killed mid-write can leave such a hidden temporary behind, never a partial file under `path`.
class AtomicFile {
 public:
  // Creates missing parent folders of `path`; throws mipnerf::Error naming the folder when that fails.
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& path() const { return path_; }
  // Where the producer writes the complete file.
  const std::string& temporary_path() const { return temporary_; }

  // Flushes the temporary to disk (fsync), renames it over path(), then flushes the folder entry.
  // Throws mipnerf::Error naming path() when the temporary is missing or a step fails (e.g. disk full).
  void commit();

 private:
  std::string path_;
  std::string temporary_;
  bool committed_ = false;
};

// Runs produce(temporary_path) (any writer that takes a file name: OpenEXR, libpng, std::ofstream, ...),
// then commits. An exception from produce propagates after the temporary is removed.
void write_atomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& produce);

// Writes `bytes` to `path` atomically.
void write_bytes_atomically(const std::string& path, std::string_view bytes);

// Removes the temporaries in `folder` (not below it) that processes killed mid-write left behind: hidden files named
// as AtomicFile names them whose process no longer runs. Each removal is logged (info) through `log` when set.
void remove_stale_temporaries(const std::string& folder, const LogFn& log);

}  // namespace mipnerf::io
