// The CSV logs of a run folder.
#include "train/run_log.hpp"

#include <cstdlib>
#include <filesystem>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace mipnerf::train {
namespace fs = std::filesystem;

void trim_log(const std::string& csv_path, int64_t step, const std::string& header_line) {
  std::ifstream in(csv_path);
  std::string kept, line;
  bool header = true;
  while (std::getline(in, line)) {
    if (in.eof()) break;  // the last line has no newline: cut short
    if (!header) {
      char* end = nullptr;
      const long long row_step = std::strtoll(line.c_str(), &end, 10);
      if (end == line.c_str() || *end != ',' || row_step > step) continue;
    }
    header = false;
    kept += line + "\n";
  }
  io::write_bytes_atomically(csv_path, kept.empty() ? header_line : kept);
}

// Opens a run's CSV log: appended to (its rows after `step` dropped) when resuming, else started anew.
void open_log(std::ofstream& csv, const std::string& csv_path, int64_t step, const std::string& header_line) {
  const bool append = step > 0 && fs::exists(csv_path);
  if (append) trim_log(csv_path, step, header_line);
  csv.open(csv_path, append ? std::ios::app : std::ios::trunc);
  if (!csv) throw Error(csv_path + ": cannot write this log; check the folder's permissions and free space");
  if (!append) csv << header_line << std::flush;
}

}  // namespace mipnerf::train
