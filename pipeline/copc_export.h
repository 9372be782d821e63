// COPC (https://copc.io, LAS 1.4 with an octree of LAZ chunks) of a build's layers, for tools that
// stream point clouds: Potree, QGIS (3.26 on), CloudCompare, PDAL, copc.js. What a build writes
// when its scene asks ("copc": {"layers": true, "scene": true}; scene.h) and what
// `candi export copc` writes from a finished build (pipeline/build.h) without rebuilding; both
// read the layer files (layers/<name>.ply) and go through the same code, so they give the same
// bytes.
//
//   layers/<name>.copc.laz   one layer
//   copc/<scene>.copc.laz    every layer in one file (the scene's name, characters other than
//                            [A-Za-z0-9_.-] as '_')
// Each point keeps its world position (to the LAS scale, kCopcScale: 1 mm; the LAS offset is the
// scene's frame origin), its colour (8-bit, stored as 16-bit x 257) and its layer as the LAS
// point source ID: the layer's index in the scene (0-based, the order of archive.json's "layers"
// and of the layer PLYs' scalar_scene_layer). Point source ID is a standard LAS attribute every
// viewer shows and colours by (Potree's "point source id", QGIS's PointSourceId, CloudCompare's
// "Point Source ID"), where an extra-bytes field is not shown by every one and classification has
// the ASPRS classes' meaning. A "candi" VLR (record kCopcLayersRecord) names the layers, one
// "<index>=<name>" a line. The scene's CRS goes in as a WKT VLR (none when the scene has none).
// The header's creation date is 1 January 1970 (day 1): a fixed date, as reproducible builds
// date their files, so that the same layers give the same bytes. Normals and the PLYs' other
// scalar fields are left out.
//
// Failures: InputError naming the file: a folder that is not a finished build (no archive.json,
// or one without the keys a build writes), a missing or unreadable layer file, an unwritable
// output, positions beyond the LAS integers' range. Every file is written atomically. Not
// thread-safe (one call at a time); the same bytes for any thread count (io/copc/copc_write.h).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/progress.h"

namespace candi::pipeline {

inline constexpr double kCopcScale = 0.001;       // m, the LAS scale of every axis
inline constexpr uint16_t kCopcLayersRecord = 1;  // the "candi" VLR naming the layers

// Which COPC files to write. The scene file's "copc" sets it for a build (default: none, since
// writing them costs time); `candi export copc` sets `layers` by its flag and always writes the
// scene's file.
struct CopcOptions {
  bool layers = false;  // each layer as layers/<name>.copc.laz
  bool scene = false;   // every layer in one file, copc/<scene>.copc.laz
  // The memory each file's records may take until it is complete, beyond which they are spilled
  // beside it (io::CopcWriteOptions::memory_bytes; 0: half this machine's). Not the scene file's
  // (`candi build --copc-memory`, `candi export copc --copc-memory`); the bytes do not depend on it.
  uint64_t memory_bytes = 0;
  void Check() const {}
};

// A build's layers as written, and what the COPC files take from the build.
struct CopcSource {
  std::string name;  // the scene's
  std::string crs;   // the scene's CRS (any string PROJ reads), or ""
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the scene's frame origin, world, m
  std::vector<std::string> layer_names;              // in scene order
  std::vector<std::string> layer_files;              // layers/<name>.ply, paths as found
};

// One COPC file written.
struct CopcFile {
  std::string path;   // as written
  std::string layer;  // the layer's name; "" for the whole scene
  uint64_t points = 0;
  uint64_t bytes = 0;
};

// The whole scene's file name: copc/<name>.copc.laz, the name's unsafe characters as '_'.
std::string SceneCopcName(const std::string& scene_name);

// Writes what `options` asks: each layer beside its layer file (<name>.copc.laz in the same
// folder) and the whole scene to `scene_file`. Returns the files, layers first, in scene order.
// progress: points read; close_progress: each file's closing stages (its octree, its chunks) as
// "<file name> <stage>".
std::vector<CopcFile> WriteCopc(const CopcOptions& options, const CopcSource& source,
                                const std::string& scene_file,
                                const ProgressCallback& progress = nullptr,
                                const StageProgressCallback& close_progress = nullptr);

// A finished build's layers, from its archive.json.
CopcSource ReadCopcSource(const std::string& build_dir);

struct CopcExportOptions {
  std::string build;  // a finished build's folder (archive.json, layers/)
  std::string out;    // the whole scene's file; "" : <build>/copc/<scene>.copc.laz
  CopcOptions copc{false, true};
  void Check() const;
};

// `candi export copc`: the COPC files of a finished build, from its layer files.
// close_progress: each file's closing stages (its octree, its chunks) as "<file name> <stage>".
std::vector<CopcFile> ExportCopc(const CopcExportOptions& options,
                                 const ProgressCallback& progress = nullptr,
                                 const StageProgressCallback& close_progress = nullptr);

}  // namespace candi::pipeline
