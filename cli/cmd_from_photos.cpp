// `mipnerf-cl dataset from-photos PHOTOS OUT`: COLMAP (Debian's `colmap`, CPU SIFT) run from the tool — feature
// extraction, matching and mapping, with progress — then the import of its largest model (data/import): a
// forward-facing capture becomes an LLFF capture, anything else a transforms.json. COLMAP's own output goes to
// OUT/colmap/colmap.log; its work (database, sparse models) stays in OUT/colmap. The photos are read (headers only)
// first: those of another size than most are left out, named (cli/photo_folder.hpp).
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "common.hpp"
#include "core/error.hpp"
#include "core/lens_models.hpp"
#include "data/import/colmap_model.hpp"
#include "dataset_import.hpp"
#include "io/file.hpp"
#include "photo_folder.hpp"
#include "progress.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

struct FromPhotosArgs {
  std::string photos, out;
  std::string matcher = "exhaustive";
  int max_size = 1600;        // longest side COLMAP extracts features at (its default: 3200)
  int max_features = 8192;    // SIFT features per image (COLMAP's default)
  std::string layout = "auto";
  std::string colmap = "colmap";
  std::string camera_model = "SIMPLE_PINHOLE";  // what COLMAP estimates; the import keeps it
  int mapper_attempts = 3;    // mapper runs while photos stay unregistered (see map_photos)
};

// The photos COLMAP is given, after a warning naming any left out; at least 3.
PhotoSelection select_photos(const std::string& folder) {
  const PhotoSelection selection = select_photo_size(list_photos(folder), folder);
  if (!selection.other_size.empty()) std::cerr << "mipnerf-cl: warning: " << describe_left_out(selection) << "\n";
  if (selection.names.size() < 3) {
    throw Error(folder + ": " + std::to_string(selection.names.size()) + " photos (PNG or JPEG)" +
                (selection.other_size.empty() ? std::string()
                                                : " of one size (" + std::to_string(selection.other_size.size()) +
                                                      " of others left out)") +
                "; COLMAP needs at least 3 overlapping views, a capture 20 or more");
  }
  return selection;
}

// The colmap executable, or one line saying what to install.
std::string find_colmap(const std::string& name) {
  if (name.find('/') != std::string::npos) {
    if (fs::exists(name)) return name;
  } else if (const char* path = std::getenv("PATH")) {
    std::string dirs = path;
    for (size_t start = 0, end; start <= dirs.size(); start = end + 1) {
      end = dirs.find(':', start);
      if (end == std::string::npos) end = dirs.size();
      const fs::path candidate = fs::path(dirs.substr(start, end - start)) / name;
      std::error_code ec;
      if (!candidate.empty() && fs::is_regular_file(candidate, ec)) return candidate.string();
    }
  }
  throw Error("COLMAP was not found (`" + name + "`): install the Debian package 'colmap' (scripts/install-deps.sh "
              "--with-colmap installs it), or run COLMAP yourself and import its model with `mipnerf-cl dataset "
              "import-colmap`");
}

std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Runs one COLMAP step, appending its output to `log`; `on_line` sees each line (for progress). Throws naming the
// step, its exit status and its last line when it fails. `work` (OUT/colmap) also takes the log files COLMAP's
// libraries write through glog (Ceres's solver reports, ~1,300 lines a mapping), which would otherwise pile up in /tmp.
void run_step(const std::string& what, const std::vector<std::string>& argv, const fs::path& work, std::ofstream& log,
              const std::function<void(const std::string&)>& on_line) {
  std::string command;
  for (const auto& arg : argv) command += (command.empty() ? "" : " ") + quoted(arg);
  log << "$ " << command << "\n" << std::flush;
  // COLMAP's Qt may look for a display even for command-line steps; offscreen never needs one.
  std::FILE* pipe =
      ::popen(("QT_QPA_PLATFORM=offscreen GLOG_log_dir=" + quoted(work.string()) + " " + command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) throw Error("cannot start COLMAP's " + what);
  std::string line, last;
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
    line += buffer;
    if (line.empty() || line.back() != '\n') continue;
    line.pop_back();
    log << line << "\n";
    if (!line.empty()) last = line;
    on_line(line);
    line.clear();
  }
  log << std::flush;
  const int status = ::pclose(pipe);
  if (status != 0) {
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    throw Error("COLMAP's " + what + " failed (exit " + std::to_string(code) + "): " + (last.empty() ? "no output" : last));
  }
}

// A progress bar over COLMAP's "[i/N]"-style counter lines matching `pattern` (group 1: done, group 2: total).
std::function<void(const std::string&)> counter(Progress& progress, const std::regex& pattern) {
  return [&progress, pattern](const std::string& line) {
    std::smatch m;
    if (!std::regex_search(line, m, pattern)) return;
    progress.set_total(std::stoll(m[2].str()));
    progress.update(std::stoll(m[1].str()));
  };
}

// Makes `model` (a folder sparse/K) sparse/0, swapping it with the model there, and returns its new path: the model
// imported is always OUT/colmap/sparse/0, the one a user re-importing it with `dataset import-colmap` reaches for first.
// COLMAP numbers its models in the order it started them, and a later one can be the largest: a model started from
// photos the first left out may grow to register those the first has as well.
std::string renumber_as_first(const fs::path& model) {
  const fs::path first = model.parent_path() / "0";
  if (model == first) return model.string();
  const fs::path aside = model.parent_path() / "renumbering";
  const bool occupied = fs::exists(first);
  if (occupied) fs::rename(first, aside);
  fs::rename(model, first);
  if (occupied) fs::rename(aside, model);
  return first.string();
}

// A model COLMAP wrote, as from-photos judges it: the photos it registered, and those of them whose pose no sparse
// point checks (fewer than data::kMinPointsInFront points in front of them; see data::points_in_front_counts).
struct ModelCount {
  std::string dir;                  // "" when there is none
  size_t registered = 0;            // its images
  size_t placed = 0;                // registered and seeing enough points: what runs are ranked by
  std::vector<std::string> unseen;  // registered, but seeing fewer points
};

ModelCount count_model(const data::ColmapModel& model, const std::string& dir) {
  ModelCount count;
  count.dir = dir;
  count.registered = model.images.size();
  const std::vector<size_t> in_front = data::points_in_front_counts(model);
  for (size_t i = 0; i < model.images.size(); ++i) {
    if (in_front[i] >= data::kMinPointsInFront) {
      ++count.placed;
    } else {
      count.unseen.push_back(model.images[i].name);
    }
  }
  return count;
}

// The model of sparse/ with the most placed photos (dir "" when there is none).
ModelCount largest_model(const fs::path& sparse) {
  ModelCount best;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(sparse, ec)) {
    if (!entry.is_directory()) continue;
    try {
      const ModelCount count = count_model(data::read_colmap_model(entry.path().string()), entry.path().string());
      if (best.dir.empty() || count.placed > best.placed) best = count;
    } catch (const Error&) {
      // an unfinished model folder: not a candidate
    }
  }
  return best;
}

// What matching and mapping work on.
struct MappingJob {
  std::string colmap;
  fs::path database;
  std::string photos, matcher;
  fs::path work;  // OUT/colmap
  size_t n_photos;
};

// COLMAP's matcher over the database's features; `again`: its earlier matches are removed first (the matcher skips
// pairs the database has already matched).
void run_matcher(const MappingJob& job, bool again, std::ofstream& log) {
  if (again) {
    run_step("database cleaning",
             {job.colmap, "database_cleaner", "--database_path", job.database.string(), "--type", "matches"}, job.work, log,
             [](const std::string&) {});
  }
  Progress progress("COLMAP matching", 1);
  run_step(job.matcher + " matching",
           {job.colmap, job.matcher + "_matcher", "--database_path", job.database.string(), "--SiftMatching.use_gpu", "0"},
           job.work, log,
           job.matcher == "exhaustive" ? counter(progress, std::regex(R"(Matching block \[(\d+)/(\d+))"))
                                       : counter(progress, std::regex(R"(Matching image \[(\d+)/(\d+)\])")));
  progress.finish();
}

// COLMAP's mapper starts a model from one pair of photos: the pair with the most matches among those whose views are
// far enough apart, Mapper.init_min_tri_angle (the median angle between the rays to their common points; default 16°),
// and whose relative pose has enough inliers, Mapper.init_min_num_inliers (100). When no pair qualifies it relaxes
// both, twice (COLMAP 3.8, controllers/incremental_mapper.cc): 100 → 50 → 25 inliers, 16° → 8° → 4°. A forward-facing
// capture can have less parallax than that: in one matching of the first 15 photos of LLFF's flower at 504x378, no
// pair qualified above 4.5° (no model from 18°, relaxed to 4.5°; 4° found one), so whether a pair makes 4° depends on
// the run (issue 47: 0 of 15 registered three times, 13 the next time; the same photos as JPEGs of quality 75: 17 of 24
// attempts of COLMAP's defaults kept no model, 2 runs of 9 none in 3 attempts). With still less parallax (make-scene
// --forward-facing --grid-width 0.1 or 0.06) a pair does start a model at 4°, but every model stops growing under
// 10 photos and is dropped (Mapper.min_model_size), in each of 7 runs. The settings for small baselines start where
// COLMAP's relaxation ended, 2°, and so go down to 0.5° (LLFF's own COLMAP wrapper, imgs2poses, starts at 4°): they
// registered all 12 views of both those captures (at worst after one more matching) and all 15 flower photos in each of
// 6 runs, after one matching. Points keep COLMAP's filters (1.5° to triangulate or keep one): lowering them to 0.5°
// as well registered no more on those captures and took twice as long.
struct MapperSettings {
  bool small_baseline = false;
};
constexpr const char* kSmallBaselineInitAngle = "2";

std::vector<std::string> mapper_options(const MapperSettings& settings) {
  if (!settings.small_baseline) return {};
  return {"--Mapper.init_min_tri_angle", kSmallBaselineInitAngle};
}

// What one mapper run found, from its models and its log.
struct MapperRun {
  fs::path out;               // its output folder
  size_t registered = 0;      // photos in its largest model (0: none; see ModelCount)
  size_t placed = 0;          // those with enough sparse points in front of them
  bool no_matches = false;    // "No images with matches found in the database": no pair of photos matched
  bool initialized = false;   // "Initializing with image pair": a pair started a model (which may have been dropped)
  bool no_initial_pair = false;  // "No good initial image pair found"
};

// No model because no pair of photos qualified to start one (see MapperSettings).
bool lacked_initial_pair(const MapperRun& run) {
  return run.registered == 0 && !run.no_matches && !run.initialized && run.no_initial_pair;
}

// One run of COLMAP's mapper into `out`.
MapperRun run_mapper(const MappingJob& job, const fs::path& out, const MapperSettings& settings, std::ofstream& log) {
  std::error_code ec;
  fs::remove_all(out, ec);
  io::make_directories(out.string());
  Progress progress("COLMAP mapping", static_cast<int64_t>(job.n_photos));
  const std::regex registered_so_far(R"(Registering image #\d+ \((\d+)\))");
  MapperRun run;
  run.out = out;
  std::vector<std::string> argv = {job.colmap, "mapper", "--database_path", job.database.string(), "--image_path",
                                   job.photos, "--output_path", out.string()};
  for (const auto& option : mapper_options(settings)) argv.push_back(option);
  try {
    run_step("mapping", argv, job.work, log, [&](const std::string& line) {
      std::smatch m;
      if (std::regex_search(line, m, registered_so_far)) progress.update(std::stoll(m[1].str()), "registered");
      if (line.find("No images with matches found") != std::string::npos) run.no_matches = true;
      if (line.find("Initializing with image pair") != std::string::npos) run.initialized = true;
      if (line.find("No good initial image pair found") != std::string::npos) run.no_initial_pair = true;
    });
  } catch (const Error&) {
    if (!largest_model(out).dir.empty()) throw;
    // COLMAP's mapper fails ("failed to create sparse model") when it kept no model.
  }
  progress.finish();
  const ModelCount largest = largest_model(out);
  run.registered = largest.registered;
  run.placed = largest.placed;
  return run;
}

// ", 11 of them with sparse points in front" when some registered photo has too few, else "".
std::string seen_clause(const MapperRun& run) {
  if (run.placed == run.registered) return "";
  return ", " + std::to_string(run.placed) + " of them with sparse points in front";
}

// Why a run of COLMAP's default settings kept no model (photos did match), in a few words.
std::string why_no_model(const MapperRun& run, size_t n_photos) {
  if (lacked_initial_pair(run)) {
    return "COLMAP's mapper found no pair of photos to start from with enough parallax (it asks for 16° between "
           "their views, relaxed to 4°; a forward-facing capture can have less)";
  }
  if (run.initialized) {
    return "COLMAP's mapper kept no model: each it started stopped growing under " +
           std::to_string(std::min<size_t>(n_photos, 10)) + " photos and was dropped (Mapper.min_model_size)";
  }
  return "COLMAP's mapper kept no model";
}

// What mapping left: the run that registered the most, the last run (whose log says why when none found a model),
// and whether the settings for small baselines were used.
struct Mapping {
  MapperRun best, last;
  bool small_baseline = false;
};

// COLMAP's matching and mapping, both run again (up to `attempts` times) while photos stay unregistered; the best
// run's models end up in OUT/colmap/sparse. Why: COLMAP's result varies from run to run (3.8 seeds its random
// generator from the clock and has no seed option; its threads' timing matters too): the RANSAC of its matcher's
// geometric verification and the mapper's choices can leave photos out that the next run registers. On the test
// suite's 20 procedural photos (stripes: repetitive features) 1 run in 6 to 8 did on a loaded machine (14 or 11 of
// 20 registered); mapping the same matches again gave the same 11 three times, so a new attempt matches again too.
// It costs a matching and a mapping only when a run was incomplete.
// When the mapper kept no model though photos matched (no pair to start from, or models that stopped growing), the
// same matches are mapped again at once with the settings for small baselines (MapperSettings), which later attempts
// keep. When even they find no pair to start from, or no photos matched at all, matching again does not help (a trait
// of the photos, not of the run) and mapping stops there.
Mapping map_photos(const MappingJob& job, int attempts, std::ofstream& log) {
  Mapping mapping;
  MapperSettings settings;
  const auto keep_best = [&mapping](const MapperRun& run) {
    std::error_code ec;
    if (mapping.best.out.empty() || run.placed > mapping.best.placed) {
      if (!mapping.best.out.empty()) fs::remove_all(mapping.best.out, ec);
      mapping.best = run;
    } else {
      fs::remove_all(run.out, ec);
    }
  };
  for (int attempt = 1; attempt <= attempts; ++attempt) {
    const std::string name = "mapper_attempt_" + std::to_string(attempt);
    run_matcher(job, attempt > 1, log);
    mapping.last = run_mapper(job, job.work / name, settings, log);
    if (!settings.small_baseline && mapping.last.registered == 0 && !mapping.last.no_matches) {
      std::cerr << "mipnerf-cl: " << why_no_model(mapping.last, job.n_photos)
                << ": mapping the same matches again with settings for small baselines (Mapper.init_min_tri_angle "
                << kSmallBaselineInitAngle << "°, relaxed to 0.5°), as a forward-facing capture can need\n";
      settings.small_baseline = mapping.small_baseline = true;
      std::error_code ec;
      fs::remove_all(mapping.last.out, ec);
      mapping.last = run_mapper(job, job.work / (name + "_small_baseline"), settings, log);
    }
    keep_best(mapping.last);
    if (mapping.best.placed == job.n_photos || attempt == attempts) break;
    if (mapping.best.registered == 0 && (mapping.last.no_matches || lacked_initial_pair(mapping.last))) break;
    std::cerr << "mipnerf-cl: COLMAP's mapper registered " << mapping.best.registered << " of " << job.n_photos
              << " photos" << seen_clause(mapping.best) << "; matching and mapping again (attempt " << attempt + 1 << " of " << attempts
              << ": COLMAP's result varies from run to run)\n";
  }
  fs::rename(mapping.best.out, job.work / "sparse");
  return mapping;
}

// Why mapping found no model, from what COLMAP's mapper said, and what to try.
std::string no_model_message(const Mapping& mapping, size_t n_photos, const fs::path& log_path) {
  const std::string photos = std::to_string(n_photos) + " photos", log = "COLMAP's log: " + log_path.string();
  if (mapping.last.no_matches) {
    return "COLMAP found no model: no two of the " + photos + " share enough matching features (too little texture, "
           "or too little overlap between them? " + log + ")";
  }
  if (lacked_initial_pair(mapping.last)) {
    return "COLMAP found no model: no pair of the " + photos + " could start one, even with settings for small "
           "baselines: none has both 25 or more matching features and views 0.5° or more apart (take photos that "
           "overlap more, moving the camera sideways between them; " + log + ")";
  }
  if (mapping.last.initialized) {
    return "COLMAP found no model: each it started stayed under " + std::to_string(std::min<size_t>(n_photos, 10)) +
           " photos and was dropped (its Mapper.min_model_size): too little overlap between the photos? Take more, "
           "each overlapping its neighbours (" + log + ")";
  }
  return "COLMAP found no model: 0 of " + photos + " registered (" + log + ")";
}

void run_from_photos(const FromPhotosArgs& args) {
  if (args.matcher != "exhaustive" && args.matcher != "sequential") {
    throw Error("--matcher '" + args.matcher + "': expected exhaustive (any photos) or sequential (a video or a walk)");
  }
  const data::ImportLayout layout = parse_import_layout(args.layout);
  if (!find_lens_row(args.camera_model)) {
    throw Error("--camera-model '" + args.camera_model + "': expected " + lens_model_list("or"));
  }
  const PhotoSelection selection = select_photos(args.photos);
  const size_t photos = selection.names.size();
  const std::string colmap = find_colmap(args.colmap);
  const fs::path work = fs::path(args.out) / "colmap";
  const fs::path database = work / "database.db", sparse = work / "sparse", photo_list = work / "photos.txt";
  std::error_code ec;
  fs::remove(database, ec);  // a fresh run: COLMAP appends to an existing database
  fs::remove_all(sparse, ec);
  io::make_directories(work.string());
  {
    // The photos COLMAP reads: by default it takes every file under the folder, subfolders included.
    std::ofstream list(photo_list);
    for (const auto& name : selection.names) list << name << "\n";
    if (!list.flush()) throw Error(photo_list.string() + ": cannot write the list of photos here");
  }
  std::ofstream log(work / "colmap.log");
  if (!log) throw Error((work / "colmap.log").string() + ": cannot write COLMAP's log here");
  std::cerr << "mipnerf-cl: COLMAP on " << photos << " photos (" << selection.width_px << "x" << selection.height_px
            << ") in " << args.photos << " (log: " << (work / "colmap.log").string() << ")\n";
  {
    Progress progress("COLMAP features", static_cast<int64_t>(photos));
    run_step("feature extraction",
             {colmap, "feature_extractor", "--database_path", database.string(), "--image_path", args.photos,
              "--image_list_path", photo_list.string(), "--ImageReader.camera_model", args.camera_model,
              "--ImageReader.single_camera", "1", "--SiftExtraction.use_gpu", "0", "--SiftExtraction.max_image_size",
              std::to_string(args.max_size), "--SiftExtraction.max_num_features", std::to_string(args.max_features)},
             work, log, counter(progress, std::regex(R"(Processed file \[(\d+)/(\d+)\])")));
    progress.finish();
  }
  const Mapping mapping = map_photos({colmap, database, args.photos, args.matcher, work, photos},
                                     args.mapper_attempts, log);
  const ModelCount found = largest_model(sparse);
  if (found.dir.empty()) throw Error(no_model_message(mapping, photos, work / "colmap.log"));
  const std::string model = renumber_as_first(found.dir);
  const size_t registered = found.placed;  // what is imported
  for (const auto& name : found.unseen) {
    std::cerr << "mipnerf-cl: warning: COLMAP registered " << name << " but fewer than " << data::kMinPointsInFront
              << " of its sparse points lie in front of it: no point checks its pose; it is left out\n";
  }
  if (registered < 3 || 2 * registered < photos) {
    throw Error("COLMAP registered only " + std::to_string(registered) + " of " + std::to_string(photos) +
                " photos (" + model + "): take more overlapping photos, or try --matcher exhaustive");
  }
  if (registered < photos) {
    std::cerr << "mipnerf-cl: warning: COLMAP registered " << registered << " of " << photos
              << " photos; the others are left out\n";
  }
  if (mapping.small_baseline) {
    std::cerr << "mipnerf-cl: COLMAP registered " << registered << " of " << photos
              << " photos with the settings for small baselines\n";
  }
  data::ColmapImportOptions options;
  options.layout = layout;
  options.leave_out = found.unseen;
  print_import(data::import_colmap(model, args.photos, args.out, options), model);
}

}  // namespace

void register_from_photos(CLI::App& dataset) {
  auto args = std::make_shared<FromPhotosArgs>();
  auto* cmd = dataset.add_subcommand(
      "from-photos",
      "Run COLMAP (CPU SIFT; Debian package 'colmap') on a folder of photos — features, matching, mapping — and import "
      "its model: a forward-facing capture of a pinhole camera as an LLFF capture (trained in NDC with cylinders), "
      "anything else as a transforms.json (a lens model is kept and trained through). One camera for all photos.");
  cmd->add_option("PHOTOS", args->photos, "Folder of photos (PNG or JPEG) of one camera")->required();
  cmd->add_option("OUT", args->out, "Output folder: the dataset, and COLMAP's work in OUT/colmap")->required();
  cmd->add_option("--matcher", args->matcher, "exhaustive (any photos) or sequential (photos in capture order)")
      ->capture_default_str();
  cmd->add_option("--max-size", args->max_size, "Longest side, in pixels, COLMAP extracts features at")
      ->check(CLI::Range(64, 16384))
      ->capture_default_str();
  cmd->add_option("--max-features", args->max_features, "SIFT features per photo (fewer: faster matching)")
      ->check(CLI::Range(64, 65536))
      ->capture_default_str();
  cmd->add_option("--layout", args->layout, "auto (LLFF when forward-facing), llff or transforms")
      ->capture_default_str();
  cmd->add_option("--colmap", args->colmap, "The COLMAP executable")->capture_default_str();
  cmd->add_option("--mapper-attempts", args->mapper_attempts,
                  "Runs of COLMAP's matching and mapping while photos stay unregistered (its result varies from run "
                  "to run); the run that registers the most is kept. A run whose mapper found no pair of photos to "
                  "start from maps its matches again with settings for small baselines (forward-facing captures)")
      ->check(CLI::Range(1, 10))
      ->capture_default_str();
  cmd->add_option("--camera-model", args->camera_model,
                  "The camera COLMAP estimates and the import keeps: SIMPLE_PINHOLE (an LLFF capture when "
                  "forward-facing), PINHOLE, or a lens trained as it is: one of " + lens_model_list("or"))
      ->capture_default_str();
  cmd->callback([args] { run_from_photos(*args); });
}

}  // namespace mipnerf::cli
