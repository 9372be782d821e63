// E57 (ASTM E2807) internals shared by the E57 reader, writer and their tests: CRC-32C, the paged
// physical layer, the parsed XML description of the scans and the CompressedVector codec
// (bitPackCodec). Not part of the public point-I/O API: use io/e57/e57_io.h and io/e57/e57_writer.h.
//
// Physical layer: the file is a sequence of 1024-byte pages, each 1020 bytes of data followed by
// the CRC-32C (Castagnoli) of those bytes, stored big-endian (as libE57Format writes it).
// "Logical" offsets count data bytes only; "physical" offsets count file bytes. All offsets stored
// in the file (XML offset, section and packet offsets) are physical. Errors name physical bytes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/binary_file.h"

namespace candi {
class AtomicFile;
}  // namespace candi

namespace candi::io {

namespace e57 {

constexpr uint64_t kPageSize = 1024;
constexpr uint64_t kPageData = 1020;
constexpr size_t kFileHeaderSize = 48;
constexpr size_t kSectionHeaderSize = 32;
constexpr size_t kMaxPacketBytes = 65536;

// CRC-32C of `size` bytes (initial value and final xor 0xFFFFFFFF; "123456789" -> 0xE3069283).
uint32_t Crc32c(const void* data, size_t size);          // hardware when available
uint32_t Crc32cPortable(const void* data, size_t size);  // table, any CPU
bool HasCrc32cInstruction();                               // SSE4.2 crc32 on this CPU
uint32_t Crc32cHardware(const void* data, size_t size);   // only when HasCrc32cInstruction()

inline bool IsDataByte(uint64_t physical) { return physical % kPageSize < kPageData; }
inline uint64_t LogicalOf(uint64_t physical) {
  return physical / kPageSize * kPageData + physical % kPageSize;
}
inline uint64_t PhysicalOf(uint64_t logical) {
  return logical / kPageData * kPageSize + logical % kPageData;
}
inline std::string ByteAt(uint64_t physical) { return "byte " + std::to_string(physical); }

struct FileHeader {  // the first 48 bytes of the file
  uint32_t major = 1, minor = 0;
  uint64_t physical_length = 0;      // bytes of the file
  uint64_t xml_physical_offset = 0;  // where the XML section starts
  uint64_t xml_logical_length = 0;   // its length in data bytes
  uint64_t page_size = kPageSize;
};

// Reads logical bytes of an E57 file; verifies the CRC-32C of every page it loads. Throws
// InputError naming the path and physical byte. Not thread-safe.
class PagedReader {
 public:
  // Reads and validates the header (signature, version 1, page size 1024, lengths).
  explicit PagedReader(const std::string& path);
  const std::string& path() const { return file_.path(); }
  const FileHeader& header() const { return header_; }
  uint64_t logical_length() const { return pages_ * kPageData; }
  // n (<= 1 MiB) contiguous logical bytes at `offset`, valid until the next call; InputError
  // naming `what` when they lie beyond the file.
  const uint8_t* Fetch(uint64_t offset, size_t n, const char* what);
  std::string ReadXml();

 private:
  void Load(uint64_t first_page);

  BinaryFile file_;
  FileHeader header_;
  uint64_t pages_ = 0;
  std::vector<uint8_t> raw_, window_;
  uint64_t window_start_ = 0, window_end_ = 0;  // logical range held in window_
};

// Writes an E57 file page by page (CRC-32C appended to each) through an AtomicFile. Bytes
// already written can be patched only in held pages (page 0 is always held for the header).
class PagedWriter {
 public:
  explicit PagedWriter(const std::string& path);
  ~PagedWriter();
  uint64_t logical_position() const { return page_index_ * kPageData + fill_; }
  void Write(const void* data, size_t size);
  void PadTo4();  // zero bytes up to a multiple of 4 (logical)
  // Keeps copies of the pages holding [offset, offset + size) so Patch can change them later.
  void Hold(uint64_t offset, size_t size);
  void Patch(uint64_t offset, const void* data, size_t size);
  // Writes the XML, fills the last page, writes the header and renames the file into place.
  void Finish(const std::string& xml);

 private:
  void FlushPage();

  std::unique_ptr<AtomicFile> file_;
  uint8_t page_[kPageSize] = {};
  size_t fill_ = 0;
  uint64_t page_index_ = 0;
  std::map<uint64_t, std::vector<uint8_t>> held_;  // page index -> its 1020 data bytes
};

// ---- XML description ----

enum class FieldKind { kInteger, kScaledInteger, kFloat, kDouble };

struct FieldDesc {
  std::string name;  // element name, "/"-joined for nested prototype structures
  FieldKind kind = FieldKind::kDouble;
  int64_t minimum = INT64_MIN, maximum = INT64_MAX;  // Integer, ScaledInteger (raw)
  double scale = 1.0, offset = 0.0;                  // ScaledInteger
  int bits = 64;  // bits a value in the bytestream (0 when minimum == maximum)
};

struct ScanDesc {
  std::string element;  // "/data3D/<i>", for messages
  int line = 0;         // XML line of the scan's element
  std::string guid, name, description;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // scan to file frame
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  uint64_t section_offset = 0;  // physical offset of the CompressedVector section
  uint64_t record_count = 0;
  std::vector<FieldDesc> fields;  // prototype leaves, bytestream order
  std::optional<Eigen::Vector2d> intensity_limits;
  std::optional<Eigen::Vector2d> color_limits[3];  // red, green, blue: minimum, maximum
  int FieldIndex(const std::string& name) const;  // -1 when absent
};

struct FileDesc {
  int major = 1, minor = 0;
  std::string guid, library, coordinate_metadata;
  std::vector<ScanDesc> scans;
  size_t images = 0;  // images2D children (not read)
};

// Parses the XML section. Throws InputError(path, "XML line N[, <element>]", ...) for parse
// errors, missing or malformed elements, unsupported codecs, bad prototypes and record counts
// that the file (physical_length bytes) cannot hold.
FileDesc ParseE57Xml(const std::string& path, const std::string& xml, uint64_t physical_length);

// ---- CompressedVector sections ----

// Streams the records of one scan's CompressedVector section with bounded memory: packets are
// read in order, each field's bytes queued until every wanted field can give values.
class SectionReader {
 public:
  SectionReader(PagedReader* file, const ScanDesc& scan, std::vector<bool> wanted,
                size_t max_queued_bytes);
  // Decodes the next records (at most max_records) of every wanted field into (*columns)[f], as
  // doubles (Integer: the value; ScaledInteger: raw * scale + offset). Returns how many; 0 when
  // the scan is complete. Throws InputError when the section ends early or is malformed.
  size_t Next(size_t max_records, std::vector<std::vector<double>>* columns);
  uint64_t records_left() const { return records_left_; }

 private:
  struct Queue {
    std::vector<uint8_t> bytes;  // followed by 16 zero bytes (for unaligned 64-bit loads)
    size_t size = 0;             // valid bytes
    uint64_t bit = 0;            // next bit to read
    uint64_t Available(int bits) const;
    void Append(const uint8_t* data, size_t n);
    void Compact();
  };
  void ReadPacket();
  void Decode(size_t f, size_t n, double* out);

  PagedReader* file_;
  const ScanDesc& scan_;
  std::vector<bool> wanted_;
  size_t max_queued_;
  std::vector<Queue> queues_;
  uint64_t next_packet_ = 0, section_end_ = 0;  // logical
  uint64_t records_left_ = 0;
};

// Encodes records into data packets of a CompressedVector section (bitPackCodec).
class SectionWriter {
 public:
  // Writes the section header at out's position (4-byte aligned). packet_records > 0 caps the
  // records a packet (tests use it to force many packets); 0 fills packets up to 64 KiB.
  SectionWriter(PagedWriter* out, std::vector<FieldDesc> fields, size_t packet_records = 0);
  // Appends n records: columns[f] holds n values of field f (Integer: rounded; ScaledInteger:
  // (value - offset) / scale rounded). Throws std::invalid_argument for values outside a
  // field's minimum..maximum.
  void Append(const std::vector<const double*>& columns, size_t n);
  // Writes the last packet and completes the section header.
  void Finish();
  uint64_t section_physical_offset() const { return PhysicalOf(start_); }
  uint64_t records() const { return records_; }
  const std::vector<FieldDesc>& fields() const { return fields_; }

 private:
  struct Encoder {
    std::vector<uint8_t> bytes;
    uint64_t acc = 0;
    int acc_bits = 0;
    void Put(uint64_t value, int bits);
  };
  void Encode(size_t f, const double* values, size_t n);
  void FlushPacket(bool last);

  PagedWriter* out_;
  std::vector<FieldDesc> fields_;
  std::vector<Encoder> encoders_;
  size_t packet_records_ = 1;
  size_t pending_ = 0;  // records encoded but not yet in a packet
  uint64_t start_ = 0, first_packet_ = 0, records_ = 0;
  bool finished_ = false;
};

// Bits a bitPackCodec value takes for the integer range [minimum, maximum]: ceil(log2(range+1)).
int BitsForRange(int64_t minimum, int64_t maximum);

}  // namespace e57
}  // namespace candi::io
