// Stable sort of (code, index) keys by the low bits of the code, for the render archive's
// packer (Morton codes whose high bits are already equal within a cell).
//
// One parallel pass buckets the keys by their top 11 bits to be sorted (fixed slices of the
// input counted and scattered in parallel, in order, so the result does not depend on the
// threads), then every bucket is sorted on the rest in the cache (8-bit LSD digits, a digit whose
// values are all equal skipped), buckets in parallel: one memory-bound pass instead of the five
// of a plain LSD radix sort.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace candi::render {

// 12 bytes (4-byte aligned): the sort moves a quarter fewer bytes than with a 64-bit index.
#pragma pack(push, 4)
struct Keyed {
  Keyed() {}  // uninitialized: the sort's vectors grow without zeroing what is written next
  Keyed(uint64_t code, uint32_t index) : code(code), index(index) {}
  uint64_t code;
  uint32_t index;  // the key's position in the input, say
};
#pragma pack(pop)
static_assert(sizeof(Keyed) == 12, "Keyed must be 12 bytes");

// A stable counting sort's offsets: *counts holds, for each of `slices` consecutive slices of
// the input, its count in each of `buckets` buckets (row-major, slice by slice). Replaces every
// count with where that slice's first item of that bucket goes (buckets in order, the slices in
// order within each) and returns where each bucket starts (buckets + 1 entries, the last the
// total).
std::vector<uint64_t> StableBucketOffsets(std::vector<uint64_t>* counts, size_t slices, size_t buckets);

// Sorts *keys stably by code & (2^bits - 1) (the bits above must be equal: they are not looked
// at); *scratch is resized and used as scratch (the two vectors may trade their storage: the
// sorted keys are left where they were bucketed). bits in [0, 64].
//
// `coarse` > 0 (bits a multiple of 3, Morton levels of 3 bits): sorts only as far as a cut into
// nodes of at most `coarse` keys looks. The keys are bucketed, stably, by their next 4 levels
// (12 bits); a bucket of more than `coarse` keys is then sorted whole, the others keep their
// input order. So every node with more than `coarse` keys is a contiguous range whose children
// follow in Morton order. The archive's packer, whose chunks (at most `coarse` points) are
// shuffled after the cut, needs no more.
void SortByCode(std::vector<Keyed>* keys, std::vector<Keyed>* scratch, int bits, size_t coarse = 0);

// As SortByCode, and records move with their keys: sorted_records ends holding, for the j-th
// sorted key k, the record of input position k.index (records and sorted_records: distinct
// arrays of record_bytes-byte records). The records are moved as the keys are bucketed, read in
// their input order, so that keys whose index is their input position (the packer's) get them
// without a random read each; only buckets sorted further are gathered by index again.
void SortByCode(std::vector<Keyed>* keys, std::vector<Keyed>* scratch, int bits, size_t coarse,
                const void* records, size_t record_bytes, void* sorted_records);

}  // namespace candi::render
