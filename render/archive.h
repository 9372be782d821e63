// The render archive: a compact, chunked, memory-mapped point archive for streaming SPBR.
//
// A directory holding `manifest.json` and data files `data-NNNNN.bin`. Points are in Morton order
// (21 bits per axis over the archive's bounds) and cut into chunks of consecutive points that
// share a Morton prefix (at most `chunk_points` each), so every chunk covers a compact box. A
// point is one little-endian uint64 (8 bytes with colour):
//   bits 0..23   colour 0xRRGGBB
//   bits 24..    x (bx bits), then y (by bits), then z (bz bits); bx + by + bz = 40
// quantized on the chunk's bounding box (double, local frame): q = round((x - min) / step), half
// steps to even, step = extent / (2^b - 1). The 40 bits are shared out per chunk: each axis
// with an extent gets at least 1 bit, then each further bit goes to the axis with the largest
// step (at most 24 bits an axis); a flat axis (extent 0) gets 0 bits and step 0.
// Error bound per axis: |x - dequantized x| <= step / 2 = extent / (2^b - 1) / 2, plus the double
// rounding of min + q * step (a few ulps of the coordinates, ~1e-16 relative), tested in
// archive_test.cc. A chunk of 65536 points spanning 1 m gets 13-14 bits per axis: 0.06 mm.
// Version 2: chunks belong to one layer each (an input file, or the layer a build names): the
// points of each layer are Morton-sorted and chunked on their own. Within a chunk the points are
// in a seeded random order (a Fisher-Yates shuffle seeded by the pack seed and the chunk's
// index), so any run of them is a uniform sample of the chunk. SPBR ensemble e of a chunk of n
// points at repeat level L is its slice s = (e + r) mod L, points [floor(s n / L),
// floor((s + 1) n / L)), where r = HashIndex(render seed, chunk's first index) mod L (EnsembleSlices):
// every point falls in exactly one ensemble, a preview of k ensembles reads k/L of each chunk,
// and the seed still varies the draw. A layer drawn at a fraction f of its points (opacity: the
// point-number law, alpha' = 1 - (1 - alpha)^f) takes the first f of each slice, and for f > 1
// also of the next slices (each point then in up to ceil(f) ensembles, as multiplicities are).
// Point k of the archive (its position over all chunks) is its index for the stochastic
// rounding of point sizes above one pixel. Version 1 archives (hash-drawn ensembles, no layers)
// are refused: repack them.
// Integrity: each data file's size and each chunk's 64-bit hash are in the manifest; a missing
// or short file is an InputError at open, a chunk whose bytes do not match its hash an
// InputError when it is read (with verification on). Multiplicities (opacity control) are not
// stored: every point is one copy.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/box.h"
#include "core/field_colour.h"
#include "core/local_frame.h"
#include "core/point_cloud.h"

namespace candi::render {

inline constexpr int kArchiveVersion = 2;
inline constexpr int kArchivePositionBits = 40;
inline constexpr int kArchiveMaxAxisBits = 24;
inline constexpr const char* kArchiveManifest = "manifest.json";

// A 64-bit content hash (xxHash64's round function over 8-byte words, little-endian).
uint64_t ArchiveHash(const void* data, size_t bytes, uint64_t seed = 0);
// ArchiveHash (seed 0) of `count` (0 to 4) blocks of `bytes` bytes each, into out[0, count):
// the same values, the blocks hashed together where the CPU has AVX-512 (HashFile's blocks).
void ArchiveHashBlocks(const uint8_t* const* blocks, int count, size_t bytes, uint64_t* out);

// Quantization of one chunk's box.
struct ChunkQuantizer {
  Box3d box;             // local frame
  int bits[3] = {0, 0, 0};
  double step[3] = {0, 0, 0};

  static ChunkQuantizer ForBox(const Box3d& box);
  // The bound on |x - Dequantize(Quantize(x))| per axis (excluding double rounding).
  double ErrorBound(int axis) const { return 0.5 * step[axis]; }
  // Inline, so that callers compiled for AVX2 (the packer) round with one instruction instead of
  // a libm call; the same bits either way (nearbyint in the default rounding mode).
  uint64_t Encode(const Eigen::Vector3d& x, uint32_t rgb) const {
    uint64_t word = rgb & 0xffffff;
    int shift = 24;
    for (int a = 0; a < 3; ++a) {
      if (bits[a] == 0) continue;
      const double top = static_cast<double>((uint64_t{1} << bits[a]) - 1);  // exact (bits <= 24)
      const double t = std::clamp(std::nearbyint((x[a] - box.min[a]) / step[a]), 0.0, top);
      word |= static_cast<uint64_t>(t) << shift;
      shift += bits[a];
    }
    return word;
  }
  // Positions in the local frame: box.min + q * step per axis.
  Eigen::Vector3d Decode(uint64_t word) const {
    const uint64_t q = word >> 24;
    const uint64_t qx = q & ((uint64_t{1} << bits[0]) - 1);
    const uint64_t qy = (q >> bits[0]) & ((uint64_t{1} << bits[1]) - 1);
    const uint64_t qz = (q >> (bits[0] + bits[1])) & ((uint64_t{1} << bits[2]) - 1);
    return {box.min.x() + static_cast<double>(qx) * step[0], box.min.y() + static_cast<double>(qy) * step[1],
            box.min.z() + static_cast<double>(qz) * step[2]};
  }
  static uint32_t Color(uint64_t word) { return static_cast<uint32_t>(word & 0xffffff); }
};

struct ArchiveChunk {
  int file = 0;            // index into ArchiveManifest::files
  uint64_t offset = 0;     // byte offset in the file
  uint64_t count = 0;      // points
  uint64_t first = 0;      // archive index of the first point
  ChunkQuantizer quantizer;
  uint64_t hash = 0;       // ArchiveHash of the chunk's 8 * count bytes
  int layer = 0;           // index into ArchiveManifest::layers
};

struct ArchiveLayer {
  std::string name;
  uint64_t points = 0;
};

// The runs of a chunk's points that ensemble `ensemble` draws (see the top of this file): at
// fraction 1 one slice; at fraction f, ceil(f) runs, the first min(1, f - j) of slice s + j.
// Appends [begin, end) pairs (chunk-relative) with begin < end to `runs`.
struct PointRun {
  uint64_t begin = 0, end = 0;
};
void EnsembleSlices(uint64_t count, uint64_t chunk_first, int repeat_level, uint64_t seed, int ensemble,
                    double fraction, std::vector<PointRun>* runs);

struct ArchiveSource {
  std::string path;
  uint64_t bytes = 0;
  uint64_t hash = 0;       // ArchiveHash of the whole file
  uint64_t points = 0;
};

struct ArchiveFile {
  std::string name;        // relative to the archive directory
  uint64_t bytes = 0;
};

struct ArchiveManifest {
  int version = kArchiveVersion;
  LocalFrame frame;        // world = local + frame.origin
  Box3d bounds;            // local frame, of the (original) points
  uint64_t points = 0;
  uint64_t chunk_points = 0;  // the largest chunk allowed when packing
  uint64_t shuffle_seed = 1;  // the seed of the points' order within each chunk
  std::vector<ArchiveLayer> layers;
  std::vector<ArchiveSource> sources;
  std::vector<ArchiveFile> files;
  std::vector<ArchiveChunk> chunks;
  // Points packed coloured by a scalar field (candi pack --colour-by): the colouring, so that
  // renders draw its legend and pages read a picked colour back as the field's value.
  std::optional<FieldLegend> colour_by;

  std::string ToJson() const;
  // Throws InputError naming `path` and the field for anything malformed.
  static ArchiveManifest FromJson(const std::string& text, const std::string& path);
};

// True when `path` is a directory holding a manifest.json.
bool IsArchive(const std::string& path);
// The render archive `path` names: itself, a build directory's archive/, or a demo's output's
// archive/archive/ (what candi render, section, view and publish open); "" when none.
std::string FindArchive(const std::string& path);

// An open archive: the manifest and its data files, memory-mapped read-only.
class Archive {
 public:
  // Reads the manifest, checks that every data file exists with its recorded size, maps them.
  // Throws InputError naming the file for anything missing, short or malformed.
  explicit Archive(const std::string& directory);
  ~Archive();
  Archive(const Archive&) = delete;
  Archive& operator=(const Archive&) = delete;

  const std::string& directory() const { return directory_; }
  const ArchiveManifest& manifest() const { return manifest_; }
  // The chunk's words (count of them), mapped. With `verify`, hashes them first (the first time
  // this object reads the chunk; a chunk that matched once is not hashed again) and throws
  // InputError naming the data file, the chunk and its offset when they do not match.
  const uint64_t* ChunkWords(size_t chunk, bool verify) const;
  // Lets the kernel drop the chunks' mapped pages (bounded resident memory while streaming).
  // Chunks adjacent in a data file are released by one call: each call makes the kernel flush
  // the TLBs of every thread of the process.
  void Release(size_t chunk) const { Release(std::vector<size_t>{chunk}); }
  void Release(std::vector<size_t> chunks) const;
  // Decodes a chunk into a PointCloud in the archive's frame (positions dequantized, colours).
  void ReadChunk(size_t chunk, PointCloud* out, bool verify = true) const;
  // Every point, dequantized (tests; small archives).
  PointCloud ReadAll() const;

 private:
  std::string directory_;
  ArchiveManifest manifest_;
  struct Mapping {
    void* data = nullptr;
    size_t bytes = 0;
  };
  std::vector<Mapping> maps_;
  std::unique_ptr<std::atomic<uint8_t>[]> verified_;  // per chunk: its hash matched
};

}  // namespace candi::render
