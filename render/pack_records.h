// The packer's intermediate points (render/archive_pack.cc), private to it: the three record
// forms a point takes between reading and quantizing, the Morton grid over the archive's bounds,
// and the cell files of the external sort.
#pragma once

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "core/check.h"
#include "core/morton.h"
#include "io/las/las_columns.h"
#include "render/archive.h"

namespace candi::render::pack_internal {

// The points between reading and encoding (in cell files and in memory), in one of three forms.
// WidePoint: the archive-frame position in double, any input. CompactPoint: when every input
// point is a float in one frame shared by all inputs (binary PLY with float x, y, z, the usual
// photogrammetry output), that float; adding the shift from that frame to the archive's gives
// the very doubles WidePoint would hold, so the archive is the same, from 16 bytes a point
// instead of 28. LasPoint: when every input is LAS with one scale and offset, its integers,
// decoded as the LAS reader decodes them (16 bytes as well).
// How records give positions in the archive frame: CompactPoint adds `shift` to its floats,
// LasPoint decodes its integers with `las` (as the LAS reader does) and adds `shift`, WidePoint
// holds the position itself.
struct RecordFrame {
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  io::LasPositionDecoder las;
};

#pragma pack(push, 1)
struct WidePoint {
  double x, y, z;
  uint32_t rgb;
  // By value: a reference to a member of a packed struct may be misaligned (undefined behaviour
  // that UBSan reports where Eigen's constructors take `const double&`).
  Eigen::Vector3d Position(const RecordFrame& /*frame*/) const { return Eigen::Vector3d(double{x}, double{y}, double{z}); }
};
#pragma pack(pop)
static_assert(sizeof(WidePoint) == 28, "WidePoint must be packed");

struct CompactPoint {
  float x, y, z;
  uint32_t rgb;
  Eigen::Vector3d Position(const RecordFrame& f) const {
    return Eigen::Vector3d(double{x}, double{y}, double{z}) + f.shift;
  }
};
static_assert(sizeof(CompactPoint) == 16, "CompactPoint must be 16 bytes");

// A LAS point record's integers (every input LAS with one scale and offset, read directly).
struct LasPoint {
  int32_t x, y, z;
  uint32_t rgb;
  Eigen::Vector3d Position(const RecordFrame& f) const {
    return Eigen::Vector3d(f.las.Axis(0, x), f.las.Axis(1, y), f.las.Axis(2, z)) + f.shift;
  }
};
static_assert(sizeof(LasPoint) == 16, "LasPoint must be 16 bytes");

constexpr int kMortonBits = 21;  // per axis; 63-bit codes, 21 levels of 3 bits

struct MortonGrid {
  Eigen::Vector3d min, scale;  // cells per metre
  // The point's cell on each axis: 21 bits.
  void Quantize(const Eigen::Vector3d& p, uint64_t q[3]) const {
    const double top = static_cast<double>((1 << kMortonBits) - 1);
    for (int a = 0; a < 3; ++a) q[a] = static_cast<uint64_t>(std::clamp((p[a] - min[a]) * scale[a], 0.0, top));
  }
  uint64_t Code(const Eigen::Vector3d& p) const {
    uint64_t q[3];
    Quantize(p, q);
    return MortonCode21(q[0], q[1], q[2]);
  }
};

// The key of a point at a level: the code's top 3 * levels bits.
inline uint64_t Prefix(uint64_t code, int levels) { return levels == 0 ? 0 : code >> (63 - 3 * levels); }

template <typename P>
class CellFile {
 public:
  explicit CellFile(std::string path) : path_(std::move(path)) {}
  ~CellFile() {
    if (fd_ >= 0) close(fd_);
    if (!path_.empty()) unlink(path_.c_str());
  }
  // Appends n points to the file.
  void Append(const P* points, size_t n) {
    if (n == 0) return;
    if (fd_ < 0) {
      fd_ = open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
      if (fd_ < 0) throw InputError(path_, "", std::string("cannot create cell file: ") + std::strerror(errno));
    }
    const char* p = reinterpret_cast<const char*>(points);
    size_t left = n * sizeof(P);
    while (left > 0) {
      const ssize_t w = write(fd_, p, left);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) throw InputError(path_, "", std::string("cannot write cell file: ") + std::strerror(errno));
      p += w, left -= static_cast<size_t>(w);
    }
    count_ += n;
  }
  uint64_t count() const { return count_; }
  // The flushed points, memory-mapped (read-only) while the Mapping lives.
  class Mapping {
   public:
    Mapping(void* data, size_t bytes) : data_(data), bytes_(bytes) {}
    ~Mapping() {
      if (data_) munmap(data_, bytes_);
    }
    Mapping(const Mapping&) = delete;
    Mapping& operator=(const Mapping&) = delete;
    const P* points() const { return static_cast<const P*>(data_); }

   private:
    void* data_;
    size_t bytes_;
  };
  Mapping Map() const {
    const size_t bytes = static_cast<size_t>(count_) * sizeof(P);
    if (bytes == 0) return Mapping(nullptr, 0);
    void* p = mmap(nullptr, bytes, PROT_READ, MAP_PRIVATE, fd_, 0);
    if (p == MAP_FAILED) throw InputError(path_, "", std::string("cannot map cell file: ") + std::strerror(errno));
    madvise(p, bytes, MADV_SEQUENTIAL);
    return Mapping(p, bytes);
  }
  // Reads points [from, from + n).
  void Read(uint64_t from, size_t n, P* out) const {
    size_t left = n * sizeof(P);
    char* p = reinterpret_cast<char*>(out);
    uint64_t offset = from * sizeof(P);
    while (left > 0) {
      const ssize_t got = pread(fd_, p, left, static_cast<off_t>(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) throw InputError(path_, "byte " + std::to_string(offset), "cannot read cell file back");
      p += got, left -= static_cast<size_t>(got), offset += static_cast<uint64_t>(got);
    }
  }

 private:
  std::string path_;
  int fd_ = -1;
  uint64_t count_ = 0;
};

// Quantizes points[0, n) on a chunk's quantizer into words[0, n) (ChunkQuantizer::Encode).
// Compiled for AVX2 as well (the loader picks), where Encode's rounding is one instruction rather
// than a libm call: the same words.
void Encode(const ChunkQuantizer& q, const RecordFrame& f, const WidePoint* points, size_t n, uint64_t* words);
void Encode(const ChunkQuantizer& q, const RecordFrame& f, const CompactPoint* points, size_t n, uint64_t* words);
void Encode(const ChunkQuantizer& q, const RecordFrame& f, const LasPoint* points, size_t n, uint64_t* words);

// MortonGrid::Code of each point's Position(f) into codes[0, n), vectorized (compiled for AVX2
// as well): the same codes.
void MortonCodes(const MortonGrid& g, const RecordFrame& f, const WidePoint* points, size_t n, uint64_t* codes);
void MortonCodes(const MortonGrid& g, const RecordFrame& f, const CompactPoint* points, size_t n, uint64_t* codes);
void MortonCodes(const MortonGrid& g, const RecordFrame& f, const LasPoint* points, size_t n, uint64_t* codes);

// The box of points[0, n) (n > 0): the positions' min and max on each axis.
template <typename P>
Box3d ChunkBox(const P* points, size_t n, const RecordFrame& f) {
  Box3d box;
  for (size_t i = 0; i < n; ++i) box.Extend(points[i].Position(f));
  return box;
}
// LAS: a position is monotonic in its integer on each axis (increasing, or decreasing for a
// negative scale), so the box is that of the integers' extremes, decoded: the same doubles.
Box3d ChunkBox(const LasPoint* points, size_t n, const RecordFrame& f);

// Whether v is a float (so CompactPoint holds it exactly); false for NaN and beyond float's range.
inline bool IsFloat(double v) {
  return std::abs(v) <= std::numeric_limits<float>::max() && double{static_cast<float>(v)} == v;
}
inline bool IsFloat(const Eigen::Vector3d& p) { return IsFloat(p.x()) && IsFloat(p.y()) && IsFloat(p.z()); }

}  // namespace candi::render::pack_internal
