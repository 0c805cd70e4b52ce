// What every fuzz target (tests/fuzz/fuzz_<reader>.cpp, libFuzzer) shares: a scratch folder made once per process
// with the small images the fuzzed dataset files may name, writing the input there, and the contract checked on
// every input: a reader either returns or throws mipnerf::Error whose message is one line naming the file. Any
// other exception escapes the target, and libFuzzer reports it as a crash (as it does sanitizer reports, hangs and
// allocations beyond -malloc_limit_mb).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

namespace mipnerf::fuzz {

// <$TMPDIR, else /dev/shm, else /tmp>/mipnerf-fuzz-XXXXXX, created on the first call and removed at exit, holding
// 4x4 RGBA PNGs where the seed corpora's frames point: train/r_0.png, train/r_1.png, val/r_0.png, test/r_0.png,
// images/0.png (8-bit), images/16bit.png (16-bit RGB, 8x8), the multiscale pyramid
// images_{train,val,test}/00{0,1}_d{0,1,2}.png (4x4, 2x2, 1x1), and an LLFF capture's images without its poses:
// llff/images/00{0,1,2}.png (4x4) and llff/images_2/00{0,1,2}.png (2x2).
const std::filesystem::path& scratch_folder();

// scratch_folder()/nested: the same images again, one level down. A dataset file written here that names
// "../images/0.png" names a real image outside its own folder, which a reader must refuse (data/path_policy.hpp).
const std::filesystem::path& nested_folder();

// Whether `file` lies inside `folder`, lexically (no `..` out of it once normalised): what a dataset may read.
bool lies_inside(const std::filesystem::path& file, const std::filesystem::path& folder);

// Writes the input to `path` (replacing what was there).
void write_input(const std::filesystem::path& path, const uint8_t* data, size_t size);

// Runs `read`. A mipnerf::Error must be one non-empty line that names a file: it contains `name` (the folder or
// the name the reader was given) or starts with an absolute path (an image file a frame names, anywhere). A
// message that breaks this aborts (a defect, saved by libFuzzer as a crash input); other exceptions propagate.
void expect_only_errors(const std::string& name, const std::function<void()>& read);

// Aborts with `what` when `condition` is false: checks of a successful read's result.
void check(bool condition, const char* what);

}  // namespace mipnerf::fuzz
