// Dense stereo on a COLMAP dense workspace in bounded memory, resumable: the photos stream
// through three stages, each writing one file a photo (or a cell) under WORKSPACE/stereo/:
//
//   1. sources  patch-match.cfg (COLMAP's format): each photo's sources, chosen once from the
//               sparse model (source_views.h) and used by every stage below;
//   2. stereo   candi/<name>.raw.bin: PatchMatch of the photo against its sources. Only the photo
//               and its sources' images are needed; they come through a cache of at most
//               `max_memory` bytes (least recently used out first);
//   3. filter   candi/<name>.filtered.bin, and depth_maps/ + normal_maps/<name>.geometric.bin
//               (COLMAP's arrays, for its stereo_fusion): the consistency filter against the
//               neighbours' raw maps (its sources and the photos that have it as a source);
//   4. fusion   candi/fused/tile_<k>.bin: fusion.h's cells, each from the filtered maps of the
//               views with pixels in it, run in parallel as far as `max_memory` allows.
//
// Every file is written atomically and is the resume point: run again after an interruption, a
// stage keeps the files it finds and says how many. candi/settings.txt holds what the files
// depend on (the options, the model's bytes, the images' sizes and times); when it differs, the
// earlier files are removed first. Peak memory does not grow with the number of photos: stereo
// holds one photo's map and the cache, the filter a photo's and its neighbours' maps, fusion the
// maps of as many cells as run at once.
//
// Same bytes as RunPatchMatch + FuseDepthMaps on the workspace when the model's cells are one;
// the same bytes whatever the thread count, and whether or not the run was interrupted.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "reconstruction/photogrammetry/mvs/fusion.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"

namespace candi::photogrammetry {

struct DenseStreamOptions {
  PatchMatchOptions stereo;
  FusionOptions fusion;
  uint64_t max_memory = 0;   // bytes of images and maps held at once; 0 = a quarter of the machine's
  bool keep_maps = true;     // false: WORKSPACE/stereo's files are removed after a finished run
  // Called after each file is committed, with the stage ("stereo", "filter", "fusion") and the
  // files of that stage done so far (tests stop a run here).
  std::function<void(const std::string& stage, size_t done)> committed;
  // Under mpirun (pipeline/dense_ranks.h): this process is `rank` of `ranks`; photo r and cell t
  // are rank (r mod ranks)'s and (t mod ranks)'s. `all_gather` is collective (each rank's string
  // to every rank, in rank order); it ends every stage, so no rank starts a stage before all the
  // files of the one before are written, and one rank's failure fails them all. Rank 0 writes the
  // settings and gathers the cells into the cloud; the others return no points.
  int rank = 0, ranks = 1;
  std::function<std::vector<std::string>(const std::string&)> all_gather;
  // When set, rank 0 hands the points over cell by cell, in cell order, as it reads them back (a
  // point file's writer), and the result's cloud stays empty: the points are never all held.
  std::function<void(const PointCloud& cell)> cells_out;
  void Check() const;
};

struct DenseStreamResult {
  PointCloud cloud;                      // fused points with colours and normals, the model's frame
  size_t points = 0;                     // fused points (in `cloud`, or handed to cells_out)
  size_t images = 0, sparse_points = 0;
  bool sources_from_tracks = false;      // false: the model has no tracks (the geometric rule)
  // Counts over every rank (under mpirun: added up at the end of each stage).
  size_t maps_found = 0, maps_made = 0;  // stereo: found finished on disk, computed now
  size_t filtered_found = 0, tiles = 0, tiles_found = 0;
  std::vector<std::string> empty_maps;   // photos with no depth after the filter
  uint64_t valid_pixels = 0, total_pixels = 0;
  double stereo_seconds = 0, filter_seconds = 0, fusion_seconds = 0;
  uint64_t max_memory = 0;               // the budget used
  uint64_t peak_cache_bytes = 0;         // images held by this rank's stereo cache at most
  bool settings_changed = false;         // earlier files were found and removed
};

// InputError for a workspace that cannot be read (naming the file) or written (naming the path).
DenseStreamResult RunDenseStream(const DenseStreamOptions& options, const std::string& workspace);

// What the machine offers by default: a quarter of its physical memory.
uint64_t DefaultDenseMemory();

}  // namespace candi::photogrammetry
