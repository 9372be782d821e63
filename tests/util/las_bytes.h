// Test helper (header-only): little-endian fields of a LAS/LAZ file held in a string, read and
// patched in place by byte offset (LAS 1.4 R15 table 3 gives the header's offsets), and the point
// records located from the file's own header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/binary_file.h"

namespace candi::testing {

// The little-endian T at byte `at` of `bytes`.
template <typename T>
T GetLE(const std::string& bytes, size_t at) {
  return LoadLE<T>(reinterpret_cast<const uint8_t*>(bytes.data()) + at);
}
// Overwrites the little-endian T at byte `at` of `*bytes`.
template <typename T>
void PutLE(std::string* bytes, size_t at, T v) {
  StoreLE<T>(reinterpret_cast<uint8_t*>(bytes->data()) + at, v);
}

// The point records of an uncompressed LAS file's bytes: offset to point data (byte 96), record
// length (105) and count (107, or the 64-bit count at 247 of a LAS 1.4 file that leaves it 0).
inline std::string LasPointRecords(const std::string& file) {
  const uint32_t offset = GetLE<uint32_t>(file, 96);
  const uint16_t length = GetLE<uint16_t>(file, 105);
  uint64_t count = GetLE<uint32_t>(file, 107);
  if (count == 0 && file[25] >= 4) count = GetLE<uint64_t>(file, 247);
  return file.substr(offset, count * length);
}

}  // namespace candi::testing
