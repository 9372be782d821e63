#include "io/las/las_header.h"

#include <cmath>
#include <limits>

#include "core/check.h"
#include "core/log.h"

namespace candi::io {

namespace {

constexpr size_t kVlrHeaderSize = 54;
constexpr size_t kEvlrHeaderSize = 60;
constexpr size_t kExtraBytesDescriptorSize = 192;

std::string Byte(uint64_t position) { return "byte " + std::to_string(position); }

// A fixed-size, NUL-padded character field.
std::string FixedString(const uint8_t* p, size_t size) {
  size_t n = 0;
  while (n < size && p[n] != 0) ++n;
  return std::string(reinterpret_cast<const char*>(p), n);
}

void PutFixedString(const std::string& s, size_t size, uint8_t* p) {
  std::memcpy(p, s.data(), std::min(s.size(), size));
}

std::string DescribeVector(const Eigen::Vector3d& v) {
  return std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z());
}

void DecodeHeaderFields(const uint8_t* b, LasHeader* h) {
  h->file_source_id = LoadLE<uint16_t>(b + 4);
  h->global_encoding = LoadLE<uint16_t>(b + 6);
  h->version_minor = b[25];
  h->system_identifier = FixedString(b + 26, 32);
  h->generating_software = FixedString(b + 58, 32);
  h->creation_day = LoadLE<uint16_t>(b + 90);
  h->creation_year = LoadLE<uint16_t>(b + 92);
  h->header_size = LoadLE<uint16_t>(b + 94);
  h->offset_to_point_data = LoadLE<uint32_t>(b + 96);
  h->number_of_vlrs = LoadLE<uint32_t>(b + 100);
  h->point_format = b[104];
  h->record_length = LoadLE<uint16_t>(b + 105);
  h->legacy_count = LoadLE<uint32_t>(b + 107);
  for (int i = 0; i < 5; ++i) h->legacy_by_return[i] = LoadLE<uint32_t>(b + 111 + 4 * i);
  for (int k = 0; k < 3; ++k) {
    h->scale[k] = LoadLE<double>(b + 131 + 8 * k);
    h->offset[k] = LoadLE<double>(b + 155 + 8 * k);
    h->bounds.max[k] = LoadLE<double>(b + 179 + 16 * k);
    h->bounds.min[k] = LoadLE<double>(b + 187 + 16 * k);
  }
}

// Fields of 1.3 and 1.4, read only when the file's header holds them.
void DecodeExtendedFields(const uint8_t* b, LasHeader* h) {
  if (h->version_minor >= 3) h->start_of_waveform = LoadLE<uint64_t>(b + 227);
  if (h->version_minor < 4) return;
  h->start_of_first_evlr = LoadLE<uint64_t>(b + 235);
  h->number_of_evlrs = LoadLE<uint32_t>(b + 243);
  h->count = LoadLE<uint64_t>(b + 247);
  for (int i = 0; i < 15; ++i) h->by_return[i] = LoadLE<uint64_t>(b + 255 + 8 * i);
}

void CheckSizes(const BinaryFile& file, const LasHeader& h) {
  const std::string& path = file.path();
  const int version_size = LasHeaderSize(h.version_minor);
  if (h.header_size < version_size) {
    throw InputError(path, Byte(94),
                     "header size " + std::to_string(h.header_size) + " is smaller than the " +
                         std::to_string(version_size) + " bytes of a LAS 1." +
                         std::to_string(h.version_minor) + " header");
  }
  if (h.offset_to_point_data < h.header_size || h.offset_to_point_data > file.size()) {
    throw InputError(path, Byte(96),
                     "offset to point data " + std::to_string(h.offset_to_point_data) +
                         " lies outside the file (header " + std::to_string(h.header_size) +
                         " bytes, file " + std::to_string(file.size()) + " bytes)");
  }
}

// LASzip marks compressed point data with bits 7 (and 6) of the format byte; the LAS reader
// decodes it (io/laz/laz_format.h), so only the format proper is checked here.
void CheckPointFormat(const std::string& path, const LasHeader& h) {
  const int format = h.point_format & 0x3F;
  const LasFormatLayout layout = LasLayoutOf(format);
  if (!layout.supported) {
    throw InputError(path, Byte(104),
                     "point format " + std::to_string(format) +
                         (layout.record_size > 0 ? " (waveform) is not supported" : " is unknown") +
                         " (candi reads point formats 0-3 and 6-8)");
  }
  if (h.record_length < layout.record_size) {
    throw InputError(path, Byte(105),
                     "point record length " + std::to_string(h.record_length) +
                         " is smaller than the " + std::to_string(layout.record_size) +
                         " bytes of point format " + std::to_string(format));
  }
}

void CheckScaleAndOffset(const std::string& path, const LasHeader& h) {
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(h.scale[k]) || h.scale[k] == 0.0) {
      throw InputError(
          path, Byte(131 + 8 * k),
          "scale factors (" + DescribeVector(h.scale) + ") must be finite and non-zero");
    }
    if (!std::isfinite(h.offset[k])) {
      throw InputError(path, Byte(155 + 8 * k), "offsets must be finite");
    }
  }
}

int ExtraBytesTypeSize(int data_type) {
  static constexpr int kSizes[] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
  if (data_type >= 1 && data_type <= 10) return kSizes[data_type - 1];
  if (data_type >= 11 && data_type <= 20) return 2 * kSizes[data_type - 11];
  if (data_type >= 21 && data_type <= 30) return 3 * kSizes[data_type - 21];
  return 0;
}

}  // namespace

LasFormatLayout LasLayoutOf(int point_format) {
  LasFormatLayout l;
  static constexpr int kSizes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  if (point_format < 0 || point_format > 10) return l;
  l.record_size = kSizes[point_format];
  l.extended = point_format >= 6;
  l.supported = point_format <= 3 || (point_format >= 6 && point_format <= 8);
  if (point_format == 1 || point_format == 3 || point_format == 4 || point_format == 5) {
    l.gps_offset = 20;
  }
  if (l.extended) l.gps_offset = 22;
  if (point_format == 2) l.color_offset = 20;
  if (point_format == 3 || point_format == 5) l.color_offset = 28;
  if (point_format == 7 || point_format == 8 || point_format == 10) l.color_offset = 30;
  if (point_format == 8 || point_format == 10) l.nir_offset = 36;
  return l;
}

uint16_t LasHeaderSize(int version_minor) {
  return version_minor >= 4 ? 375 : version_minor == 3 ? 235 : 227;
}

LasHeader ReadLasHeader(BinaryFile* file) {
  const std::string& path = file->path();
  if (file->size() == 0) throw InputError(path, Byte(0), "empty file");
  uint8_t b[375] = {};
  file->Seek(0);
  const size_t got = file->ReadSome(b, sizeof(b));
  if (got < 4 || std::memcmp(b, "LASF", 4) != 0) {
    throw InputError(path, Byte(0), "not a LAS file (no \"LASF\" signature)");
  }
  if (got < 227) {
    throw InputError(
        path, Byte(got),
        "file ends inside the LAS header (" + std::to_string(got) + " of at least 227 bytes)");
  }
  LasHeader h;
  DecodeHeaderFields(b, &h);
  if (b[24] != 1 || h.version_minor > 4) {
    throw InputError(path, Byte(24),
                     "unsupported LAS version " + std::to_string(b[24]) + "." +
                         std::to_string(h.version_minor) + " (candi reads 1.0-1.4)");
  }
  CheckSizes(*file, h);
  DecodeExtendedFields(b, &h);
  CheckPointFormat(path, h);
  CheckScaleAndOffset(path, h);
  return h;
}

std::string EncodeLasHeader(const LasHeader& h) {
  uint8_t b[375] = {};
  std::memcpy(b, "LASF", 4);
  StoreLE<uint16_t>(b + 4, h.file_source_id);
  StoreLE<uint16_t>(b + 6, h.global_encoding);
  b[24] = 1;
  b[25] = h.version_minor;
  PutFixedString(h.system_identifier, 32, b + 26);
  PutFixedString(h.generating_software, 32, b + 58);
  StoreLE<uint16_t>(b + 90, h.creation_day);
  StoreLE<uint16_t>(b + 92, h.creation_year);
  StoreLE<uint16_t>(b + 94, h.header_size);
  StoreLE<uint32_t>(b + 96, h.offset_to_point_data);
  StoreLE<uint32_t>(b + 100, h.number_of_vlrs);
  b[104] = h.point_format;
  StoreLE<uint16_t>(b + 105, h.record_length);
  StoreLE<uint32_t>(b + 107, h.legacy_count);
  for (int i = 0; i < 5; ++i) StoreLE<uint32_t>(b + 111 + 4 * i, h.legacy_by_return[i]);
  for (int k = 0; k < 3; ++k) {
    StoreLE<double>(b + 131 + 8 * k, h.scale[k]);
    StoreLE<double>(b + 155 + 8 * k, h.offset[k]);
    StoreLE<double>(b + 179 + 16 * k, h.bounds.max[k]);
    StoreLE<double>(b + 187 + 16 * k, h.bounds.min[k]);
  }
  StoreLE<uint64_t>(b + 227, h.start_of_waveform);
  StoreLE<uint64_t>(b + 235, h.start_of_first_evlr);
  StoreLE<uint32_t>(b + 243, h.number_of_evlrs);
  StoreLE<uint64_t>(b + 247, h.count);
  for (int i = 0; i < 15; ++i) StoreLE<uint64_t>(b + 255 + 8 * i, h.by_return[i]);
  CANDI_CHECK(h.header_size == LasHeaderSize(h.version_minor)) << "header size " << h.header_size;
  return std::string(reinterpret_cast<const char*>(b), h.header_size);
}

uint64_t LasPointCount(const LasHeader& header) {
  if (header.version_minor < 4 || header.count == 0) return header.legacy_count;
  if (header.legacy_count != 0 && header.legacy_count != header.count) {
    LogWarning("LAS header: legacy point count " + std::to_string(header.legacy_count) +
               " differs from the 64-bit count " + std::to_string(header.count) +
               "; using the 64-bit count");
  }
  return header.count;
}

bool SetLasCounts(uint64_t count, const std::array<uint64_t, 15>& by_return, LasHeader* header) {
  const bool fits = count <= std::numeric_limits<uint32_t>::max();
  const bool legacy_format = (header->point_format & 0x3F) <= 5;
  if (header->version_minor < 4 && !(fits && legacy_format)) return false;
  header->count = count;
  header->by_return = by_return;
  header->legacy_count = fits && legacy_format ? static_cast<uint32_t>(count) : 0;
  for (int i = 0; i < 5; ++i) {
    // Each per-return count is at most the total, so it fits whenever the total does.
    header->legacy_by_return[i] = header->legacy_count ? static_cast<uint32_t>(by_return[i]) : 0;
  }
  return true;
}

std::vector<LasVlr> ReadLasVlrs(BinaryFile* file, const LasHeader& header) {
  std::vector<LasVlr> vlrs;
  uint64_t position = header.header_size;
  const uint64_t end = header.offset_to_point_data;
  for (uint32_t i = 0; i < header.number_of_vlrs; ++i) {
    uint8_t b[kVlrHeaderSize];
    if (position + kVlrHeaderSize > end) {
      throw InputError(file->path(), Byte(position),
                       "VLR " + std::to_string(i + 1) + " of " +
                           std::to_string(header.number_of_vlrs) +
                           " runs past the start of the point data at byte " + std::to_string(end));
    }
    file->Seek(position);
    file->ReadExact(b, sizeof(b), "a VLR header");
    LasVlr vlr;
    vlr.user_id = FixedString(b + 2, 16);
    vlr.record_id = LoadLE<uint16_t>(b + 18);
    vlr.description = FixedString(b + 22, 32);
    const uint16_t length = LoadLE<uint16_t>(b + 20);
    if (position + kVlrHeaderSize + length > end) {
      throw InputError(file->path(), Byte(position + 20),
                       "VLR '" + vlr.user_id + "' " + std::to_string(vlr.record_id) + " (" +
                           std::to_string(length) +
                           " bytes) runs past the start of the point "
                           "data at byte " +
                           std::to_string(end));
    }
    vlr.data.resize(length);
    file->ReadExact(vlr.data.data(), length, "a VLR payload");
    vlrs.push_back(std::move(vlr));
    position += kVlrHeaderSize + length;
  }
  return vlrs;
}

std::vector<LasVlr> ReadLasEvlrs(BinaryFile* file, const LasHeader& header) {
  std::vector<LasVlr> evlrs;
  if (header.version_minor < 4 || header.number_of_evlrs == 0) return evlrs;
  uint64_t position = header.start_of_first_evlr;
  if (position < header.offset_to_point_data) {
    throw InputError(
        file->path(), Byte(235),
        "start of the first EVLR (" + std::to_string(position) + ") lies before the point data");
  }
  for (uint32_t i = 0; i < header.number_of_evlrs; ++i) {
    uint8_t b[kEvlrHeaderSize];
    file->Seek(position);  // throws naming the position when it lies beyond the end
    file->ReadExact(b, sizeof(b), "an EVLR header");
    LasVlr vlr;
    vlr.extended = true;
    vlr.user_id = FixedString(b + 2, 16);
    vlr.record_id = LoadLE<uint16_t>(b + 18);
    vlr.description = FixedString(b + 28, 32);
    const uint64_t length = LoadLE<uint64_t>(b + 20);
    if (length > file->remaining()) {
      throw InputError(file->path(), Byte(position + 20),
                       "EVLR '" + vlr.user_id + "' promises " + std::to_string(length) +
                           " bytes but the file holds " + std::to_string(file->remaining()));
    }
    vlr.data.resize(length);
    file->ReadExact(vlr.data.data(), length, "an EVLR payload");
    evlrs.push_back(std::move(vlr));
    position += kEvlrHeaderSize + length;
  }
  return evlrs;
}

std::string EncodeLasVlr(const LasVlr& vlr) {
  const size_t header_size = vlr.extended ? kEvlrHeaderSize : kVlrHeaderSize;
  CANDI_CHECK(vlr.extended || vlr.data.size() <= 65535) << "VLR payload " << vlr.data.size();
  std::string out(header_size, '\0');
  auto* b = reinterpret_cast<uint8_t*>(out.data());
  PutFixedString(vlr.user_id, 16, b + 2);
  StoreLE<uint16_t>(b + 18, vlr.record_id);
  if (vlr.extended) {
    StoreLE<uint64_t>(b + 20, vlr.data.size());
  } else {
    StoreLE<uint16_t>(b + 20, static_cast<uint16_t>(vlr.data.size()));
  }
  PutFixedString(vlr.description, 32, b + header_size - 32);
  return out + vlr.data;
}

bool IsLasExtraBytesVlr(const LasVlr& vlr) {
  return vlr.user_id == "LASF_Spec" && vlr.record_id == 4;
}

std::vector<LasExtraBytes> ParseLasExtraBytes(const std::string& data, int first_offset) {
  std::vector<LasExtraBytes> fields;
  const auto* base = reinterpret_cast<const uint8_t*>(data.data());
  int offset = first_offset;
  for (size_t at = 0; at + kExtraBytesDescriptorSize <= data.size();
       at += kExtraBytesDescriptorSize) {
    const uint8_t* d = base + at;
    LasExtraBytes field;
    field.data_type = d[2];
    const uint8_t options = d[3];
    field.name = FixedString(d + 4, 32);
    // Type 0 ("undocumented extra bytes") keeps its length in the options byte.
    field.size = field.data_type == 0 ? options : ExtraBytesTypeSize(field.data_type);
    field.offset = offset;
    const double scale = LoadLE<double>(d + 112);
    const double add = LoadLE<double>(d + 136);
    if ((options & 0x08) && std::isfinite(scale) && scale != 0.0) field.scale = scale;
    if ((options & 0x10) && std::isfinite(add)) field.add = add;
    field.scaled = field.scale != 1.0 || field.add != 0.0;
    offset += field.size;
    fields.push_back(field);
  }
  return fields;
}

std::string EncodeLasExtraBytes(const std::vector<LasExtraBytes>& fields) {
  std::string out(fields.size() * kExtraBytesDescriptorSize, '\0');
  for (size_t i = 0; i < fields.size(); ++i) {
    auto* d = reinterpret_cast<uint8_t*>(out.data()) + i * kExtraBytesDescriptorSize;
    CANDI_CHECK(fields[i].data_type == 9 || fields[i].data_type == 10) << fields[i].data_type;
    d[2] = static_cast<uint8_t>(fields[i].data_type);
    PutFixedString(fields[i].name, 32, d + 4);
    PutFixedString("candi scalar field", 32, d + 160);
  }
  return out;
}

}  // namespace candi::io
