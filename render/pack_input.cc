#include "render/pack_input.h"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/mapped_file.h"
#include "core/parallel.h"

namespace candi::render {

uint64_t HashFile(const std::string& path, uint64_t* bytes) {
  // Through a map of the file: its blocks are hashed where the page cache holds them, with no
  // copy out (a read copies every byte, a fifth of a LAS pack's time).
  const std::shared_ptr<const MappedFile> map = MapShared(path);  // shared with its records' read
  const MappedFile& file = *map;
  *bytes = file.size();
  // Four whole blocks at a time (ArchiveHashBlocks), then the last, shorter one.
  constexpr uint64_t kBlock = pack_internal::kHashBlock;
  constexpr int kGroup = 4;
  const uint64_t whole = file.size() / kBlock, tail = file.size() % kBlock;
  std::vector<uint64_t> blocks(static_cast<size_t>(whole + (tail > 0 ? 1 : 0)));
  file.WillNeed(0, kGroup * kBlock);
  for (uint64_t b = 0; b < whole; b += kGroup) {
    const int m = static_cast<int>(std::min<uint64_t>(kGroup, whole - b));
    file.CheckSize((b + m) * kBlock, "block for hashing");
    file.WillNeed((b + m) * kBlock, kGroup * kBlock);  // the next group's
    const uint8_t* group[kGroup];
    for (int k = 0; k < m; ++k) group[k] = file.data() + (b + k) * kBlock;
    ArchiveHashBlocks(group, m, kBlock, &blocks[b]);
  }
  if (tail > 0) {
    file.CheckSize(file.size(), "block for hashing");
    blocks.back() = ArchiveHash(file.data() + whole * kBlock, static_cast<size_t>(tail));
  }
  return ArchiveHash(blocks.data(), 8 * blocks.size(), file.size());
}

namespace pack_internal {

namespace {

// Records are converted and checked in parallel blocks of this many.
constexpr size_t kRecordBlock = size_t{1} << 14;

// Whether a float's bits are NaN or infinite (exponent all ones): adding one to that exponent
// carries into the sign bit.
inline uint32_t NonFiniteBit(uint32_t bits) { return ((bits & 0x7f800000u) + 0x00800000u) & 0x80000000u; }

template <typename T>
inline T LoadCoordinate(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// The first record in [0, n) with a NaN or infinite coordinate (of type T), or n.
template <typename T>
size_t FirstNonFinite(const io::PointRecordLayout& l, const uint8_t* records, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* r = records + i * l.stride;
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(LoadCoordinate<T>(r + l.xyz[a]))) return i;
    }
  }
  return n;
}

[[noreturn]] void FailNonFinite(const std::string& path, uint64_t vertex) {
  throw InputError(path, "vertex " + std::to_string(vertex), "coordinate is NaN or infinite");
}

// A file too short for its records is refused as the PLY reader refuses it.
void CheckHoldsRecords(const std::string& path, const io::PointRecordLayout& l, uint64_t file_bytes) {
  const uint64_t end = l.first_byte + l.count * l.stride;
  if (file_bytes >= end) return;
  const uint64_t whole = file_bytes > l.first_byte ? (file_bytes - l.first_byte) / l.stride : 0;
  throw InputError(path, "byte " + std::to_string(file_bytes),
                   "file ends inside vertex " + std::to_string(whole) + " of " + std::to_string(l.count));
}

// Min and max of the records' coordinates (T: float or double), whether any is NaN or infinite,
// and whether every one is a float (doubles that a float holds exactly; floats are).
template <typename T>
struct CoordinateBox {
  T lo[3] = {std::numeric_limits<T>::infinity(), std::numeric_limits<T>::infinity(),
             std::numeric_limits<T>::infinity()};
  T hi[3] = {-std::numeric_limits<T>::infinity(), -std::numeric_limits<T>::infinity(),
             -std::numeric_limits<T>::infinity()};
  bool bad = false;
  bool floats = true;
};
template <typename T>
CoordinateBox<T> BoxOfRecords(const io::PointRecordLayout& l, const uint8_t* records, size_t n) {
  CoordinateBox<T> box;
  uint32_t bad = 0;
  bool floats = true;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* r = records + i * l.stride;
    for (int a = 0; a < 3; ++a) {
      const T v = LoadCoordinate<T>(r + l.xyz[a]);
      if constexpr (std::is_same_v<T, float>) {
        uint32_t bits;
        std::memcpy(&bits, r + l.xyz[a], 4);
        bad |= NonFiniteBit(bits);
      } else {
        bad |= std::isfinite(v) ? 0u : 1u;
        floats &= IsFloat(v);
      }
      box.lo[a] = std::min(box.lo[a], v);
      box.hi[a] = std::max(box.hi[a], v);
    }
  }
  box.bad = bad != 0;
  box.floats = floats;
  return box;
}

}  // namespace

struct RecordFile::Impl {
  explicit Impl(const std::string& path) : shared(MapShared(path)), map(*shared) {}
  // The records are used where the page cache holds them, through the map the input's hash
  // reads on its thread when that is still at work.
  std::shared_ptr<const MappedFile> shared;
  const MappedFile& map;
};

RecordFile::RecordFile(const std::string& path, const io::PointRecordLayout& layout)
    : impl_(std::make_unique<Impl>(path)), layout_(layout) {
  CheckHoldsRecords(path, layout_, impl_->map.size());
}

RecordFile::~RecordFile() = default;

size_t RecordFile::Next(size_t max_points, const uint8_t** records) {
  const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, layout_.count - next_));
  if (n == 0) return 0;
  const size_t bytes = n * layout_.stride;
  const uint64_t at = layout_.first_byte + next_ * layout_.stride;
  const MappedFile& map = impl_->map;
  try {
    map.CheckSize(at + bytes, "point records");  // a file that shrank: an error, not SIGBUS
  } catch (const InputError&) {
    CheckHoldsRecords(map.path(), layout_, BinaryFile(map.path()).size());  // as the PLY reader says it
    throw;
  }
  map.WillNeed(at, bytes);
  next_ += n;
  *records = map.data() + at;
  return n;
}

namespace {

template <typename T>
RecordScan ScanRecordsOf(const std::string& path, const io::PointRecordLayout& l, const LocalFrame& frame) {
  RecordScan scan;
  scan.map = MapShared(path);
  const MappedFile& map = *scan.map;
  scan.bytes = map.size();
  CheckHoldsRecords(path, l, scan.bytes);
  const uint64_t end = l.first_byte + l.count * l.stride;
  // HashFile's blocks, each with the start of the record that crosses its end.
  std::vector<uint64_t> hashes;
  CoordinateBox<T> total;
  for (uint64_t at = 0; at < scan.bytes; at += kHashBlock) {
    const size_t block = static_cast<size_t>(std::min<uint64_t>(kHashBlock, scan.bytes - at));
    const size_t want = static_cast<size_t>(std::min<uint64_t>(kHashBlock + l.stride, scan.bytes - at));
    map.CheckSize(at + want, "a block to hash");  // a file that shrank: an error, not SIGBUS
    map.WillNeed(at + want, kHashBlock);
    const uint8_t* bytes = map.data() + at;
    // The records that start in this block.
    auto first_at_or_after = [&](uint64_t byte) {
      return byte <= l.first_byte ? 0 : std::min<uint64_t>(l.count, (byte - l.first_byte + l.stride - 1) / l.stride);
    };
    const uint64_t r0 = first_at_or_after(at), r1 = first_at_or_after(std::min<uint64_t>(at + block, end));
    const size_t n = static_cast<size_t>(r1 - r0), parts = (n + kRecordBlock - 1) / kRecordBlock;
    const uint8_t* records = bytes + (l.first_byte + r0 * l.stride - at);
    std::vector<CoordinateBox<T>> boxes(parts);
    uint64_t hash = 0;
    // Task 0 hashes the block while the others take the bounds of its records.
    ParallelFor(size_t{0}, parts + 1, [&](size_t t) {
      if (t == 0) {
        hash = ArchiveHash(bytes, block);
        return;
      }
      const size_t a = (t - 1) * kRecordBlock;
      boxes[t - 1] = BoxOfRecords<T>(l, records + a * l.stride, std::min(kRecordBlock, n - a));
    });
    hashes.push_back(hash);
    for (size_t p = 0; p < parts; ++p) {
      const size_t a = p * kRecordBlock;
      if (boxes[p].bad) FailNonFinite(path, r0 + a + FirstNonFinite<T>(l, records + a * l.stride, std::min(kRecordBlock, n - a)));
      total.floats = total.floats && boxes[p].floats;
      for (int a = 0; a < 3; ++a) {
        total.lo[a] = std::min(total.lo[a], boxes[p].lo[a]);
        total.hi[a] = std::max(total.hi[a], boxes[p].hi[a]);
      }
    }
  }
  scan.hash = ArchiveHash(hashes.data(), 8 * hashes.size(), scan.bytes);
  scan.floats = total.floats;
  if (l.count > 0) {
    // frame.ToWorld is monotonic on each axis, so the bounds of the world positions are those of
    // the float bounds, the same doubles as a point-by-point pass.
    scan.world.Extend(frame.ToWorld(Eigen::Vector3d(total.lo[0], total.lo[1], total.lo[2])));
    scan.world.Extend(frame.ToWorld(Eigen::Vector3d(total.hi[0], total.hi[1], total.hi[2])));
  }
  return scan;
}

}  // namespace

RecordScan ScanRecords(const std::string& path, const io::PointRecordLayout& l, const LocalFrame& frame) {
  using Coordinates = io::PointRecordLayout::Coordinates;
  CANDI_CHECK(l.coordinates != Coordinates::kLasInt32) << "ScanRecords: " << path << " holds LAS integers";
  return l.coordinates == Coordinates::kFloat64 ? ScanRecordsOf<double>(path, l, frame)
                                                : ScanRecordsOf<float>(path, l, frame);
}

template <typename P>
InputBatches<P>::InputBatches(const std::vector<PackInput>& inputs, const LocalFrame& frame, Rgb8 default_color,
                              const Eigen::Vector3d& compact_origin, const io::LasPositionDecoder& las,
                              bool direct)
    : inputs_(inputs),
      frame_(frame),
      default_color_(default_color),
      compact_origin_(compact_origin),
      las_(las),
      direct_(direct && !std::is_same_v<P, WidePoint>) {}

template <typename P>
InputBatches<P>::~InputBatches() = default;

template <typename P>
bool InputBatches<P>::ReadRecords(UninitVector<P>* out) {
  const uint8_t* records = nullptr;
  const size_t n = records_->Next(1 << 20, &records);
  if (n == 0) return false;
  const io::PointRecordLayout& l = records_->layout();
  out->resize(n);
  const uint32_t fallback = PackColor(default_color_);
  std::atomic<bool> bad{false};
  ParallelFor(size_t{0}, (n + kRecordBlock - 1) / kRecordBlock, [&](size_t b) {
    // The layout in the task's own locals: the records' stores could alias it (and the captured
    // references), so the compiler would reload every field for every record.
    const size_t stride = l.stride;
    const size_t ox = l.xyz[0], oy = l.xyz[1], oz = l.xyz[2];
    const bool has_rgb = l.rgb[0] >= 0;
    const size_t o0 = has_rgb ? l.rgb[0] : 0, o1 = has_rgb ? l.rgb[1] : 0, o2 = has_rgb ? l.rgb[2] : 0;
    const int color_shift = l.color_shift;
    const uint32_t fallback_rgb = fallback;
    const uint8_t* const in = records;
    P* const points = out->data();
    const size_t end = std::min(n, (b + 1) * kRecordBlock);
    uint32_t nonfinite = 0;
    for (size_t i = b * kRecordBlock; i < end; ++i) {
      const uint8_t* r = in + i * stride;
      P& p = points[i];
      if constexpr (!std::is_same_v<P, WidePoint>) {
        std::memcpy(&p.x, r + ox, 4);
        std::memcpy(&p.y, r + oy, 4);
        std::memcpy(&p.z, r + oz, 4);
      }
      if constexpr (std::is_same_v<P, CompactPoint>) {
        uint32_t bits[3];
        std::memcpy(bits, &p, 12);
        nonfinite |= NonFiniteBit(bits[0]) | NonFiniteBit(bits[1]) | NonFiniteBit(bits[2]);
        p.rgb = !has_rgb ? fallback_rgb : uint32_t{r[o0]} << 16 | uint32_t{r[o1]} << 8 | uint32_t{r[o2]};
      } else if constexpr (std::is_same_v<P, LasPoint>) {  // 16-bit colour >> color_shift, as the reader
        auto channel = [&](size_t o) { return uint32_t{static_cast<uint8_t>(LoadLE<uint16_t>(r + o) >> color_shift)}; };
        p.rgb = !has_rgb ? fallback_rgb : channel(o0) << 16 | channel(o1) << 8 | channel(o2);
      }
    }
    if (nonfinite) bad = true;
  });
  if (bad) FailNonFinite(inputs_[next_ - 1].name, index_ + FirstNonFinite<float>(l, records, n));
  index_ += n;
  return true;
}

template <typename P>
bool InputBatches<P>::operator()(UninitVector<P>* out) {
  out->clear();
  while (true) {
    if (!reader_ && !records_) {
      if (next_ >= inputs_.size()) return false;
      reader_ = inputs_[next_++].open();
      index_ = 0;
      const std::optional<io::PointRecordLayout> layout = reader_->record_layout();
      using Coordinates = io::PointRecordLayout::Coordinates;
      const Coordinates wanted = std::is_same_v<P, LasPoint> ? Coordinates::kLasInt32 : Coordinates::kFloat32;
      if (direct_ && layout && layout->coordinates == wanted) {
        if (reader_->info().frame.origin != compact_origin_ ||
            (wanted == Coordinates::kLasInt32 && !(io::LasPositionDecoder(layout->scale, layout->offset) == las_))) {
          throw InputError(inputs_[next_ - 1].name, "", "changed between the two reads (its frame, scale or offset)");
        }
        records_ = std::make_unique<RecordFile>(reader_->path(), *layout);
        reader_.reset();
      } else if (std::is_same_v<P, LasPoint>) {
        throw InputError(inputs_[next_ - 1].name, "", "changed between the two reads (no longer LAS records)");
      }
    }
    if (records_) {
      if (ReadRecords(out)) return true;
      records_.reset();
      continue;
    }
    const size_t n = reader_->Read(1 << 20, &chunk_);
    if (n == 0) {
      reader_.reset();
      continue;
    }
    const Eigen::Vector3d shift = chunk_.frame.origin - frame_.origin;
    out->resize(n);
    const uint32_t fallback = PackColor(default_color_);
    std::atomic<bool> finite{true}, exact{true};
    ParallelFor(tbb::blocked_range<size_t>(0, n, kRecordBlock), [&](const tbb::blocked_range<size_t>& r) {
      bool ok = true, floats = true;
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const uint32_t rgb = chunk_.schema.colors ? PackColor(chunk_.colors[i]) : fallback;
        if constexpr (std::is_same_v<P, LasPoint>) {
          CANDI_CHECK(false) << "LasPoints are read directly";
        } else if constexpr (std::is_same_v<P, CompactPoint>) {
          const Eigen::Vector3d& p = chunk_.positions[i];
          if (IsFloat(p)) {
            (*out)[i] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), rgb};
          } else {
            floats = false;
          }
        } else {
          const Eigen::Vector3d p = chunk_.positions[i] + shift;
          ok &= std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
          (*out)[i] = {p.x(), p.y(), p.z(), rgb};
        }
      }
      if (!ok) finite = false;
      if (!floats) exact = false;
    });
    // Compact points were all finite floats in one frame on the first read: anything else now
    // means the input changed.
    if (!exact || (std::is_same_v<P, CompactPoint> && chunk_.frame.origin != compact_origin_)) {
      size_t i = 0;  // the first point that is no longer a float (the first of a moved frame)
      if (!exact) while (i < n && IsFloat(chunk_.positions[i])) ++i;
      throw InputError(inputs_[next_ - 1].name, "point " + std::to_string(index_ + i),
                       "changed between the two reads (its points were floats in one frame)");
    }
    if (!finite) {
      for (size_t i = 0; i < n; ++i) {
        if (!chunk_.positions[i].allFinite()) {
          throw InputError(inputs_[next_ - 1].name, "point " + std::to_string(index_ + i),
                           "NaN or infinite coordinate");
        }
      }
    }
    index_ += n;
    return true;
  }
}

template class InputBatches<WidePoint>;
template class InputBatches<CompactPoint>;
template class InputBatches<LasPoint>;

}  // namespace pack_internal

}  // namespace candi::render
