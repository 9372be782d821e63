#include "render/archive_pack.h"

#include <unistd.h>
#include <tbb/blocked_range.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <future>
#include <optional>
#include <type_traits>

#include "core/atomic_file.h"
#include "core/binary_file.h"
#include "core/check.h"
#include "core/fresh_memory.h"
#include "core/interrupt.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "core/spill_file.h"
#include "render/morton_sort.h"
#include "render/pack_input.h"
#include "render/pack_records.h"
#include "render/splat_cloud.h"

namespace candi::render {

namespace fs = std::filesystem;

void PackOptions::Check() const {
  CANDI_CHECK_OPTION_IN(chunk_points, 64, 16777216);  // 2^24
  // A cell's points are indexed by 32 bits.
  CANDI_CHECK_OPTION(memory_points < (uint64_t{1} << 32), memory_points, "< 2^32");
  CANDI_CHECK_OPTION(memory_points >= chunk_points, memory_points,
                     ">= chunk_points (" + std::to_string(chunk_points) + ")");
  CANDI_CHECK_OPTION_MSG(file_bytes >= 8 * chunk_points, file_bytes,
                         "must hold at least one chunk");
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
}

PackInput PackInputFromFile(const std::string& path, const std::string& columns) {
  PackInput in;
  in.name = path;
  in.path = path;
  in.layer = fs::path(path).stem().string();
  in.open = [path, columns] {
    io::PointReadOptions read;
    read.columns = columns;
    read.scalar_fields = false;
    return io::OpenPointReader(path, read);
  };
  return in;
}

namespace {

class GeneratedReader : public io::PointReader {
 public:
  GeneratedReader(const std::string& name, uint64_t total, uint64_t piece,
                  std::function<PointCloud(uint64_t, uint64_t)> make)
      : io::PointReader(name), total_(total), piece_(piece), make_(std::move(make)) {
    info_.count = total;
    info_.description = "generated";
    info_.schema.colors = true;
  }
  size_t Read(size_t max_points, PointCloud* chunk) override {
    if (at_ >= cloud_.size()) {
      if (next_ * piece_ >= total_) return 0;
      cloud_ = make_(next_, std::min(piece_, total_ - next_ * piece_));
      ++next_;
      at_ = 0;
      if (cloud_.empty()) return 0;
    }
    const size_t n = std::min<size_t>(max_points, cloud_.size() - at_);
    chunk->SetSchema(cloud_.schema);
    chunk->frame = cloud_.frame;
    chunk->Resize(0);
    chunk->positions.assign(cloud_.positions.begin() + at_, cloud_.positions.begin() + at_ + n);
    if (cloud_.schema.colors) chunk->colors.assign(cloud_.colors.begin() + at_, cloud_.colors.begin() + at_ + n);
    if (cloud_.schema.alphas) chunk->alphas.assign(cloud_.alphas.begin() + at_, cloud_.alphas.begin() + at_ + n);
    chunk->Resize(n);
    at_ += n;
    points_read_ += n;
    return n;
  }

 private:
  uint64_t total_, piece_;
  std::function<PointCloud(uint64_t, uint64_t)> make_;
  PointCloud cloud_;
  uint64_t next_ = 0;
  size_t at_ = 0;
};

}  // namespace

PackInput PackInputFromGenerator(const std::string& name, uint64_t total, uint64_t piece,
                                 std::function<PointCloud(uint64_t k, uint64_t n)> make) {
  CANDI_CHECK(piece > 0) << "PackInputFromGenerator: piece 0";
  PackInput in;
  in.name = name;
  in.layer = name;
  in.open = [=] { return std::unique_ptr<io::PointReader>(new GeneratedReader(name, total, piece, make)); };
  return in;
}

namespace {

using namespace pack_internal;

// Pass 1 bounds and pass 2 converts the points in parallel blocks of this many.
constexpr size_t kBoundsBlock = size_t{1} << 14;

// Points are routed to their cells in pieces of this many (the pieces do not depend on the
// thread count, so neither do the cell files).
constexpr size_t kRoutePiece = size_t{1} << 16;

// A source of points in batches: returns false at the end.
template <typename P>
using Batches = std::function<bool(UninitVector<P>*)>;

// P: WidePoint, CompactPoint or LasPoint; `frame` turns its records into archive positions.
template <typename P>
class Packer {
 public:
  Packer(const PackOptions& o, const std::string& dir, const MortonGrid& grid, const RecordFrame& frame,
         uint64_t total, const ProgressCallback& progress)
      : o_(o), dir_(dir), grid_(grid), frame_(frame), total_(total), progress_(progress) {}

  // Sorts points (all of one cell at `level`) in memory and writes their chunks.
  void AddCell(const P* points, size_t n, int level) {
    if (n == 0) return;
    Reserve(n);
    keys_.resize(n);
    ParallelFor(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
      uint64_t codes[256];
      for (size_t a = r.begin(); a < r.end(); a += 256) {
        const size_t m = std::min<size_t>(256, r.end() - a);
        MortonCodes(grid_, frame_, points + a, m, codes);
        for (size_t i = 0; i < m; ++i) keys_[a + i] = {codes[i], static_cast<uint32_t>(a + i)};
      }
    });
    // Sorted only as far as Cut looks: chunks of at most chunk_points are shuffled anyway. The
    // records move with their keys.
    sorted_.resize(n);
    SortByCode(&keys_, &scratch_, 63 - 3 * level, o_.chunk_points, points, sizeof(P), sorted_.data());
    ranges_.clear();
    Cut(0, n, level);
    WriteChunks();
  }

  // Buckets a stream of points (one cell at `level`, `count` of them) into cell files by the
  // next Morton levels, then handles each cell in Morton order.
  void Spill(const Batches<P>& source, uint64_t count, int level) {
    if (level >= kMortonBits) {  // every code equal: any order is Morton order
      UninitVector<P> batch;
      while (source(&batch)) {
        for (size_t i = 0; i < batch.size(); i += o_.chunk_points) {
          UninitVector<P> part(batch.begin() + i,
                                       batch.begin() + std::min<size_t>(batch.size(), i + o_.chunk_points));
          AddCell(part.data(), part.size(), kMortonBits);
        }
      }
      return;
    }
    int k = 1;
    while (k < 3 && level + k < kMortonBits && count >> (3 * k) > o_.memory_points / 2) ++k;
    const size_t cells = size_t{1} << (3 * k);
    std::vector<std::unique_ptr<SpillRecords<P>>> files(cells);
    const std::string stem = dir_ + "/cell-L" + std::to_string(level) + "-" + std::to_string(spill_id_++) + "-";
    for (size_t c = 0; c < cells; ++c) files[c] = std::make_unique<SpillRecords<P>>(stem + std::to_string(c) + ".tmp");
    UninitVector<P> batch;
    UninitVector<P> grouped;
    UninitVector<uint16_t> cell;
    std::vector<uint64_t> at;  // per piece and cell: its count, then where its points go
    while (source(&batch)) {
      spilled_ += batch.size();
      // A counting sort of the batch by cell, stable (pieces in order, points in order within
      // a piece), then one write per cell: each point is copied once and written once.
      const size_t n = batch.size(), pieces = (n + kRoutePiece - 1) / kRoutePiece;
      cell.resize(n);
      at.assign(pieces * cells, 0);
      ParallelFor(size_t{0}, pieces, [&](size_t piece) {
        uint64_t* count = &at[piece * cells];
        const size_t a = piece * kRoutePiece, m = std::min(n, a + kRoutePiece) - a;
        MortonCells(grid_, frame_, batch.data() + a, m, kMortonBits - level - k, k, &cell[a]);
        for (size_t i = a; i < a + m; ++i) ++count[cell[i]];
      });
      const std::vector<uint64_t> start = StableBucketOffsets(&at, pieces, cells);
      grouped.resize(n);
      ParallelFor(size_t{0}, pieces, [&](size_t piece) {
        // In locals: the counters' stores could alias what the lambda captures by reference.
        uint64_t* next = &at[piece * cells];
        const uint16_t* const to = cell.data();
        const P* const from = batch.data();
        P* const out = grouped.data();
        const size_t end = std::min(n, (piece + 1) * kRoutePiece);
        for (size_t i = piece * kRoutePiece; i < end; ++i) out[next[to[i]]++] = from[i];
      });
      // The page-cache copies of different cells run in parallel.
      ParallelFor(size_t{0}, cells, [&](size_t c) {
        files[c]->Append(grouped.data() + start[c], static_cast<size_t>(start[c + 1] - start[c]));
      });
    }
    // Room for the largest cell sorted in memory, taken once: buffers grown cell by cell would
    // each be faulted in afresh (and the words copied over), ~0.1 CPU-s at 10^8 points.
    uint64_t largest = 0;
    for (size_t c = 0; c < cells; ++c) {
      if (files[c]->count() <= o_.memory_points) largest = std::max(largest, files[c]->count());
    }
    Reserve(static_cast<size_t>(largest));
    for (size_t c = 0; c < cells; ++c) {
      SpillRecords<P>& f = *files[c];
      const uint64_t n = f.count();
      if (n == 0) {
        files[c].reset();
        continue;
      }
      if (n <= o_.memory_points) {
        {
          // Mapped, not copied out of the page cache; the file is deleted as soon as it is
          // sorted, so disk stays ~ one copy of the input.
          const SpillFile::Mapping mapped = f.Map();
          AddCell(reinterpret_cast<const P*>(mapped.data()), static_cast<size_t>(n), level + k);
        }
        files[c].reset();
      } else {
        uint64_t next = 0;
        const size_t batch_points = std::max<size_t>(1, o_.memory_points / 4);
        Spill(
            [&](UninitVector<P>* out) {
              if (next >= n) return false;
              const size_t m = static_cast<size_t>(std::min<uint64_t>(batch_points, n - next));
              out->resize(m);
              f.Read(next, m, out->data());
              next += m;
              return true;
            },
            n, level + k);
        files[c].reset();
      }
    }
  }

  // The layer the chunks written next belong to.
  void SetLayer(int layer) { layer_ = layer; }

  // Closes the last data file; returns the manifest's chunks and files.
  void Finish(ArchiveManifest* m) {
    WaitForWrites();
    CloseFile();
    m->chunks = std::move(chunks_);
    m->files = std::move(files_);
  }
  uint64_t spilled() const { return spilled_; }
  const double* max_error() const { return max_error_; }

 private:
  // Capacity for cells of n points. The sort writes its keys and records to thousands of
  // buckets at once: on huge pages.
  void Reserve(size_t n) {
    ReserveHuge(&keys_, n);
    ReserveHuge(&scratch_, n);
    ReserveHuge(&sorted_, n);
    // words_ and writing_ trade places: each is grown once, to the largest cell yet.
    reserved_ = std::max(reserved_, n);
    if (words_.capacity() < n) words_ = UninitVector<uint64_t>(), words_.reserve(reserved_);
  }

  // Cuts sorted_[a, b) (codes equal in the first `level` levels) into chunks of points sharing
  // a Morton prefix: consecutive children are grouped while they fit, a child too big recurses.
  void Cut(size_t a, size_t b, int level) {
    if (b - a <= o_.chunk_points) {
      ranges_.push_back({a, b});
      return;
    }
    if (level >= kMortonBits) {
      for (size_t i = a; i < b; i += o_.chunk_points) ranges_.push_back({i, std::min(b, i + o_.chunk_points)});
      return;
    }
    size_t group = a;
    size_t child = a;
    while (child < b) {
      const uint64_t key = Prefix(keys_[child].code, level + 1);
      size_t end = child;
      // The child's end: galloping then binary search (children are contiguous).
      size_t step = 1;
      while (end + step < b && Prefix(keys_[end + step].code, level + 1) == key) end += step, step *= 2;
      size_t lo = end, hi = std::min(b, end + step);  // key at lo, not at hi (or hi == b)
      while (hi - lo > 1) {
        const size_t mid = lo + (hi - lo) / 2;
        if (Prefix(keys_[mid].code, level + 1) == key) lo = mid; else hi = mid;
      }
      end = hi;
      if (end - child > o_.chunk_points) {
        if (child > group) ranges_.push_back({group, child});
        Cut(child, end, level + 1);
        group = end;
      } else if (end - group > o_.chunk_points) {
        ranges_.push_back({group, child});
        group = child;
      }
      child = end;
    }
    if (b > group) ranges_.push_back({group, b});
  }

  void WriteChunks() {
    const size_t n = ranges_.size();
    std::vector<ArchiveChunk> made(n);
    words_.resize(sorted_.size());
    const uint64_t base = chunks_made_;
    ParallelFor(size_t{0}, n, [&](size_t k) {
      const auto [a, b] = ranges_[k];
      const Box3d box = ChunkBox(&sorted_[a], b - a, frame_);
      ArchiveChunk& c = made[k];
      c.layer = layer_;
      c.quantizer = ChunkQuantizer::ForBox(box);
      c.count = b - a;
      Encode(c.quantizer, frame_, &sorted_[a], b - a, &words_[a]);
      // A seeded random order within the chunk (Fisher-Yates over the 8-byte words, which stay
      // in cache): any run is a uniform sample. j = floor(u * i) from 32 random bits (chunks hold
      // at most 2^24 points, so each position's probability is off by at most 2^-8 of itself).
      Rng rng(HashIndex(o_.seed, base + k, /*stream=*/0x5A0FF1E));
      uint64_t* w = &words_[a];
      for (size_t i = b - a; i > 1; --i) {
        const size_t j = static_cast<size_t>(((rng.Next() >> 32) * static_cast<uint64_t>(i)) >> 32);
        std::swap(w[i - 1], w[j]);
      }
      c.hash = ArchiveHash(&words_[a], 8 * (b - a));
    });
    chunks_made_ += n;
    // The chunks go into the data file on a thread of their own while the next cell is sorted
    // and encoded (into the other words buffer), in order: the last cell's first.
    WaitForWrites();
    words_.swap(writing_);
    writes_ = std::async(std::launch::async, [this, made = std::move(made), ranges = ranges_]() mutable {
      for (size_t k = 0; k < made.size(); ++k) {
        const auto [a, b] = ranges[k];
        if (!file_ || file_->Tell() >= o_.file_bytes) OpenFile();
        ArchiveChunk& c = made[k];
        c.file = static_cast<int>(files_.size() - 1);
        c.offset = file_->Tell();
        c.first = written_;
        file_->Write(&writing_[a], 8 * (b - a));
        written_ += c.count;
        for (int ax = 0; ax < 3; ++ax) max_error_[ax] = std::max(max_error_[ax], c.quantizer.ErrorBound(ax));
        chunks_.push_back(c);
      }
    });
  }

  // Waits for the chunks being written, and rethrows what the writing threw.
  void WaitForWrites() {
    if (!writes_.valid()) return;
    writes_.get();
    if (progress_) progress_(written_, total_);
  }

  void OpenFile() {
    CloseFile();
    char name[32];
    std::snprintf(name, sizeof(name), "data-%05zu.bin", files_.size());
    files_.push_back({name, 0});
    file_ = std::make_unique<AtomicFile>(dir_ + "/" + name);
  }
  void CloseFile() {
    if (!file_) return;
    files_.back().bytes = file_->Tell();
    file_->Commit();
    file_.reset();
  }

  const PackOptions& o_;
  std::string dir_;
  MortonGrid grid_;
  RecordFrame frame_;
  uint64_t total_;
  ProgressCallback progress_;
  std::vector<Keyed> keys_, scratch_;
  UninitVector<P> sorted_;
  UninitVector<uint64_t> words_;  // every word is written before it is read
  std::vector<std::pair<size_t, size_t>> ranges_;
  std::vector<ArchiveChunk> chunks_;
  std::vector<ArchiveFile> files_;
  std::unique_ptr<AtomicFile> file_;
  uint64_t written_ = 0, spilled_ = 0, chunks_made_ = 0;
  size_t reserved_ = 0;  // the most points a cell was given room for
  int spill_id_ = 0, layer_ = 0;
  double max_error_[3] = {0, 0, 0};
  // The words of the cell being written, and its writing: from WriteChunks until WaitForWrites,
  // only that thread touches file_, files_, chunks_, written_ and max_error_. Last, so that it
  // is destroyed (its destructor waits for the thread) before what the thread uses.
  UninitVector<uint64_t> writing_;
  std::future<void> writes_;
};

}  // namespace

PackSummary PackArchive(const PackOptions& options, const std::vector<PackInput>& inputs,
                        const std::string& output_dir, const ProgressCallback& progress) {
  options.Check();
  if (inputs.empty()) throw std::invalid_argument("PackArchive: no inputs");
  // What the rename at the end would refuse, refused before the work.
  CheckReplaceableFolder(fs::absolute(output_dir).string(), IsArchive, "a candi render archive");
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<tbb::task_arena> arena;
  if (options.threads > 0) arena = std::make_unique<tbb::task_arena>(options.threads);
  PackSummary summary;
  ArchiveManifest manifest;
  manifest.chunk_points = options.chunk_points;
  manifest.shuffle_seed = options.seed;
  manifest.colour_by = options.colour_by;
  // The layers, in the order their first input comes; the inputs of each.
  std::vector<std::vector<size_t>> layer_inputs;
  for (size_t k = 0; k < inputs.size(); ++k) {
    const std::string name = inputs[k].layer.empty() ? inputs[k].name : inputs[k].layer;
    size_t l = 0;
    while (l < manifest.layers.size() && manifest.layers[l].name != name) ++l;
    if (l == manifest.layers.size()) {
      manifest.layers.push_back({name, 0});
      layer_inputs.emplace_back();
    }
    layer_inputs[l].push_back(k);
  }

  // The input files' hashes for the manifest. Files of records (binary PLY) are hashed by pass
  // 1 from the bytes it reads; the others on another thread while the packer goes on (the
  // futures' destructors wait for them if packing fails).
  std::vector<uint64_t> hashes(inputs.size(), 0), hashed_bytes(inputs.size(), 0);
  std::vector<std::future<double>> hashing;
  auto hash_later = [&](size_t k) {
    if (inputs[k].path.empty()) return;
    hashing.push_back(std::async(std::launch::async, [&inputs, &hashes, &hashed_bytes, k] {
      const auto t0 = std::chrono::steady_clock::now();
      hashes[k] = HashFile(inputs[k].path, &hashed_bytes[k]);
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }));
  };

  // Pass 1: bounds and counts (headers when they state both), in the arena like pass 2.
  Box3d world;
  uint64_t total = 0;
  std::vector<uint64_t> counts(inputs.size(), 0);
  // Whether every point is a float in one frame shared by all inputs (then CompactPoints).
  bool floats = true;
  std::optional<Eigen::Vector3d> shared_origin;
  // Whether every input is LAS read directly, all in one frame with one scale and offset (then
  // LasPoints), and that frame and decoder.
  bool las = options.direct_reads;
  std::optional<Eigen::Vector3d> las_origin;
  io::LasPositionDecoder las_decoder;
  std::shared_ptr<const MappedFile> first_map;
  auto pass1 = [&] {
    for (size_t k = 0; k < inputs.size(); ++k) {
      auto reader = inputs[k].open();
      const io::PointFileInfo& info = reader->info();
      const std::optional<io::PointRecordLayout> layout = reader->record_layout();
      const bool direct = options.direct_reads && layout && !inputs[k].path.empty() && reader->path() == inputs[k].path;
      if (direct && layout->coordinates == io::PointRecordLayout::Coordinates::kLasInt32) {
        const io::LasPositionDecoder decoder(layout->scale, layout->offset);
        if (!las_origin) las_origin = info.frame.origin, las_decoder = decoder;
        las = las && *las_origin == info.frame.origin && decoder == las_decoder;
      } else {
        las = false;
      }
      if (info.header_bounds && info.count != io::kUnknownCount) {
        hash_later(k);
        counts[k] = info.count;
        if (info.count > 0) world.Extend(*info.header_bounds);
        floats = false;  // its points are not read here
        continue;
      }
      if (direct && (layout->coordinates == io::PointRecordLayout::Coordinates::kFloat32 ||
                     layout->coordinates == io::PointRecordLayout::Coordinates::kFloat64)) {
        // Binary PLY: the bounds, whether every coordinate is a float, and the hash, in one read.
        RecordScan scan = ScanRecords(reader->path(), *layout, info.frame);
        // Pass 2 reads input 0 first (its layer is the first): its map is kept for pass 2 to
        // share, so that its pages are mapped once (~0.3 CPU-s for 2.7 GB). Only the first, so
        // that the maps held do not grow with the inputs.
        if (k == 0) first_map = std::move(scan.map);
        hashes[k] = scan.hash;
        hashed_bytes[k] = scan.bytes;
        counts[k] = layout->count;
        if (layout->count == 0) continue;
        if (!shared_origin) shared_origin = info.frame.origin;
        floats = floats && scan.floats && info.frame.origin == *shared_origin;
        world.Extend(scan.world);
        continue;
      }
      hash_later(k);
      PointCloud chunk;
      std::vector<Box3d> boxes;
      while (reader->Read(1 << 20, &chunk) > 0) {
        // Per block of points, in parallel; min and max do not depend on the order.
        const size_t n = chunk.size(), blocks = (n + kBoundsBlock - 1) / kBoundsBlock;
        boxes.assign(blocks, Box3d());
        if (!shared_origin) shared_origin = chunk.frame.origin;
        floats = floats && chunk.frame.origin == *shared_origin;
        std::atomic<bool> all_floats{floats};
        ParallelFor(size_t{0}, blocks, [&](size_t b) {
          bool block_floats = true;
          for (size_t i = b * kBoundsBlock; i < std::min(n, (b + 1) * kBoundsBlock); ++i) {
            const Eigen::Vector3d& p = chunk.positions[i];
            block_floats &= IsFloat(p);
            if (!p.allFinite()) continue;  // reported with its index in pass 2
            boxes[b].Extend(chunk.frame.ToWorld(p));
          }
          if (!block_floats) all_floats = false;
        });
        floats = all_floats;
        for (const Box3d& box : boxes) world.Extend(box);
        counts[k] += n;
      }
    }
  };
  if (arena) arena->execute(pass1); else pass1();
  for (uint64_t c : counts) total += c;
  if (total == 0 || world.IsEmpty()) throw InputError("nothing to pack: the inputs hold no points");
  auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  summary.bounds_seconds = since(start);
  manifest.frame = RenderFrameFor(world);
  MortonGrid grid;
  const Box3d local = world.Translated(-manifest.frame.origin);
  grid.min = local.min;
  for (int a = 0; a < 3; ++a) {
    const double extent = local.max[a] - local.min[a];
    grid.scale[a] = extent > 0 ? std::ldexp(1.0, kMortonBits) / extent : 0.0;
  }

  // The output is built beside its destination.
  const fs::path out_path = fs::absolute(output_dir);
  const std::string temp = out_path.string() + ".candi-tmp-" + std::to_string(getpid());
  std::error_code ec;
  fs::remove_all(temp, ec);
  // Created and registered in one step: an interrupt removes it, or comes before it exists.
  const int interrupt_id = CreateTempDirectory(temp, &ec);
  if (interrupt_id < 0) throw InputError(temp, "", "cannot create the archive's build directory: " + ec.message());
  TempFolder cleanup(temp, interrupt_id);

  auto pack = [&](auto point_type) {
    using P = decltype(point_type);
    // The records' frame (CompactPoint: the inputs' shared one; LasPoint: the LAS files').
    const Eigen::Vector3d origin = std::is_same_v<P, LasPoint> ? las_origin.value_or(Eigen::Vector3d::Zero())
                                                               : shared_origin.value_or(Eigen::Vector3d::Zero());
    RecordFrame frame;
    if (!std::is_same_v<P, WidePoint>) frame.shift = origin - manifest.frame.origin;
    frame.las = las_decoder;
    Packer<P> packer(options, temp, grid, frame, total, progress);
    for (size_t l = 0; l < layer_inputs.size(); ++l) {
      std::vector<PackInput> group;
      uint64_t group_total = 0;
      for (size_t k : layer_inputs[l]) group.push_back(inputs[k]), group_total += counts[k];
      manifest.layers[l].points = group_total;
      if (group_total == 0) continue;
      packer.SetLayer(static_cast<int>(l));
      InputBatches<P> batches(group, manifest.frame, options.default_color, origin, las_decoder, options.direct_reads);
      // Once the first batch is read, input 0's reader holds the map it shares: pass 1's hold
      // is let go, so the map lasts as long as that reader.
      auto next = [&batches, &first_map](UninitVector<P>* out) {
        const bool more = batches(out);
        first_map.reset();
        return more;
      };
      if (group_total <= options.memory_points) {
        UninitVector<P> all, batch;
        all.reserve(group_total);
        while (next(&batch)) all.insert(all.end(), batch.begin(), batch.end());
        packer.AddCell(all.data(), all.size(), 0);
      } else {
        packer.Spill(next, group_total, 0);
      }
    }
    packer.Finish(&manifest);
    summary.spilled_points = packer.spilled();
    for (int a = 0; a < 3; ++a) summary.max_error[a] = packer.max_error()[a];
  };
  const bool compact = floats && shared_origin.has_value() && !options.wide_records;
  const bool las_records = !compact && las && las_origin.has_value() && !options.wide_records;
  summary.record_bytes = compact ? sizeof(CompactPoint) : las_records ? sizeof(LasPoint) : sizeof(WidePoint);
  auto run = [&] {
    if (compact) {
      pack(CompactPoint{});
    } else if (las_records) {
      pack(LasPoint{});
    } else {
      pack(WidePoint{});
    }
  };
  const auto sort_start = std::chrono::steady_clock::now();
  if (arena) arena->execute(run); else run();
  summary.sort_seconds = since(sort_start);

  manifest.points = manifest.chunks.empty() ? 0 : manifest.chunks.back().first + manifest.chunks.back().count;
  if (manifest.points != total) {
    throw InputError(inputs.front().name, "", "the inputs gave " + std::to_string(manifest.points) +
                                                  " points on the second read, " + std::to_string(total) +
                                                  " on the first (did a file change?)");
  }
  manifest.bounds = local;
  for (std::future<double>& h : hashing) summary.hash_seconds += h.get();
  for (size_t k = 0; k < inputs.size(); ++k) {
    ArchiveSource src;
    src.path = inputs[k].path.empty() ? inputs[k].name : inputs[k].path;
    src.points = counts[k];
    src.hash = hashes[k];
    src.bytes = hashed_bytes[k];
    manifest.sources.push_back(src);
  }
  WriteFileAtomic(temp + "/" + kArchiveManifest, manifest.ToJson());
  CommitTempPath(cleanup.id(), [&] {
    ReplaceFolder(temp, out_path.string(), IsArchive, "a candi render archive");
    cleanup.Keep();
  });

  summary.points = manifest.points;
  summary.colour_by = manifest.colour_by;
  summary.chunks = manifest.chunks.size();
  summary.files = manifest.files.size();
  for (const ArchiveFile& f : manifest.files) summary.bytes += f.bytes;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

PackSummary PackFiles(const PackOptions& options, const std::vector<std::string>& files, const std::string& columns,
                      const std::string& output_dir, const ProgressCallback& progress,
                      const FieldColouring& colour_by) {
  if (colour_by.active()) {
    PackOptions coloured = options;
    coloured.colour_by = ResolveFieldColouringOfFiles(files, columns, colour_by, progress);
    return PackArchive(coloured, PackInputsColouredByField(files, columns, *coloured.colour_by), output_dir,
                       progress);
  }
  std::vector<PackInput> inputs;
  for (const std::string& file : files) inputs.push_back(PackInputFromFile(file, columns));
  return PackArchive(options, inputs, output_dir, progress);
}

}  // namespace candi::render
