// The LAS/LAZ/COPC writer behind OpenLasWriter (io/las/las_io.h): the version and point
// format, the header and VLRs, records encoded column by column, LAZ chunks compressed in
// parallel, and for a .copc.laz name the octree's nodes (io/copc/copc_octree.h, copc_write.h).
#include "io/las/las_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <ctime>
#include <functional>
#include <limits>
#include <stdexcept>

#include <unistd.h>

#include "core/atomic_file.h"
#include "core/binary_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/text_format.h"
#include "io/copc/copc_octree.h"
#include "io/copc/copc_store.h"
#include "io/copc/copc_write.h"
#include "io/crs.h"
#include "io/las/las_columns.h"
#include "io/las/las_crs_internal.h"
#include "io/las/las_header.h"
#include "io/laz/laz_chunks.h"
#include "io/laz/laz_format.h"

namespace candi::io {

namespace {

constexpr const char* kGeneratingSoftware = "candi 0.1.0";
constexpr uint32_t kLazChunkPoints = 50000;  // LASzip's default chunk size

// ---- Choice of version and point format ----

struct SchemaNeeds {
  bool colors = false, gps = false, nir = false, channel = false;
  bool huge = false;  // more points than the 32-bit count holds
};

SchemaNeeds NeedsOf(const PointWriteSpec& spec) {
  SchemaNeeds needs;
  needs.colors = spec.schema.colors;
  needs.gps = spec.schema.ScalarIndex(las_field::kGpsTime) >= 0;
  needs.nir = spec.schema.ScalarIndex(las_field::kNir) >= 0;
  needs.channel = spec.schema.ScalarIndex(las_field::kScannerChannel) >= 0;
  needs.huge = spec.count != kUnknownCount && spec.count > std::numeric_limits<uint32_t>::max();
  return needs;
}

// The attribute of the points that `format` has no place for, or "".
std::string MissingAttribute(int format, const SchemaNeeds& needs) {
  const LasFormatLayout l = LasLayoutOf(format);
  if (needs.colors && l.color_offset < 0) return "colours";
  if (needs.gps && l.gps_offset < 0) return las_field::kGpsTime;
  if (needs.nir && l.nir_offset < 0) return las_field::kNir;
  if (needs.channel && !l.extended) return las_field::kScannerChannel;
  return "";
}

// True when the format holds exactly the points' attributes: nothing lost, nothing invented.
bool Fits(int version, int format, const SchemaNeeds& needs) {
  const LasFormatLayout l = LasLayoutOf(format);
  if (!l.supported || version < 2 || version > 4) return false;
  if ((l.extended || needs.huge) && version < 4) return false;
  return MissingAttribute(format, needs).empty() && (l.color_offset >= 0) == needs.colors &&
         (l.gps_offset >= 0) == needs.gps && (l.nir_offset >= 0) == needs.nir;
}

int LegacyFormat(const SchemaNeeds& needs) { return (needs.colors ? 2 : 0) + (needs.gps ? 1 : 0); }

struct LasFormatChoice {
  int version_minor = 2;
  int format = 0;
};

LasFormatChoice AutoChoice(const SchemaNeeds& needs) {
  if (needs.nir || needs.channel || needs.huge) return {4, needs.nir ? 8 : needs.colors ? 7 : 6};
  return {2, LegacyFormat(needs)};
}

LasFormatChoice ExplicitChoice(const LasMetadata& meta, const PointWriteOptions& options,
                               const SchemaNeeds& needs) {
  const int version = options.las_version_minor;
  LasFormatChoice c;
  if (options.las_point_format >= 0) {
    c.format = options.las_point_format;
  } else if (meta.present && Fits(version, meta.point_format, needs)) {
    c.format = meta.point_format;
  } else {
    c.format = version < 4 ? LegacyFormat(needs) : AutoChoice(needs).format;
  }
  const bool meta_version = meta.present && meta.version_minor >= 2 && meta.version_minor <= 4;
  c.version_minor = version >= 0                    ? version
                    : (c.format >= 6 || needs.huge) ? 4
                    : meta_version                  ? meta.version_minor
                                                    : 2;
  const std::string missing = MissingAttribute(c.format, needs);
  if (!missing.empty()) {
    throw std::invalid_argument(
        (options.las_point_format >= 0
             ? "PointWriteOptions::las_point_format = " + std::to_string(c.format)
             : "PointWriteOptions::las_version_minor = " + std::to_string(version)) +
        "; point format " + std::to_string(c.format) + " cannot hold the points' " + missing);
  }
  if ((c.format >= 6 || needs.huge) && c.version_minor < 4) {
    throw std::invalid_argument(
        "PointWriteOptions::las_version_minor = " + std::to_string(c.version_minor) + "; " +
        (needs.huge ? "more than 2^32-1 points" : "point format " + std::to_string(c.format)) +
        " needs LAS 1.4");
  }
  return c;
}

LasFormatChoice ChooseLasFormat(const PointWriteSpec& spec, const PointWriteOptions& options) {
  const SchemaNeeds needs = NeedsOf(spec);
  const LasMetadata& meta = spec.meta.las;
  if (options.las_point_format >= 0 || options.las_version_minor >= 0) {
    return ExplicitChoice(meta, options, needs);
  }
  if (meta.present && Fits(meta.version_minor, meta.point_format, needs)) {
    return {meta.version_minor, meta.point_format};
  }
  return AutoChoice(needs);
}

// ---- Writer ----

// A GeoTIFF-key projection record (LASF_Projection 34735-34737).
bool IsGeoTiffKeyRecord(const LasVlr& vlr) {
  return vlr.user_id == "LASF_Projection" && vlr.record_id >= 34735 && vlr.record_id <= 34737;
}

// The offset of the chunk table at the start of the point data, then the table.
void WriteChunkTable(AtomicFile* file, uint64_t point_data, const std::vector<uint8_t>& table) {
  uint8_t offset[8];
  StoreLE<uint64_t>(offset, file->Tell());
  file->Write(table.data(), table.size());
  file->WriteAt(point_data, offset, 8);
}

class LasWriter : public PointWriter {
 public:
  LasWriter(const std::string& path, const PointWriteSpec& spec, const PointWriteOptions& options);
  void Write(const PointCloud& chunk) override;
  void Close() override;

 private:
  void InitHeader(const LasFormatChoice& choice, const PointWriteOptions& options);
  void BuildColumns();
  void BindSource(const char* name, LasColumn* c, std::vector<bool>* used) const;
  void AddExtraBytes(const std::string& name, ScalarType type, int scalar, int axis, int* offset);
  void SplitVlrs();
  void AddCrsVlr();
  void WriteHeaderAndVlrs();
  std::string EncodedHeader() const;
  // What a block of records adds to the header: its bounds and return counts, or the first of
  // its points that does not fit (`bad` < its size).
  struct BlockTally {
    std::array<int32_t, 3> min, max;
    std::array<uint64_t, 16> returns{};
    size_t size = 0, bad = 0;
  };
  // Encodes the chunk's blocks [begin, end) (kLasBlockRecords points each) into `records` on
  // the pool's threads, then adds their tallies in order (throwing for the first point that does
  // not fit).
  void EncodeBlocks(const PointCloud& chunk, size_t begin, size_t end, uint8_t* records);
  void EncodeBlock(const PointCloud& chunk, size_t first, size_t n, uint8_t* records,
                   BlockTally* tally) const;
  [[noreturn]] void ThrowOutOfRange(const PointCloud& chunk, size_t i) const;
  Box3d WrittenBounds() const;
  void WriteLazPointData();
  void WriteCopcPointData();

  std::string path_;
  PointWriteSpec spec_;
  LasHeader header_;
  LasFormatLayout layout_;
  bool offset_pending_ = false;  // chosen from the first chunk's bounds
  uint16_t color_factor_ = 257;
  std::vector<LasColumn> columns_;
  std::vector<LasExtraBytes> extra_;
  std::vector<LasVlr> vlrs_, evlrs_;
  std::array<int32_t, 3> min_, max_;
  std::array<uint64_t, 15> by_return_{};
  std::vector<uint8_t> buffer_;
  // COPC (a .copc.laz name): every record is held until Close() builds the octree, in memory or
  // spilled beside the file (io/copc/copc_store.h; a stated count the disk cannot hold is
  // refused before anything is written).
  bool copc_ = false;
  CopcWriteOptions copc_options_;
  StageProgressCallback close_progress_;
  std::unique_ptr<CopcRecordStore> copc_records_;
  std::unique_ptr<AtomicFile> file_;  // created last: a rejected spec creates nothing
  // LAZ (a .laz name): the records go through the chunk writer; the point data starts with the
  // chunk table's offset, patched by Close().
  bool compressed_ = false;
  std::unique_ptr<LazChunkWriter> laz_;
  bool failed_ = false, closed_ = false;
};

bool EndsWith(const std::string& path, const std::string& suffix) {
  if (path.size() < suffix.size()) return false;
  std::string ext = path.substr(path.size() - suffix.size());
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == suffix;
}

bool IsLazPath(const std::string& path) { return EndsWith(path, ".laz"); }

// COPC holds LAS 1.4 formats 6-8 only; 0-3 become 6 or 7 as PDAL's writers.copc converts them.
LasFormatChoice CopcChoice(LasFormatChoice c) {
  c.version_minor = 4;
  if (c.format < 6) c.format = c.format >= 2 ? 7 : 6;
  return c;
}

LasWriter::LasWriter(const std::string& path, const PointWriteSpec& spec,
                     const PointWriteOptions& options)
    : path_(path),
      spec_(spec),
      copc_(EndsWith(path, ".copc.laz")),
      copc_options_(options.copc),
      close_progress_(options.close_progress),
      compressed_(IsLazPath(path)) {
  min_.fill(std::numeric_limits<int32_t>::max());
  max_.fill(std::numeric_limits<int32_t>::min());
  const LasFormatChoice choice = ChooseLasFormat(spec, options);
  InitHeader(copc_ ? CopcChoice(choice) : choice, options);
  BuildColumns();
  SplitVlrs();
  if (copc_) {
    copc_records_ = std::make_unique<CopcRecordStore>(path, header_.record_length,
                                                      layout_.gps_offset, options.copc, spec.count);
  }
  file_ = std::make_unique<AtomicFile>(path);
  WriteHeaderAndVlrs();
}

void SetCreationDateToday(LasHeader* header) {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  header->creation_day = static_cast<uint16_t>(utc.tm_yday + 1);
  header->creation_year = static_cast<uint16_t>(utc.tm_year + 1900);
}

void LasWriter::InitHeader(const LasFormatChoice& choice, const PointWriteOptions& options) {
  const LasMetadata& meta = spec_.meta.las;
  header_.version_minor = static_cast<uint8_t>(choice.version_minor);
  header_.point_format = static_cast<uint8_t>(choice.format);
  header_.header_size = LasHeaderSize(choice.version_minor);
  layout_ = LasLayoutOf(choice.format);
  header_.scale = options.las_scale ? *options.las_scale
                  : meta.present    ? meta.scale
                                    : Eigen::Vector3d::Constant(0.001);
  if (options.las_offset) {
    header_.offset = *options.las_offset;
  } else if (meta.present) {
    header_.offset = meta.offset;
  } else {
    header_.offset = spec_.frame.origin.array().round();
    offset_pending_ = spec_.frame.IsIdentity();
  }
  if (!header_.offset.allFinite()) {
    throw std::invalid_argument("PointWriteOptions::las_offset must be finite");
  }
  CANDI_CHECK(header_.scale.allFinite() && (header_.scale.array() != 0.0).all())
      << "LAS scale " << header_.scale.transpose();
  if (meta.present) {
    header_.file_source_id = meta.file_source_id;
    // Keep the GPS-time type and synthetic-returns bits, and the WKT bit where it exists (1.4);
    // the waveform bits would promise data this writer does not write.
    header_.global_encoding = meta.global_encoding & (choice.version_minor >= 4 ? 0x19 : 0x09);
    header_.system_identifier = meta.system_identifier;
    header_.generating_software = meta.generating_software;
    header_.creation_day = meta.creation_day;
    header_.creation_year = meta.creation_year;
  }
  if (header_.system_identifier.empty()) header_.system_identifier = "candi";
  if (header_.generating_software.empty()) header_.generating_software = kGeneratingSoftware;
  if (header_.creation_year == 0) SetCreationDateToday(&header_);
  // LAS 1.4 asks for the WKT bit with formats 6-10; a preserved header keeps what it had.
  if (!meta.present && layout_.extended) header_.global_encoding |= 0x10;
  color_factor_ = meta.color_16bit ? 257 : 1;
}

// Standard attributes come from the scalar fields of their names; every other scalar field and
// the normals become extra bytes (float or double).
void LasWriter::BuildColumns() {
  const PointSchema& schema = spec_.schema;
  std::vector<bool> used(schema.scalars.size(), false);
  for (const LasStandardColumn& s : LasStandardColumns(header_.point_format)) {
    LasColumn c = ColumnOf(s);
    BindSource(s.name, &c, &used);
    columns_.push_back(c);
  }
  int offset = layout_.record_size;
  for (size_t i = 0; i < schema.scalars.size(); ++i) {
    if (!used[i]) {
      AddExtraBytes(schema.scalars[i].name, schema.scalars[i].type, static_cast<int>(i), -1,
                    &offset);
    }
  }
  if (schema.normals) {
    for (int axis = 0; axis < 3; ++axis) {
      AddExtraBytes(axis == 0   ? "nx"
                    : axis == 1 ? "ny"
                                : "nz",
                    ScalarType::kFloat32, -1, axis, &offset);
    }
  }
  if (offset > 65535 || extra_.size() > 65535 / 192) {
    throw std::invalid_argument("too many scalar fields for a LAS point record (" +
                                std::to_string(extra_.size()) + " extra-bytes fields, " +
                                std::to_string(offset) + " bytes per point)");
  }
  header_.record_length = static_cast<uint16_t>(offset);
}

void LasWriter::BindSource(const char* name, LasColumn* c, std::vector<bool>* used) const {
  const PointSchema& schema = spec_.schema;
  const std::string field = name;
  int index = schema.ScalarIndex(field);
  // Formats 0-5 store the scan angle in degrees, 6-10 in units of 0.006 degrees.
  if (index < 0 && field == las_field::kScanAngleRank) {
    index = schema.ScalarIndex(las_field::kScanAngle);
    c->scale = 0.006;
  } else if (index < 0 && field == las_field::kScanAngle) {
    index = schema.ScalarIndex(las_field::kScanAngleRank);
    c->scale = 1.0 / 0.006;
  }
  if (index >= 0) {
    c->scalar = index;
    (*used)[index] = true;
  } else {
    c->scale = 1.0;
    const bool is_return =
        field == las_field::kReturnNumber || field == las_field::kNumberOfReturns;
    c->constant = is_return ? 1.0 : 0.0;  // a single return, unless told otherwise
  }
}

void LasWriter::AddExtraBytes(const std::string& name, ScalarType type, int scalar, int axis,
                              int* offset) {
  if (name.size() > 32) {
    LogWarning(path_ + ": scalar field '" + name +
               "' is longer than the 32 bytes of a LAS extra-bytes name; truncated");
  }
  const bool is_double = type == ScalarType::kFloat64;
  LasExtraBytes e;
  e.name = name.substr(0, 32);
  e.data_type = is_double ? 10 : 9;
  e.size = is_double ? 8 : 4;
  e.offset = *offset;
  extra_.push_back(e);
  LasColumn c;
  c.raw = is_double ? LasRaw::kF64 : LasRaw::kF32;
  c.offset = *offset;
  c.scalar = scalar;
  c.normal_axis = axis;
  columns_.push_back(c);
  *offset += e.size;
}

// EVLRs stay EVLRs in 1.4; before 1.4 they become VLRs when they fit in one.
void LasWriter::SplitVlrs() {
  const bool v14 = header_.version_minor >= 4;
  for (const LasVlr& vlr : spec_.meta.las.vlrs) {
    if (IsLasExtraBytesVlr(vlr)) continue;  // replaced by this file's own
    // A COPC source's octree describes its own point data: replaced in COPC, dropped otherwise
    // (a stale info VLR first would make readers take the file for COPC).
    if (vlr.user_id == kCopcUserId) continue;
    // COPC is LAS 1.4 format 6-8, whose CRS is WKT only: GeoTIFF keys give way to AddCrsVlr's.
    if (copc_ && IsGeoTiffKeyRecord(vlr)) continue;
    LasVlr copy = vlr;
    const bool fits = vlr.data.size() <= 65535;
    copy.extended = v14 && (vlr.extended || !fits);
    if (copy.extended) {
      evlrs_.push_back(std::move(copy));
    } else if (fits) {
      vlrs_.push_back(std::move(copy));
    } else {
      LogWarning(path_ + ": dropping record '" + vlr.user_id + "' " +
                 std::to_string(vlr.record_id) + " (" + std::to_string(vlr.data.size()) +
                 " bytes): LAS 1." + std::to_string(header_.version_minor) +
                 " VLRs hold at most 65535 bytes");
    }
  }
  if (!extra_.empty()) {
    vlrs_.push_back({"LASF_Spec", 4, "Extra Bytes", EncodeLasExtraBytes(extra_), false});
  }
  AddCrsVlr();
  if (copc_) {  // the info VLR first, as COPC requires; Close() fills it in
    vlrs_.insert(vlrs_.begin(),
                 LasVlr{kCopcUserId, kCopcInfoRecord, "COPC info", EncodeCopcInfo({}), false});
  }
  if (compressed_) {  // last, as LASzip writes it
    const laz::Vlr vlr = laz::WriterVlr(header_.point_format,
                                        header_.record_length - layout_.record_size,
                                        copc_ ? laz::kVariableChunkSize : kLazChunkPoints);
    vlrs_.push_back({"laszip encoded", 22204, "laszip", laz::EncodeVlr(vlr), false});
    if (copc_) return;  // Close() compresses the octree's nodes
    laz_ = std::make_unique<LazChunkWriter>(
        vlr, header_.record_length,
        [this](const uint8_t* data, size_t size) { file_->Write(data, size); });
  }
}

// Points from a file that stated its CRS elsewhere (E57's coordinateMetadata, a scene) carry it
// into the LAS file as a WKT record; records kept from a LAS source already state it.
void LasWriter::AddCrsVlr() {
  const std::string& crs = spec_.meta.crs;
  const bool stated = copc_ ? HasLasCrsRecord(vlrs_) || HasLasCrsRecord(evlrs_)
                            : HasLasCrsRecord(spec_.meta.las.vlrs);
  if (stated) return;
  if (crs.empty()) {
    const bool dropped = copc_ && std::any_of(spec_.meta.las.vlrs.begin(),
                                              spec_.meta.las.vlrs.end(), IsGeoTiffKeyRecord);
    if (dropped) {
      LogWarning(path_ + ": the source's GeoTIFF keys name no CRS PROJ knows; the COPC file, "
                         "which states its CRS as WKT, states none");
    }
    return;
  }
  std::string wkt;
  try {
    wkt = CrsAsWkt1(crs, path_);
  } catch (const InputError& e) {
    LogWarning(std::string(e.what()) + "; the LAS file states no CRS");
    return;
  }
  LasVlr vlr = LasWktVlr(wkt);
  if (vlr.data.size() > 65535 && header_.version_minor < 4) {
    LogWarning(path_ + ": the CRS's WKT (" + std::to_string(vlr.data.size()) +
               " bytes) does not fit a LAS 1." + std::to_string(header_.version_minor) +
               " VLR; the LAS file states no CRS");
    return;
  }
  vlr.extended = vlr.data.size() > 65535;
  (vlr.extended ? evlrs_ : vlrs_).push_back(std::move(vlr));
  if (header_.version_minor >= 4) header_.global_encoding |= 0x10;  // WKT states the CRS
}

void LasWriter::WriteHeaderAndVlrs() {
  std::string records;
  for (const LasVlr& vlr : vlrs_) records += EncodeLasVlr(vlr);
  const uint64_t point_offset = header_.header_size + records.size();
  if (point_offset > std::numeric_limits<uint32_t>::max()) {
    throw InputError(
        path_, "", "VLRs too large for a LAS header (" + std::to_string(point_offset) + " bytes)");
  }
  header_.number_of_vlrs = static_cast<uint32_t>(vlrs_.size());
  header_.offset_to_point_data = static_cast<uint32_t>(point_offset);
  if (spec_.count != kUnknownCount && !compressed_) {
    file_->Reserve(point_offset + spec_.count * header_.record_length);
  }
  file_->Write(EncodedHeader());  // counts and bounds are patched by Close()
  file_->Write(records);
  if (compressed_) file_->Write(std::string(8, '\0'));  // the chunk table's offset
}

std::string LasWriter::EncodedHeader() const {
  if (!compressed_) return EncodeLasHeader(header_);
  LasHeader header = header_;
  header.point_format |= 0x80;  // LASzip's mark of compressed point data
  return EncodeLasHeader(header);
}

void LasWriter::Write(const PointCloud& chunk) {
  CANDI_CHECK(!closed_) << "LasWriter::Write after Close";
  CANDI_CHECK(!failed_) << "LasWriter::Write after a failed Write";
  CANDI_CHECK(chunk.schema == spec_.schema) << "chunk schema differs from the writer's spec";
  chunk.CheckConsistent();
  const size_t n = chunk.size();
  if (n == 0) return;
  if (offset_pending_) {
    // No offset given and no frame: centre the first chunk, so survey coordinates fit int32.
    header_.offset = LocalFrame::Auto(chunk.WorldBounds()).origin;
    offset_pending_ = false;
  }
  const size_t length = header_.record_length;
  const size_t blocks = (n + kLasBlockRecords - 1) / kLasBlockRecords;
  failed_ = true;  // until the chunk is complete: a throw leaves a partial chunk behind
  if (copc_ && !copc_records_->spilled()) {  // straight into the records held for Close()
    uint8_t* records = copc_records_->Extend(n);
    EncodeBlocks(chunk, 0, blocks, records);
    copc_records_->Add(records, n);
  } else {
    // A round of blocks through one buffer that stays in the cache, and no chunk-sized buffer
    // is faulted in.
    constexpr size_t kRoundBlocks = 16;
    buffer_.resize(std::min(n, kRoundBlocks * kLasBlockRecords) * length);
    for (size_t begin = 0; begin < blocks; begin += kRoundBlocks) {
      const size_t end = std::min(blocks, begin + kRoundBlocks);
      EncodeBlocks(chunk, begin, end, buffer_.data());
      const size_t records = std::min(n, end * kLasBlockRecords) - begin * kLasBlockRecords;
      if (copc_) {
        copc_records_->Add(buffer_.data(), records);
      } else if (laz_) {
        laz_->Add(buffer_.data(), records);
      } else {
        file_->Write(buffer_.data(), records * length);
      }
    }
  }
  failed_ = false;
  points_written_ += n;
}

void LasWriter::EncodeBlocks(const PointCloud& chunk, size_t begin, size_t end,
                             uint8_t* records) {
  const size_t n = chunk.size(), length = header_.record_length;
  std::vector<BlockTally> tallies(end - begin);
  ParallelFor(begin, end, [&](size_t b) {
    const size_t first = b * kLasBlockRecords;
    EncodeBlock(chunk, first, std::min(kLasBlockRecords, n - first),
                records + (b - begin) * kLasBlockRecords * length, &tallies[b - begin]);
  });
  for (size_t b = begin; b < end; ++b) {
    const BlockTally& t = tallies[b - begin];
    if (t.bad < t.size) ThrowOutOfRange(chunk, b * kLasBlockRecords + t.bad);
    for (int k = 0; k < 3; ++k) {
      min_[k] = std::min(min_[k], t.min[k]);
      max_[k] = std::max(max_[k], t.max[k]);
    }
    for (int r = 1; r <= 15; ++r) by_return_[r - 1] += t.returns[r];
  }
}

void LasWriter::EncodeBlock(const PointCloud& chunk, size_t first, size_t n, uint8_t* records,
                            BlockTally* tally) const {
  const size_t length = header_.record_length;
  std::memset(records, 0, n * length);
  tally->size = n;
  tally->min.fill(std::numeric_limits<int32_t>::max());
  tally->max.fill(std::numeric_limits<int32_t>::min());
  tally->bad = EncodeLasPositions(chunk.positions.data() + first, n, chunk.frame.origin,
                                  header_.offset, header_.scale, records, length,
                                  tally->min.data(), tally->max.data());
  if (tally->bad < n) return;
  if (spec_.schema.colors && layout_.color_offset >= 0) {
    const uint16_t f = color_factor_;
    const Rgb8* colors = chunk.colors.data() + first;
    uint8_t* p = records + layout_.color_offset;
    for (size_t i = 0; i < n; ++i, p += length) {
      StoreLE<uint16_t>(p, static_cast<uint16_t>(colors[i].r * f));
      StoreLE<uint16_t>(p + 2, static_cast<uint16_t>(colors[i].g * f));
      StoreLE<uint16_t>(p + 4, static_cast<uint16_t>(colors[i].b * f));
    }
  }
  for (const LasColumn& c : columns_) EncodeLasColumn(c, chunk, first, n, records, length);
  const uint8_t mask = layout_.extended ? 15 : 7;
  for (size_t i = 0; i < n; ++i) ++tally->returns[records[i * length + 14] & mask];
}

void LasWriter::ThrowOutOfRange(const PointCloud& chunk, size_t i) const {
  const Eigen::Vector3d w = chunk.WorldPosition(i);
  auto text = [](const Eigen::Vector3d& v) {
    return std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z());
  };
  throw InputError(path_, "point " + std::to_string(points_written_ + i),
                   "coordinate (" + text(w) + ") does not fit LAS int32 with scale (" +
                       text(header_.scale) + ") and offset (" + text(header_.offset) +
                       "); choose a larger scale or a nearer offset");
}

Box3d LasWriter::WrittenBounds() const {
  if (points_written_ == 0) return Box3d{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  Box3d box;
  Eigen::Vector3d a, b;
  for (int k = 0; k < 3; ++k) {
    a[k] = min_[k] * header_.scale[k] + header_.offset[k];
    b[k] = max_[k] * header_.scale[k] + header_.offset[k];
  }
  box.Extend(a);
  box.Extend(b);
  return box;
}

void LasWriter::Close() {
  CANDI_CHECK(!closed_) << "LasWriter::Close twice";
  CANDI_CHECK(!failed_) << "LasWriter::Close after a failed Write";
  closed_ = true;
  if (!SetLasCounts(points_written_, by_return_, &header_)) {
    throw InputError(path_, "",
                     std::to_string(points_written_) + " points do not fit the " +
                         "32-bit point count of LAS 1." + std::to_string(header_.version_minor) +
                         "; write LAS 1.4");
  }
  header_.bounds = WrittenBounds();
  if (copc_) {
    WriteCopcPointData();
  } else if (laz_) {
    WriteLazPointData();
  }
  if (!evlrs_.empty()) {
    header_.start_of_first_evlr = file_->Tell();
    header_.number_of_evlrs = static_cast<uint32_t>(evlrs_.size());
    for (const LasVlr& evlr : evlrs_) file_->Write(EncodeLasVlr(evlr));
  }
  const std::string header = EncodedHeader();
  file_->WriteAt(0, header.data(), header.size());
  file_->Commit();
}

void LasWriter::WriteLazPointData() {
  WriteChunkTable(file_.get(), header_.offset_to_point_data, laz_->Finish());
}

// The octree's nodes as chunks, the chunk table, then the hierarchy as the first EVLR (its pages)
// and the info VLR completed in place.
void LasWriter::WriteCopcPointData() {
  auto stage = [this](const char* name) -> ProgressCallback {
    if (!close_progress_) return {};
    return [this, name](uint64_t done, uint64_t total) { close_progress_(name, done, total); };
  };
  const CopcRecords records = copc_records_->Records();
  const CopcXyzBounds xyz_bounds{min_, max_};  // what the records hold, when n > 0
  const laz::Vlr vlr = laz::ParseVlr(vlrs_.back().data);
  const CopcPointData data = WriteCopcNodes(
      {}, records, header_.scale, header_.offset, &xyz_bounds, vlr, file_->Tell(),
      [this](const uint8_t* bytes, size_t size) { file_->Write(bytes, size); }, stage("octree"),
      stage("chunks"));
  const CopcOctree& tree = data.tree;
  copc_records_->Release();
  WriteChunkTable(file_.get(), header_.offset_to_point_data, data.chunk_table);
  CopcInfo info;
  info.center = tree.center;
  info.halfsize = tree.halfsize;
  info.spacing = tree.spacing;
  // The EVLRs start here, the hierarchy first: its payload after the 60-byte EVLR header.
  const uint64_t payload = file_->Tell() + 60;
  CopcHierarchy hierarchy = EncodeCopcHierarchyPages(copc_options_, data.entries, payload);
  info.root_hier_offset = payload + hierarchy.root_offset;
  info.root_hier_size = hierarchy.root_size;
  const std::array<double, 2> gps = copc_records_->GpsTimes();
  info.gpstime_minimum = gps[0];
  info.gpstime_maximum = gps[1];
  const std::string encoded = EncodeCopcInfo(info);
  file_->WriteAt(header_.header_size + 54, encoded.data(), encoded.size());
  evlrs_.insert(evlrs_.begin(),
                LasVlr{kCopcUserId, kCopcHierarchyRecord, "EPT hierarchy",
                       std::move(hierarchy.data), true});
}

}  // namespace

std::unique_ptr<PointWriter> OpenLasWriter(const std::string& path, const PointWriteSpec& spec,
                                           const PointWriteOptions& options) {
  options.Check();
  return std::make_unique<LasWriter>(path, spec, options);
}

}  // namespace candi::io
