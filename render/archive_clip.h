// The points of a render archive inside clipping regions, reading only the chunks they cross.
//
// A chunk is read when its box is not wholly outside every region (ClipRegion::Classify); its
// points are kept when inside one region at least (a union of regions: the slabs of an unrolled
// section's segments). Regions are in the archive's frame (ClipRegion::ToLocal of a world
// region). Positions are the dequantized ones (ChunkQuantizer::Decode), the same ones the
// renderer draws and clips. Chunks are decoded in parallel and concatenated in chunk order, so
// the result does not depend on the thread count.
// Failures: InputError from the archive (a chunk whose hash does not match, with `verify`).
// Thread-safe for distinct outputs (the archive is read-only).
#pragma once

#include <cstdint>
#include <vector>

#include "core/clip.h"
#include "core/point_cloud.h"
#include "core/progress.h"
#include "render/archive.h"

namespace candi::render {

struct ClippedReadOptions {
  std::vector<char> layers;  // per archive layer: read it (empty: every layer)
  bool verify = true;        // check each read chunk's hash
  int threads = 0;           // 0: as TBB allows
  // The most points kept (0: no limit): more is std::length_error, before they are all held.
  uint64_t max_points = 0;
  void Check() const {}
};

struct ClippedPoints {
  PointCloud cloud;          // archive frame; colours; `layers` holds the archive layer of each point
  std::vector<uint8_t> region;  // per point: the first region holding it
  uint64_t chunks = 0, chunks_read = 0, points_read = 0;
  double seconds = 0;
};

ClippedPoints ReadClipped(const ClippedReadOptions& options, const Archive& archive,
                          const std::vector<ClipRegion>& regions, const ProgressCallback& progress = nullptr);

}  // namespace candi::render
