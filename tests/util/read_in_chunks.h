// Test helper (header-only; link candi_io): a point reader read to the end in chunks of a chosen
// size, so that tests can vary the chunking a reader sees.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>

#include "core/point_cloud.h"
#include "io/point_file.h"

namespace candi::testing {

// The points `reader` has left, read `chunk_size` at a time, in a cloud with the reader's schema
// and metadata (its frame is left at the default). Expects points_read() to end at info().count.
inline PointCloud ReadInChunks(io::PointReader& reader, size_t chunk_size) {
  PointCloud cloud;
  cloud.SetSchema(reader.info().schema);
  cloud.meta = reader.info().meta;
  PointCloud chunk;
  while (reader.Read(chunk_size, &chunk) > 0) cloud.Append(chunk);
  EXPECT_EQ(reader.points_read(), reader.info().count);
  return cloud;
}

}  // namespace candi::testing
