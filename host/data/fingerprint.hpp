// A digest of what a split trains on, to tell the same training data from other data whatever its folder is called
// (train --resume compares the checkpoint's with the data it is given or finds).
#pragma once

#include <string>

#include "data/dataset.hpp"

namespace mipnerf::data {

// "fnv1a64:<16 hex digits>" over every image's pixels as loaded (composited, at the factor and scales trained), each
// camera's pose, intrinsics, near/far, lossmult and lens, and each image's scale level. 64-bit FNV-1a: it tells data
// apart, it is no protection against someone who wants a collision.
std::string fingerprint(const Split& split);

}  // namespace mipnerf::data
