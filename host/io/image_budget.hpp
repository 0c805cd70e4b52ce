// The most memory one image's decode may take. A PNG or JPEG declares its size in a header a few bytes long, and
// deflate or a progressive JPEG can describe a huge image in a small file: a 2 KB 1-bit PNG of 4096x4096 decodes to
// 320 MB of samples and floats, one of ~130 KB at PNG's 32768x32768 to ~20 GiB. Every image reader checks what it
// is about to allocate (the samples after expansion to 8/16-bit RGB(A), and their float copies) against this budget
// before allocating, and refuses with one line that names the file, its size and the budget.
#pragma once

#include <cstdint>
#include <string>

namespace mipnerf::io {

// 2 GiB: a 48-megapixel phone photo as JPEG takes ~1.5 GB through the dataset reader (8-bit rows, float RGB, float
// RGBA); an image past it is far larger than mip-NeRF trains on (downsample it: `train --factor`, LLFF's images_N).
inline constexpr uint64_t kDefaultImageBudgetBytes = uint64_t{2} << 30;

// The budget in bytes; `mipnerf-cl --max-image-mib` sets it for the process.
uint64_t image_budget_bytes();
void set_image_budget_bytes(uint64_t bytes);

// Throws mipnerf::Error "<name>: a WxH image needs N MiB to decode (what), more than the M MiB one image may take:
// …" when width · height · bytes_per_pixel exceeds the budget. `what` says what the bytes per pixel hold.
void check_image_budget(const std::string& name, uint64_t width, uint64_t height, uint64_t bytes_per_pixel,
                        const std::string& what);

}  // namespace mipnerf::io
