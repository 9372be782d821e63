#include "render/archive_clip.h"

#include <tbb/task_arena.h>

#include <chrono>

#include "core/check.h"
#include "core/parallel.h"

namespace candi::render {

namespace {

// The kept points of one chunk, in its stored order.
struct ChunkPart {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Rgb8> colors;
  std::vector<uint8_t> region;
};

void ReadChunkPart(const Archive& archive, size_t k, const std::vector<ClipRegion>& regions,
                   const std::vector<ClipRelation>& relation, bool verify, ChunkPart* out) {
  const ArchiveChunk& c = archive.manifest().chunks[k];
  const uint64_t* words = archive.ChunkWords(k, verify);
  for (uint64_t i = 0; i < c.count; ++i) {
    const Eigen::Vector3d x = c.quantizer.Decode(words[i]);
    for (size_t r = 0; r < regions.size(); ++r) {
      if (relation[r] == ClipRelation::kOutside) continue;
      if (relation[r] == ClipRelation::kPartial && !regions[r].Contains(x)) continue;
      const uint32_t rgb = ChunkQuantizer::Color(words[i]);
      out->positions.push_back(x);
      out->colors.push_back({static_cast<uint8_t>(rgb >> 16), static_cast<uint8_t>(rgb >> 8), static_cast<uint8_t>(rgb)});
      out->region.push_back(static_cast<uint8_t>(r));
      break;
    }
  }
}

}  // namespace

ClippedPoints ReadClipped(const ClippedReadOptions& options, const Archive& archive,
                          const std::vector<ClipRegion>& regions, const ProgressCallback& progress) {
  CANDI_CHECK(!regions.empty() && regions.size() <= 255);
  const auto start = std::chrono::steady_clock::now();
  const ArchiveManifest& m = archive.manifest();
  CANDI_CHECK(options.layers.empty() || options.layers.size() == m.layers.size());
  // Which chunks to read, and how each region meets them.
  std::vector<size_t> crossed;
  std::vector<std::vector<ClipRelation>> relations;
  uint64_t total = 0;
  for (size_t k = 0; k < m.chunks.size(); ++k) {
    if (!options.layers.empty() && !options.layers[m.chunks[k].layer]) continue;
    std::vector<ClipRelation> rel;
    bool any = false;
    for (const ClipRegion& r : regions) {
      rel.push_back(r.Classify(m.chunks[k].quantizer.box));
      any |= rel.back() != ClipRelation::kOutside;
    }
    if (!any) continue;
    crossed.push_back(k);
    relations.push_back(std::move(rel));
    total += m.chunks[k].count;
  }
  ClippedPoints out;
  out.chunks = m.chunks.size();
  out.chunks_read = crossed.size();
  PointSchema schema;
  schema.colors = true;
  schema.layers = true;
  out.cloud.SetSchema(schema);
  out.cloud.frame = m.frame;
  // Groups of chunks: decoded in parallel, appended in order, released (bounded memory).
  const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads);
  const size_t group = static_cast<size_t>(16 * threads);
  for (size_t g = 0; g < crossed.size(); g += group) {
    const size_t n = std::min(group, crossed.size() - g);
    std::vector<ChunkPart> parts(n);
    arena.execute([&] {
      ParallelFor(size_t{0}, n, [&](size_t i) {
        ReadChunkPart(archive, crossed[g + i], regions, relations[g + i], options.verify, &parts[i]);
      });
    });
    for (size_t i = 0; i < n; ++i) {
      const ChunkPart& p = parts[i];
      const uint16_t layer = static_cast<uint16_t>(m.chunks[crossed[g + i]].layer);
      out.cloud.positions.insert(out.cloud.positions.end(), p.positions.begin(), p.positions.end());
      out.cloud.colors.insert(out.cloud.colors.end(), p.colors.begin(), p.colors.end());
      out.cloud.layers.insert(out.cloud.layers.end(), p.positions.size(), layer);
      out.region.insert(out.region.end(), p.region.begin(), p.region.end());
      out.points_read += m.chunks[crossed[g + i]].count;
    }
    if (options.max_points > 0 && out.cloud.size() > options.max_points) {
      throw std::length_error("the clipped region holds more than " + std::to_string(options.max_points) +
                              " points (the limit; " + std::to_string(out.cloud.size()) + " in the first " +
                              std::to_string(g + n) + " of " + std::to_string(crossed.size()) + " chunks)");
    }
    archive.Release(std::vector<size_t>(crossed.begin() + g, crossed.begin() + g + n));
    if (progress) progress(out.points_read, total);
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace candi::render
