// SPBR of points that stream through in chunks: the renderer holds frame buffers and a bounded
// chunk, never the cloud.
//
// Points are staged for the resident ensembles by parallel blocks (each ensemble's points in the
// stream's order), then each ensemble is drawn by one thread: chunk by chunk into its resident
// z-buffer, or, when few points are expected (SpbrStreamOptions::expected_points), all of its
// points gathered at the end of the pass.
// Ensembles are assigned exactly as in SplatCloud (a seeded hash of each point's index in the
// stream, m copies in m distinct ensembles). A pass keeps K ensembles' z-buffers resident (K from
// the memory budget: 8 bytes a pixel each) and the caller feeds every point once per pass; with
// K >= L one pass suffices. Positions are used at full float precision in the render frame (no
// 16-bit quantization), so images match the in-memory renderer's statistically, not bit for bit.
// Deterministic: the same points, order and seed give the same image for any thread count, chunk
// size or budget.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/local_frame.h"
#include "core/point_cloud.h"
#include "core/spbr_settings.h"
#include "io/point_file.h"
#include "render/camera.h"
#include "render/spbr.h"

namespace candi::render {

struct SpbrStreamOptions {
  SpbrSettings spbr;             // L, seed, point size; opaque: L = 1, no multiplicities
  bool use_multiplicity = true;  // honour `spbr_multiplicity` (unless spbr.opaque)
  Rgb8 default_color{200, 200, 200};             // for clouds without colours
  uint64_t memory_budget = uint64_t{1} << 30;    // bytes for resident z-buffers, >= one frame
  // The points a pass brings, when known (0: not). Few enough that their staged copies (16 bytes
  // each, 24 with point sizes) take no more than the resident z-buffers would: one pass gathers
  // them by ensemble and draws each ensemble at its end in one thread's z-buffer, so L frames'
  // z-buffers are never held (faulting them in was a third of a 2·10^7-point render). The same
  // image either way.
  uint64_t expected_points = 0;
  int threads = 0;                               // 0: as TBB allows
  void Check() const;
};

class SpbrStreamRenderer {
 public:
  // `camera` is in `frame` (the render frame; chunks may come in other frames).
  SpbrStreamRenderer(const SpbrStreamOptions& options, const Camera& camera, const LocalFrame& frame);
  ~SpbrStreamRenderer();

  int passes() const;          // how many times the caller must feed all points
  int ensembles_per_pass() const;
  void BeginPass(int pass);    // points are numbered from 0 again
  void Add(const PointCloud& chunk);  // throws InputError for NaN positions
  // Adds n point records of `layout` at `records` (io/point_records.h: a file read in place),
  // their positions in the frame whose origin is `origin` (the reader's info().frame): the same
  // image as Add() of the chunks the reader gives, without them. Throws InputError for NaN.
  void AddRecords(const uint8_t* records, const io::PointRecordLayout& layout, const Eigen::Vector3d& origin,
                  size_t n);
  void EndPass();
  SpbrResult Finish();         // after the last EndPass

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace candi::render
