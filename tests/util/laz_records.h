// Test helper (header-only, for io's tests): the point records of a LAZ file, decoded through the
// chunk table and chunk decoders of io/laz, and the file's laszip VLR.
#pragma once

#include <cstdint>
#include <string>

#include "core/binary_file.h"
#include "io/las/las_header.h"
#include "io/laz/laz_chunks.h"
#include "io/laz/laz_format.h"

namespace candi::testing {

inline io::laz::Vlr LaszipVlrOf(BinaryFile* file, const io::LasHeader& header) {
  io::laz::Vlr vlr;
  for (const LasVlr& v : io::ReadLasVlrs(file, header)) {
    if (v.user_id == "laszip encoded") vlr = io::laz::ParseVlr(v.data);
  }
  return vlr;
}

// The decoded records of a LAZ file.
inline std::string LazRecords(const std::string& path) {
  BinaryFile file(path);
  io::LasHeader header = io::ReadLasHeader(&file);
  header.point_format &= 0x3F;
  const io::laz::Vlr vlr = LaszipVlrOf(&file, header);
  const uint64_t count = io::LasPointCount(header);
  io::LazPointData data(
      &file, vlr,
      io::ReadLazChunkTable(file, vlr, header.offset_to_point_data, count, header.record_length),
      header.record_length);
  std::string records;
  for (uint64_t done = 0; done < count;) {
    size_t n = 0;
    const uint8_t* r = data.Records(done, count, &n);
    records.append(reinterpret_cast<const char*>(r), n * header.record_length);
    done += n;
  }
  return records;
}

}  // namespace candi::testing
