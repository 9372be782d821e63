#include "render/morton_sort.h"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <cstring>
#include <type_traits>
#include <utility>

#include "core/check.h"
#include "core/parallel.h"

namespace candi::render {

namespace {

// LSD radix sort of keys[0, n) by the code's bits [0, bits), stable, with temp[0, n) as
// scratch: 8-bit digits, a digit whose values are all equal skipped. The range is small (one
// bucket of SortByCode, < 2^32 keys), so the passes stay in the cache. The counts of every digit
// are taken in one first pass: the keys come nearly in order, so counting one digit at a time
// would increment the same counter again and again, each increment waiting for the last.
void LocalRadixSort(Keyed* keys, Keyed* temp, size_t n, int bits) {
  constexpr int kMaxDigits = 8;
  const int digits = std::min(kMaxDigits, (bits + 7) / 8);
  uint32_t count[kMaxDigits][256];
  std::memset(count, 0, sizeof(count[0]) * static_cast<size_t>(digits));
  for (size_t i = 0; i < n; ++i) {
    const uint64_t code = keys[i].code;
    for (int d = 0; d < digits; ++d) ++count[d][(code >> (8 * d)) & 0xff];
  }
  Keyed *from = keys, *to = temp;
  for (int d = 0; d < digits; ++d) {
    uint32_t* c = count[d];
    if (*std::max_element(c, c + 256) == n) continue;  // one value: already in order
    uint32_t sum = 0;
    for (int v = 0; v < 256; ++v) {
      const uint32_t m = c[v];
      c[v] = sum;
      sum += m;
    }
    const int shift = 8 * d;
    for (size_t i = 0; i < n; ++i) to[c[(from[i].code >> shift) & 0xff]++] = from[i];
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

namespace {

// What moves with the keys: nothing, records of a fixed size, or of any size. carry(from, to)
// puts the record of input position `from` at sorted place `to`.
struct NoRecords {
  void operator()(size_t /*from*/, size_t /*to*/) const {}
};
template <size_t B>  // a constant size: the copy is one or two moves
struct FixedRecords {
  const unsigned char* in;
  unsigned char* out;
  void operator()(size_t from, size_t to) const { std::memcpy(out + to * B, in + from * B, B); }
};
struct AnyRecords {
  const unsigned char* in;
  unsigned char* out;
  size_t bytes;
  void operator()(size_t from, size_t to) const { std::memcpy(out + to * bytes, in + from * bytes, bytes); }
};

template <typename Carry>
void Sort(std::vector<Keyed>* keys, std::vector<Keyed>* scratch, int bits, size_t coarse, const Carry& carry) {
  CANDI_CHECK(bits <= 64) << "SortByCode: " << bits << " bits";
  CANDI_CHECK(coarse == 0 || bits % 3 == 0) << "SortByCode: coarse, " << bits << " bits";
  const size_t n = keys->size();
  if (bits <= 0 || n < 2 || n <= coarse) {  // in order already: the records follow their keys
    if constexpr (!std::is_same_v<Carry, NoRecords>) {
      const Keyed* k = keys->data();
      ParallelFor(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
        const Keyed* const sorted = k;
        const Carry move = carry;  // in a local: the records' byte stores could alias the capture
        for (size_t i = r.begin(); i < r.end(); ++i) move(sorted[i].index, i);
      });
    }
    return;
  }
  // Coarse: the top bits whole levels (bits is a multiple of 3, so is the shift below them).
  const int kTopBits = coarse > 0 ? 12 : 11;
  const int top = std::min(kTopBits, bits), shift = bits - top;
  const size_t buckets = size_t{1} << top;
  constexpr size_t kSlices = 16;
  scratch->resize(n);
  std::vector<uint64_t> count(kSlices * buckets, 0);
  auto slice = [&](size_t s) { return std::pair<size_t, size_t>{n * s / kSlices, n * (s + 1) / kSlices}; };
  const Keyed* in = keys->data();
  // The loops below keep what they read of the captures in locals: their stores (the counters,
  // the keys) could otherwise alias the captures, which would be reloaded at every key.
  ParallelFor(size_t{0}, kSlices, [&](size_t s) {
    const auto [a, b] = slice(s);
    uint64_t* const c = &count[s * buckets];
    const Keyed* const from = in;
    const int right = shift;
    const uint64_t mask = buckets - 1;
    for (size_t i = a; i < b; ++i) ++c[(from[i].code >> right) & mask];
  });
  const std::vector<uint64_t> bucket_start = StableBucketOffsets(&count, kSlices, buckets);
  // The keys bucketed into scratch, and their records beside them: read in input order, each
  // written to its bucket's next place (a few thousand places advancing in step, where reading
  // them by the sorted keys' indices would be a cache miss for every record).
  Keyed* out = scratch->data();
  ParallelFor(size_t{0}, kSlices, [&](size_t s) {
    const auto [a, b] = slice(s);
    uint64_t* const c = &count[s * buckets];
    const Keyed* const from = in;
    Keyed* const to_keys = out;
    const Carry move = carry;
    const int right = shift;
    const uint64_t mask = buckets - 1;
    for (size_t i = a; i < b; ++i) {
      const Keyed k = from[i];
      const size_t to = c[(k.code >> right) & mask]++;
      to_keys[to] = k;
      move(k.index, to);
    }
  });
  // Each bucket sorted where it lies in scratch (keys its temporary), which then becomes keys:
  // no copy back. A coarse sort touches only the buckets of more than `coarse` keys, whose
  // records are then gathered again in their new order.
  Keyed* temp = keys->data();
  ParallelFor(tbb::blocked_range<size_t>(0, buckets, 16), [&](const tbb::blocked_range<size_t>& r) {
    Keyed* const sorted = out;
    const Carry move = carry;
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const size_t a = bucket_start[k], m = bucket_start[k + 1] - a;
      if (m < 2 || m <= coarse) continue;
      LocalRadixSort(sorted + a, temp + a, m, shift);
      for (size_t i = a; i < a + m; ++i) move(sorted[i].index, i);
    }
  });
  keys->swap(*scratch);
}

}  // namespace

void SortByCode(std::vector<Keyed>* keys, std::vector<Keyed>* scratch, int bits, size_t coarse) {
  Sort(keys, scratch, bits, coarse, NoRecords{});
}

void SortByCode(std::vector<Keyed>* keys, std::vector<Keyed>* scratch, int bits, size_t coarse,
                const void* records, size_t record_bytes, void* sorted_records) {
  CANDI_CHECK(record_bytes > 0 && (keys->empty() || (records != nullptr && sorted_records != nullptr)))
      << "SortByCode: records of " << record_bytes << " bytes";
  const auto* in = static_cast<const unsigned char*>(records);
  auto* out = static_cast<unsigned char*>(sorted_records);
  switch (record_bytes) {
    case 16:
      Sort(keys, scratch, bits, coarse, FixedRecords<16>{in, out});
      break;
    case 28:
      Sort(keys, scratch, bits, coarse, FixedRecords<28>{in, out});
      break;
    default:
      Sort(keys, scratch, bits, coarse, AnyRecords{in, out, record_bytes});
  }
}

}  // namespace candi::render
