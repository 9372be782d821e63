// Packing point files into a render archive (render/archive.h), streaming with bounded memory.
//
// Pass 1 finds the bounds (LAS headers, else a read of the points) and the archive's frame (the
// render frame: origin at the centre, rounded to metres). Files of records are read directly
// (render/pack_input.h): for binary PLY one read gives the bounds and the manifest's hash (and,
// for doubles, whether each is a float), and pass 2 takes records of floats without widening
// them to doubles; LAS (bounds from its
// header) is sorted as its integers when all inputs share a scale and offset. Other inputs, and
// LAS, are hashed on another thread. Pass 2 reads the points once more and
// computes 63-bit Morton codes (21 bits per axis over the bounds). Inputs of at most
// `memory_points` points are sorted in memory; larger ones are bucketed by the top Morton bits
// into up to 512 cell files on disk (16 bytes a point when every input point is a float in one
// frame shared by the inputs, as in binary PLY with float x, y, z, or all inputs are LAS with one
// scale and offset; else 28), then each cell, in
// Morton order, is sorted in memory, only as far as the chunk cut looks (render/morton_sort.h's
// `coarse`: a chunk is shuffled anyway; a cell still too large is bucketed again by the next bits),
// so memory stays ~ 100 bytes x memory_points (400 MB by default) whatever the input size.
// Each layer (PackInput::layer) is sorted and chunked on its own, so a chunk holds one layer.
// Sorted points are cut into chunks of consecutive points sharing a Morton prefix
// (<= chunk_points each), quantized and written to data files of ~file_bytes. The output
// directory appears complete or not at all. Within a chunk the points are then shuffled
// (seeded by options.seed and the chunk's index; render/archive.h). The output (built beside it, then renamed; an existing archive
// there is replaced, anything else refused).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/field_colour.h"
#include "core/progress.h"
#include "io/point_io.h"
#include "render/archive.h"

namespace candi::render {

struct PackOptions {
  uint64_t chunk_points = 65536;               // points per chunk at most, [64, 2^24]
  uint64_t memory_points = uint64_t{4} << 20;  // points sorted in memory at once, >= chunk_points
  uint64_t file_bytes = uint64_t{1} << 30;     // data files are cut at chunk ends past this size
  Rgb8 default_color{200, 200, 200};           // for inputs without colours
  uint64_t seed = 1;                           // the points' random order within each chunk
  int threads = 0;                             // 0: as TBB allows
  // Sort 28-byte double records even when every point is a float in one frame (16-byte ones
  // then; the same archive either way). For tests and benchmarks.
  bool wide_records = false;
  // Read files of records (io/point_io.h's PointRecordLayout: binary PLY of floats, LAS)
  // directly: PLY's bounds and hash from one read, records without widening to doubles. false:
  // through their point readers (the same archive). For tests and benchmarks.
  bool direct_reads = true;
  // The inputs' colours are a scalar field's (PackFiles with a colouring): recorded in the
  // manifest (ArchiveManifest::colour_by).
  std::optional<FieldLegend> colour_by;
  void Check() const;
};

// One input: a name for messages and the manifest, and how to open it (called twice: bounds,
// then points). `path` (may be empty, e.g. generated points) is hashed into the manifest.
struct PackInput {
  std::string name;
  std::string path;
  // The archive layer the points go to; inputs naming the same layer are packed together.
  // PackInputFromFile: the file's stem; PackInputFromGenerator: the name.
  std::string layer;
  std::function<std::unique_ptr<io::PointReader>()> open;
};
// `columns`: the XYZ/PTS column spec (io/point_io.h), "" for the default.
PackInput PackInputFromFile(const std::string& path, const std::string& columns = "");
// Points made on demand, `piece` at a time: make(k, n) returns piece k (n points, any frame).
// For generated data (benchmarks, tests) that never touches a point file.
PackInput PackInputFromGenerator(const std::string& name, uint64_t total, uint64_t piece,
                                 std::function<PointCloud(uint64_t k, uint64_t n)> make);

struct PackSummary {
  uint64_t points = 0, chunks = 0, files = 0, bytes = 0;
  uint64_t spilled_points = 0;  // points that went through cell files on disk (external sort)
  size_t record_bytes = 0;      // bytes a point while sorting: 16 (floats in one frame) or 28
  double seconds = 0;           // whole pack, including bounds and hashing
  // Its stages: the bounds (pass 1), reading, sorting and writing the chunks (pass 2), and
  // hashing the input files for the manifest (on another thread, during both passes; binary PLY
  // is hashed by pass 1 itself and not counted here).
  double bounds_seconds = 0, sort_seconds = 0, hash_seconds = 0;
  double max_error[3] = {0, 0, 0};  // largest quantization step / 2 over the chunks, m
  std::optional<FieldLegend> colour_by;  // the colouring by a field the manifest records
};

PackSummary PackArchive(const PackOptions& options, const std::vector<PackInput>& inputs,
                        const std::string& output_dir, const ProgressCallback& progress = nullptr);
// Point files (one layer each, named by the file's stem; `columns` for XYZ/PTS) packed into
// `output_dir`. With `colour_by` active, the points are coloured by that scalar field (one
// colouring over every file, resolved from their values before anything is written; InputError
// naming a file without the field), and the manifest records the colouring.
PackSummary PackFiles(const PackOptions& options, const std::vector<std::string>& files, const std::string& columns,
                      const std::string& output_dir, const ProgressCallback& progress = nullptr,
                      const FieldColouring& colour_by = FieldColouring());

// The inputs of point files whose colours are replaced by a scalar field's in `legend` (resolved
// over every file's values by ResolveFieldColouringOfFiles). Each reads the file with its
// scalar fields; `legend` must outlive them.
std::vector<PackInput> PackInputsColouredByField(const std::vector<std::string>& files, const std::string& columns,
                                                 const FieldLegend& legend);
// The colouring of `colour_by` over the values of every file's field (one read of each).
FieldLegend ResolveFieldColouringOfFiles(const std::vector<std::string>& files, const std::string& columns,
                                         const FieldColouring& colour_by, const ProgressCallback& progress = nullptr);

// The hash of a file recorded in the manifest: xxHash64 over the xxHash64s of its 64 MiB blocks.
uint64_t HashFile(const std::string& path, uint64_t* bytes);

}  // namespace candi::render
