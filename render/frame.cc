#include "render/frame.h"

#include "core/check.h"

namespace candi::render {

void Accumulator::Merge(const Accumulator& other) {
  CANDI_CHECK(other.sums.size() == sums.size()) << "accumulators of different sizes";
  for (size_t i = 0; i < sums.size(); ++i) sums[i] += other.sums[i];
}

}  // namespace candi::render
