// The Zip-NeRF stage's options as its double reference takes them: one conversion for the stage's tests and the
// graph's (ops::ZipFeatureOptions → ref::ZipFeatureSettings, with the key that draws the training patterns).
#pragma once

#include "core/stage_options.hpp"
#include "ops/zip_features.hpp"
#include "ref/zip_features.hpp"

namespace mipnerf::test {

inline ref::ZipFeatureSettings zip_reference_settings(const ops::ZipFeatureOptions& o, RngKey key) {
  ref::ZipFeatureSettings s;
  s.features = o.features;
  s.multisample = o.multisample;
  s.downweight = o.downweight;
  s.append_scale = o.append_scale;
  s.cylinder = o.cylinder;
  s.randomized = o.randomized;
  s.contract = o.contract;
  for (int a = 0; a < 3; ++a) s.box[a] = o.box_min[a];
  s.box[3] = o.box_size;
  s.scale_mult = o.scale_mult;
  s.precondition = o.precondition;
  s.seed = key.seed;
  s.step = key.step;
  s.first_ray = key.first_ray;
  return s;
}

}  // namespace mipnerf::test
