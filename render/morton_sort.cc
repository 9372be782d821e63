#include "render/morton_sort.h"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <utility>

#include "core/check.h"
#include "core/parallel.h"

namespace candi::render {

namespace {

// LSD radix sort of keys[0, n) by the code's bits [0, bits), stable, with temp[0, n) as
// scratch: 8-bit digits, a digit whose values are all equal skipped. The range is small (one
// bucket of SortByCode), so the passes stay in the cache.
void LocalRadixSort(Keyed* keys, Keyed* temp, size_t n, int bits) {
  uint64_t count[256];
  Keyed *from = keys, *to = temp;
  for (int shift = 0; shift < bits; shift += 8) {
    std::fill(count, count + 256, uint64_t{0});
    for (size_t i = 0; i < n; ++i) ++count[(from[i].code >> shift) & 0xff];
    if (*std::max_element(count, count + 256) == n) continue;  // one value: already in order
    uint64_t sum = 0;
    for (uint64_t& c : count) {
      const uint64_t m = c;
      c = sum;
      sum += m;
    }
    for (size_t i = 0; i < n; ++i) to[count[(from[i].code >> shift) & 0xff]++] = from[i];
    std::swap(from, to);
  }
  if (from != keys) std::copy(from, from + n, keys);
}

}  // namespace

std::vector<uint64_t> StableBucketOffsets(std::vector<uint64_t>* counts, size_t slices, size_t buckets) {
  CANDI_CHECK_EQ(counts->size(), slices * buckets);
  std::vector<uint64_t> start(buckets + 1, 0);
  uint64_t sum = 0;
  for (size_t k = 0; k < buckets; ++k) {
    start[k] = sum;
    for (size_t s = 0; s < slices; ++s) {
      uint64_t& c = (*counts)[s * buckets + k];
      const uint64_t m = c;
      c = sum;
      sum += m;
    }
  }
  start[buckets] = sum;
  return start;
}

void SortByCode(std::vector<Keyed>* keys, std::vector<Keyed>* scratch, int bits) {
  CANDI_CHECK(bits <= 64) << "SortByCode: " << bits << " bits";
  const size_t n = keys->size();
  if (bits <= 0 || n < 2) return;
  constexpr int kTopBits = 11;
  const int top = std::min(kTopBits, bits), shift = bits - top;
  const size_t buckets = size_t{1} << top;
  constexpr size_t kSlices = 16;
  scratch->resize(n);
  std::vector<uint64_t> count(kSlices * buckets, 0);
  auto slice = [&](size_t s) { return std::pair<size_t, size_t>{n * s / kSlices, n * (s + 1) / kSlices}; };
  const Keyed* in = keys->data();
  ParallelFor(size_t{0}, kSlices, [&](size_t s) {
    const auto [a, b] = slice(s);
    uint64_t* c = &count[s * buckets];
    for (size_t i = a; i < b; ++i) ++c[(in[i].code >> shift) & (buckets - 1)];
  });
  const std::vector<uint64_t> bucket_start = StableBucketOffsets(&count, kSlices, buckets);
  Keyed* out = scratch->data();
  ParallelFor(size_t{0}, kSlices, [&](size_t s) {
    const auto [a, b] = slice(s);
    uint64_t* c = &count[s * buckets];
    for (size_t i = a; i < b; ++i) out[c[(in[i].code >> shift) & (buckets - 1)]++] = in[i];
  });
  // Each bucket sorted from scratch back into keys.
  Keyed* result = keys->data();
  ParallelFor(tbb::blocked_range<size_t>(0, buckets, 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const size_t a = bucket_start[k], m = bucket_start[k + 1] - a;
      if (m == 0) continue;
      LocalRadixSort(out + a, result + a, m, shift);  // sorted in out + a ...
      std::copy(out + a, out + a + m, result + a);     // ... then moved into keys
    }
  });
}


}  // namespace candi::render
