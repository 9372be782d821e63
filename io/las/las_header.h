// LAS file layout below the codec: the public header, VLR/EVLR records, Extra Bytes descriptors and
// point record layouts (ASPRS LAS 1.4 R15: tables 3, 4, 6, 24, 25; 1.2 and 1.3 headers are prefixes
// of the 1.4 one). Internal to the LAS codec (io/las/las_reader.cc, las_writer.cc); kept apart so
// the byte-level parsing and the point-count logic can be unit-tested.
//
// Failure: ReadLasHeader/ReadLasVlrs/ReadLasEvlrs throw InputError("<path>: byte <pos>: ...").
// Not thread-safe (they move the BinaryFile's position).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/binary_file.h"
#include "core/box.h"
#include "core/point_cloud.h"

namespace candi::io {

// Byte layout of a point data record format.
struct LasFormatLayout {
  int record_size = 0;  // standard record length, bytes (0: unknown format)
  int gps_offset = -1;  // byte offset of each attribute in the record; -1 when absent
  int color_offset = -1;
  int nir_offset = -1;
  bool extended = false;   // formats 6-10: 4-bit returns, 8-bit class, int16 scan angle
  bool supported = false;  // candi reads and writes it (0-3, 6-8; not the waveform formats)
};
// `point_format` without the LAZ bits; formats above 10 give record_size 0.
LasFormatLayout LasLayoutOf(int point_format);

struct LasHeader {
  uint16_t file_source_id = 0;
  uint16_t global_encoding = 0;
  uint8_t version_minor = 2;
  std::string system_identifier, generating_software;  // up to 32 bytes each
  uint16_t creation_day = 0, creation_year = 0;
  uint16_t header_size = 227;
  uint32_t offset_to_point_data = 227;
  uint32_t number_of_vlrs = 0;
  uint8_t point_format = 0;  // the raw byte (LASzip sets bits 6-7)
  uint16_t record_length = 20;
  uint32_t legacy_count = 0;
  std::array<uint32_t, 5> legacy_by_return{};
  Eigen::Vector3d scale = Eigen::Vector3d::Constant(0.001);
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Box3d bounds;                          // world, as stated in the header
  uint64_t start_of_waveform = 0;        // 1.3+
  uint64_t start_of_first_evlr = 0;      // 1.4
  uint32_t number_of_evlrs = 0;          // 1.4
  uint64_t count = 0;                    // 1.4 64-bit point count
  std::array<uint64_t, 15> by_return{};  // 1.4 points by return number 1-15
};

// Public header size of a version: 227 (1.0-1.2), 235 (1.3), 375 (1.4).
uint16_t LasHeaderSize(int version_minor);

// Parses the public header at the start of `file` and validates what does not depend on the
// VLRs: signature, version, header size and point data offset, point format (without the LAZ
// bits 6-7, which header.point_format keeps), record length,
// scale and offset.
LasHeader ReadLasHeader(BinaryFile* file);
// The header's first header.header_size bytes (fields beyond the version's header are omitted).
std::string EncodeLasHeader(const LasHeader& header);

// Number of points the header states: the 1.4 64-bit count when non-zero, else the legacy one.
uint64_t LasPointCount(const LasHeader& header);
// Sets the count fields from the total and the per-return counts (index 0 = return 1): the
// 64-bit fields, and the legacy 32-bit ones when the count fits and the format is 0-5 (LAS 1.4
// leaves them zero otherwise). Returns false when the version (< 1.4) cannot state the count.
bool SetLasCounts(uint64_t count, const std::array<uint64_t, 15>& by_return, LasHeader* header);

// The VLRs between the header and the point data, and the EVLRs after it (1.4).
std::vector<LasVlr> ReadLasVlrs(BinaryFile* file, const LasHeader& header);
std::vector<LasVlr> ReadLasEvlrs(BinaryFile* file, const LasHeader& header);
// A record with its 54-byte (VLR) or 60-byte (EVLR, vlr.extended) header. A VLR's payload must
// fit in 65535 bytes (CANDI_CHECK).
std::string EncodeLasVlr(const LasVlr& vlr);

// One Extra Bytes descriptor (LASF_Spec record 4), reduced to what decoding needs.
struct LasExtraBytes {
  std::string name;
  int data_type = 0;    // 1-10: uchar, char, ushort, short, ulong, long, ulonglong, longlong,
                        // float, double; 0 and 11-30 (undocumented bytes, arrays) are not decoded
  int size = 0;         // bytes in the record
  int offset = 0;       // byte offset in the record
  bool scaled = false;  // value = raw * scale + add (options bits 3/4)
  double scale = 1.0, add = 0.0;
};
bool IsLasExtraBytesVlr(const LasVlr& vlr);
// Parses the 192-byte descriptors; offsets are assigned from first_offset on (the standard
// record size), in order.
std::vector<LasExtraBytes> ParseLasExtraBytes(const std::string& data, int first_offset);
// Descriptors (float/double, no scale) for the Extra Bytes VLR payload.
std::string EncodeLasExtraBytes(const std::vector<LasExtraBytes>& fields);

}  // namespace candi::io
