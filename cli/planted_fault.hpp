// Test-only, and only in the sanitizer build (MIPNERF_PLANTED_FAULTS): MIPNERF_TEST_PLANT_FAULT=leak|overflow makes
// the executable leak one block or write one int past a heap array, once, before it runs its command. tests/sanitize
// uses it to prove that a sanitizer report fails the CLI test that saw it (tests/cli/run_checked.cmake).
#pragma once

#ifdef MIPNERF_PLANTED_FAULTS
#include <cstdlib>
#include <cstring>
#include <new>

namespace mipnerf::cli {

inline void plant_fault_if_asked() {
  const char* fault = std::getenv("MIPNERF_TEST_PLANT_FAULT");
  if (fault == nullptr) return;
  if (std::strcmp(fault, "leak") == 0) {
    [[maybe_unused]] static int* volatile sink;  // volatile itself: the allocation cannot be elided
    sink = new int[16];  // never freed: LeakSanitizer reports it at exit
    sink = nullptr;
  } else if (std::strcmp(fault, "overflow") == 0) {
    // Through a volatile pointer, so the compiler can neither elide the allocation (new/delete pairs may be
    // removed) nor the store: both happen, and AddressSanitizer sees the write.
    static int* volatile block;
    block = new int[4];
    volatile size_t past_the_end = 4;
    block[past_the_end] = 1;  // AddressSanitizer: heap-buffer-overflow
    delete[] block;
  }
}

}  // namespace mipnerf::cli
#else
namespace mipnerf::cli {
inline void plant_fault_if_asked() {}
}  // namespace mipnerf::cli
#endif
