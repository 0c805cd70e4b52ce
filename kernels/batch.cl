// Training batches: which pixels a step trains on (Philox, keyed by seed and step) and their target
// colours and loss weights, gathered from the split's pixels uploaded once. Mirrored by host/ref/batch.hpp.
//
// Pixels of all images of a split (every scale of a multiscale set) are packed one image after another:
// image c owns global pixels [pixel_offsets[c], pixel_offsets[c + 1]), row-major (pixel y·width + x).

// BATCH_SINGLE_IMAGE 0: every ray picks a pixel uniformly among all pixels of all images (the official
// "all_images" batching). 1: one image per step, chosen uniformly, and the rays pick pixels uniformly in it
// (the official "single_image" batching).
#ifndef BATCH_SINGLE_IMAGE
#define BATCH_SINGLE_IMAGE 0
#endif

// A uniform integer in [0, n) from 64 random bits: floor(bits · n / 2^64). Its bias is below n / 2^64
// (with 32 bits, a split of 85 M pixels would give some pixels 2% more weight than others).
inline ulong uniform_below(uint hi_word, uint lo_word, ulong n) {
  return mul_hi(upsample(hi_word, lo_word), n);
}

// The image whose pixel range holds global pixel g: the last c with pixel_offsets[c] <= g (binary search;
// every image has at least one pixel, so the ranges are non-empty).
inline uint camera_of_pixel(__global const uint* pixel_offsets, uint num_cameras, uint g) {
  uint lo = 0, hi = num_cameras;  // invariant: offsets[lo] <= g < offsets[hi]
  while (hi - lo > 1) {
    const uint mid = lo + (hi - lo) / 2;
    if (pixel_offsets[mid] <= g) lo = mid;
    else hi = mid;
  }
  return lo;
}

// For each ray i < n_rays of training step `step`:
//   camera_ids [R], pixel_ids [R] (y·width + x within the image), target_rgb [R][3], lossmult [R].
// Random words: counter (i, step, 0, RNG_STREAM_BATCH) for the pixel, (0, step, 1, RNG_STREAM_BATCH) for
// the image of a single-image step; key = seed.
__kernel void batch_sample(const ulong seed, const uint step, __global const uint* pixel_offsets,
                           const uint num_cameras, __global const float* pixels_rgb, __global const float* cameras,
                           __global uint* camera_ids, __global uint* pixel_ids, __global float* target_rgb,
                           __global float* lossmult, const uint n_rays) {
  const uint i = get_global_id(0);
  if (i >= n_rays) return;
  const uint2 key = (uint2)((uint)seed, (uint)(seed >> 32));
  const uint4 words = philox4x32_10((uint4)(i, step, 0u, RNG_STREAM_BATCH), key);
#if BATCH_SINGLE_IMAGE
  const uint4 image_words = philox4x32_10((uint4)(0u, step, 1u, RNG_STREAM_BATCH), key);
  const uint camera = (uint)uniform_below(image_words.x, image_words.y, num_cameras);
  const uint first = pixel_offsets[camera];
  const uint global_pixel = first + (uint)uniform_below(words.x, words.y, pixel_offsets[camera + 1] - first);
#else
  const uint global_pixel = (uint)uniform_below(words.x, words.y, pixel_offsets[num_cameras]);
  const uint camera = camera_of_pixel(pixel_offsets, num_cameras, global_pixel);
#endif
  camera_ids[i] = camera;
  pixel_ids[i] = global_pixel - pixel_offsets[camera];
  for (int c = 0; c < 3; ++c) target_rgb[3 * (size_t)i + c] = pixels_rgb[3 * (size_t)global_pixel + c];
  lossmult[i] = cameras[(size_t)camera * CAMERA_STRIDE + CAMERA_LOSSMULT];
}
