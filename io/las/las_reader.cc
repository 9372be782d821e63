// The LAS/LAZ reader behind OpenLasReader (io/las/las_io.h): the header, VLRs and schema, then
// records decoded column by column from the mapped file (LAZ through its chunks).
#include "io/las/las_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/mapped_file.h"
#include "core/parallel.h"
#include "io/crs.h"
#include "io/las/las_colour_scan_internal.h"
#include "io/las/las_columns.h"
#include "io/las/las_crs_internal.h"
#include "io/las/las_header.h"
#include "io/laz/laz_chunks.h"
#include "io/laz/laz_format.h"

namespace candi::io {

namespace {

constexpr size_t kColorScanBytes = 8 << 20;

class LasReader : public PointReader {
 public:
  LasReader(const std::string& path, const PointReadOptions& options);
  size_t Read(size_t max_points, PointCloud* chunk) override;
  std::optional<PointRecordLayout> record_layout() const override;

 private:
  void TakeLaszipVlr(std::vector<LasVlr>* vlrs);
  void CheckPointDataSize() const;
  std::vector<LasExtraBytes> FillInfo(std::vector<LasVlr> vlrs);
  void BuildSchema(const std::vector<LasExtraBytes>& extra);
  void AddExtraColumns(const std::vector<LasExtraBytes>& extra);
  bool HasWideColors();
  bool HasWideColorsLaz();
  const uint8_t* PointRecords(uint64_t first, size_t n) const;
  void DecodeRecords(const uint8_t* records, size_t n, size_t first, PointCloud* chunk) const;
  void DecodeBlock(const uint8_t* records, size_t n, size_t first, PointCloud* chunk) const;

  BinaryFile file_;
  bool scalar_fields_ = true;  // PointReadOptions::scalar_fields
  LasHeader header_;
  LasFormatLayout layout_;
  std::vector<LasColumn> columns_;
  int color_shift_ = 8;
  // Uncompressed: the file, decoded in place, shared with any other pass that has it mapped
  // (MapShared: the packer's hash of its inputs).
  std::shared_ptr<const MappedFile> map_;
  // LAZ: point-format bits 6-7 set; the laszip VLR and the decoded chunks.
  bool compressed_ = false;
  laz::Vlr laz_;
  std::unique_ptr<LazPointData> laz_data_;
};

LasReader::LasReader(const std::string& path, const PointReadOptions& options)
    : PointReader(path), file_(path), scalar_fields_(options.scalar_fields) {
  header_ = ReadLasHeader(&file_);
  compressed_ = (header_.point_format & 0xC0) != 0;
  header_.point_format &= 0x3F;
  layout_ = LasLayoutOf(header_.point_format);
  std::vector<LasVlr> vlrs = ReadLasVlrs(&file_, header_);
  TakeLaszipVlr(&vlrs);
  info_.count = LasPointCount(header_);
  if (compressed_) {
    laz_data_ = std::make_unique<LazPointData>(
        &file_, laz_,
        ReadLazChunkTable(file_, laz_, header_.offset_to_point_data, info_.count,
                          header_.record_length),
        header_.record_length);
  } else {
    CheckPointDataSize();
    map_ = MapShared(path);
  }
  for (LasVlr& evlr : ReadLasEvlrs(&file_, header_)) vlrs.push_back(std::move(evlr));
  BuildSchema(FillInfo(std::move(vlrs)));
  if (info_.schema.colors) {
    info_.meta.las.color_16bit = CachedWideColours(path, [this] { return HasWideColors(); });
    color_shift_ = info_.meta.las.color_16bit ? 8 : 0;
  }
}

// LASzip marks compressed files in the format byte and describes them in a VLR. The VLR leaves
// the list (meta.las.vlrs): a LAS written from these points is not compressed.
void LasReader::TakeLaszipVlr(std::vector<LasVlr>* vlrs) {
  const auto it = std::find_if(vlrs->begin(), vlrs->end(), [](const LasVlr& vlr) {
    return vlr.user_id == "laszip encoded" && vlr.record_id == 22204;
  });
  if (it == vlrs->end()) {
    if (!compressed_) return;
    throw InputError(path_, "byte 104",
                     "the point format byte marks LAZ (compressed LAS) but the file has no "
                     "\"laszip encoded\" VLR describing the compression");
  }
  const LasVlr vlr = *it;
  vlrs->erase(it);
  if (!compressed_) {
    LogWarning(path_ + ": ignoring a \"laszip encoded\" VLR in an uncompressed LAS file");
    return;
  }
  try {
    laz_ = laz::ParseVlr(vlr.data);
    laz::CheckSupported(laz_, header_.point_format, header_.record_length);
  } catch (const laz::LazError& e) {
    throw InputError(path_, "laszip VLR", std::string("LAZ: ") + e.what());
  }
}

void LasReader::CheckPointDataSize() const {
  const uint64_t available = file_.size() - header_.offset_to_point_data;
  const uint64_t length = header_.record_length;
  if (info_.count <= available / length) return;
  const std::string needed = info_.count <= std::numeric_limits<uint64_t>::max() / length
                                 ? std::to_string(info_.count * length)
                                 : "more than 2^64";
  throw InputError(path_, "byte " + std::to_string(file_.size()),
                   "header promises " + std::to_string(info_.count) + " points (" + needed +
                       " bytes from byte " + std::to_string(header_.offset_to_point_data) +
                       ") but the file holds " + std::to_string(available) + " bytes");
}

std::vector<LasExtraBytes> LasReader::FillInfo(std::vector<LasVlr> vlrs) {
  const int format = header_.point_format;
  info_.format = PointFormat::kLas;
  info_.description =
      "LAS 1." + std::to_string(header_.version_minor) + " point format " + std::to_string(format);
  if (compressed_) info_.description = "LAZ: " + info_.description + ", " + laz::Describe(laz_);
  info_.header_bounds = header_.bounds;
  LasMetadata& las = info_.meta.las;
  las.present = true;
  las.version_minor = header_.version_minor;
  las.point_format = header_.point_format;
  las.scale = header_.scale;
  las.offset = header_.offset;
  las.file_source_id = header_.file_source_id;
  las.global_encoding = header_.global_encoding;
  las.system_identifier = header_.system_identifier;
  las.generating_software = header_.generating_software;
  las.creation_day = header_.creation_day;
  las.creation_year = header_.creation_year;
  std::string crs_note;
  info_.meta.crs = LasCrsOf(vlrs, &crs_note);
  if (!crs_note.empty()) LogInfo(path_ + ": " + crs_note);
  std::vector<LasExtraBytes> extra;
  for (LasVlr& vlr : vlrs) {
    if (!IsLasExtraBytesVlr(vlr)) {
      las.vlrs.push_back(std::move(vlr));
    } else if (extra.empty()) {
      extra = ParseLasExtraBytes(vlr.data, layout_.record_size);
    }
  }
  return extra;
}

void LasReader::BuildSchema(const std::vector<LasExtraBytes>& extra) {
  PointSchema& schema = info_.schema;
  schema.position_type = ScalarType::kFloat64;
  schema.colors = layout_.color_offset >= 0;
  for (const LasStandardColumn& s : LasStandardColumns(header_.point_format)) {
    if (!scalar_fields_) break;
    LasColumn c = ColumnOf(s);
    c.scalar = static_cast<int>(schema.scalars.size());
    schema.scalars.push_back(
        {s.name, s.raw == LasRaw::kF64 ? ScalarType::kFloat64 : ScalarType::kFloat32});
    FillLasByteTable(&c);
    columns_.push_back(c);
  }
  AddExtraColumns(extra);
}

int NormalAxis(const std::string& name) {
  return name == "nx" ? 0 : name == "ny" ? 1 : name == "nz" ? 2 : -1;
}

bool HasNormals(const std::vector<LasExtraBytes>& extra) {
  int found = 0;
  for (const LasExtraBytes& e : extra) {
    if (e.data_type >= 1 && e.data_type <= 10 && NormalAxis(e.name) >= 0) {
      found |= 1 << NormalAxis(e.name);
    }
  }
  return found == 7;
}

void LasReader::AddExtraColumns(const std::vector<LasExtraBytes>& extra) {
  PointSchema& schema = info_.schema;
  schema.normals = HasNormals(extra);
  std::string skipped;
  for (const LasExtraBytes& e : extra) {
    if (e.offset + e.size > header_.record_length) {
      LogWarning(path_ + ": extra bytes '" + e.name + "' and after lie beyond the " +
                 std::to_string(header_.record_length) + "-byte point record; ignored");
      break;
    }
    if (e.data_type < 1 || e.data_type > 10) {
      skipped += (skipped.empty() ? "'" : ", '") + e.name + "'";
      continue;
    }
    LasColumn c;
    c.raw = LasRawOfExtraBytesType(e.data_type);
    c.offset = e.offset;
    c.scale = e.scale;
    c.add = e.add;
    c.normal_axis = schema.normals ? NormalAxis(e.name) : -1;
    if (c.normal_axis < 0 && !scalar_fields_) continue;
    if (c.normal_axis < 0 && (e.name.empty() || schema.ScalarIndex(e.name) >= 0)) {
      LogWarning(path_ + ": extra bytes field '" + e.name +
                 "' is unnamed or repeats a name; skipped");
      continue;
    }
    if (c.normal_axis < 0) {
      c.scalar = static_cast<int>(schema.scalars.size());
      schema.scalars.push_back({e.name, LasScalarTypeOf(e)});
      if (!e.scaled) FillLasByteTable(&c);
    }
    columns_.push_back(c);
  }
  if (!skipped.empty()) {
    LogInfo(path_ +
            ": skipping extra bytes of unsupported types (undocumented or arrays): " + skipped);
  }
}

// Many files store 8-bit colour in the 16-bit fields; only the data tells which. Scans the high
// bytes of every colour in large reads and stops at the first one that is set.
bool LasReader::HasWideColors() {
  if (compressed_) return HasWideColorsLaz();
  const size_t length = header_.record_length;
  const size_t per_read = std::max<size_t>(1, kColorScanBytes / length);
  for (uint64_t done = 0; done < info_.count;) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(per_read, info_.count - done));
    const uint8_t* p = PointRecords(done, n) + layout_.color_offset + 1;
    uint8_t high = 0;
    for (size_t i = 0; i < n; ++i, p += length) high |= p[0] | p[2] | p[4];
    if (high != 0) return true;
    done += n;
  }
  return false;
}

// The same scan over decoded chunks, a run at a time.
bool LasReader::HasWideColorsLaz() {
  const size_t length = header_.record_length;
  for (uint64_t done = 0; done < info_.count;) {
    size_t n = 0;
    const uint8_t* p = laz_data_->Records(done, info_.count, &n) + layout_.color_offset + 1;
    uint8_t high = 0;
    for (size_t i = 0; i < n; ++i, p += length) high |= p[0] | p[2] | p[4];
    if (high != 0) return true;
    done += n;
  }
  return false;
}

size_t LasReader::Read(size_t max_points, PointCloud* chunk) {
  CANDI_CHECK(max_points > 0) << "Read needs max_points > 0";
  PrepareChunk(chunk);
  const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, info_.count - points_read_));
  chunk->Resize(n);
  if (n == 0) return 0;
  if (compressed_) {
    // Runs of decoded chunks; a run may end inside this read or reach beyond it.
    for (size_t done = 0; done < n;) {
      size_t available = 0;
      const uint8_t* records =
          laz_data_->Records(points_read_ + done, points_read_ + n, &available);
      const size_t take = std::min(n - done, available);
      DecodeRecords(records, take, done, chunk);
      done += take;
    }
  } else {
    DecodeRecords(PointRecords(points_read_, n), n, 0, chunk);
  }
  points_read_ += n;
  return n;
}

// Uncompressed: records [first, first + n) in the map. CheckPointDataSize() saw them in the
// file; CheckSize turns a file truncated since then into an error instead of SIGBUS.
const uint8_t* LasReader::PointRecords(uint64_t first, size_t n) const {
  const uint64_t begin = header_.offset_to_point_data + first * header_.record_length;
  const uint64_t bytes = uint64_t{n} * header_.record_length;
  if (begin + bytes > map_->size()) {
    throw InputError(path_, "byte " + std::to_string(map_->size()),
                     "unexpected end of file while reading point records (needed " +
                         std::to_string(bytes) + " bytes at byte " + std::to_string(begin) + ")");
  }
  map_->CheckSize(begin + bytes, "point records");
  map_->WillNeed(begin, bytes);
  return map_->data() + begin;
}

// Blocks decode independently (each writes its own range of the chunk), so they run in
// parallel; the result does not depend on the thread count.
void LasReader::DecodeRecords(const uint8_t* records, size_t n, size_t first,
                              PointCloud* chunk) const {
  const size_t length = header_.record_length;
  const size_t blocks = (n + kLasBlockRecords - 1) / kLasBlockRecords;
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    const size_t at = b * kLasBlockRecords;
    DecodeBlock(records + at * length, std::min(kLasBlockRecords, n - at), first + at, chunk);
  });
}

std::optional<PointRecordLayout> LasReader::record_layout() const {
  if (compressed_) return std::nullopt;  // compressed records: Read() decodes them
  PointRecordLayout l;
  l.coordinates = PointRecordLayout::Coordinates::kLasInt32;
  l.first_byte = header_.offset_to_point_data;
  l.stride = header_.record_length;
  l.xyz[0] = 0, l.xyz[1] = 4, l.xyz[2] = 8;
  if (info_.schema.colors) {
    for (int c = 0; c < 3; ++c) l.rgb[c] = layout_.color_offset + 2 * c;
  }
  l.color_bytes = 2;
  l.color_shift = color_shift_;
  l.scale = header_.scale;
  l.offset = header_.offset;
  l.count = info_.count;
  return l;
}

void LasReader::DecodeBlock(const uint8_t* records, size_t n, size_t first,
                            PointCloud* chunk) const {
  const size_t length = header_.record_length;
  DecodeLasPositions(records, length, n, header_.scale, header_.offset,
                     chunk->positions.data() + first);
  if (info_.schema.colors) {
    DecodeLasColors(records + layout_.color_offset, length, n, color_shift_,
                    chunk->colors.data() + first);
  }
  for (const LasColumn& c : columns_) DecodeLasColumn(c, records, length, n, first, chunk);
}

}  // namespace

std::unique_ptr<PointReader> OpenLasReader(const std::string& path,
                                           const PointReadOptions& options) {
  return std::make_unique<LasReader>(path, options);
}

}  // namespace candi::io
