// The worst element comparison of the running test case.
#include "support/comparison_log.hpp"

namespace mipnerf::test {
namespace {

WorstComparison& slot() {
  static WorstComparison worst;
  return worst;
}

}  // namespace

void record_comparison(const std::string& what, double ratio, double error) {
  WorstComparison& worst = slot();
  ++worst.count;
  if (worst.count == 1 || ratio > worst.ratio) {
    worst.what = what;
    worst.ratio = ratio;
    worst.error = error;
  }
}

const WorstComparison& worst_comparison() { return slot(); }

void reset_comparisons() { slot() = WorstComparison{}; }

}  // namespace mipnerf::test
