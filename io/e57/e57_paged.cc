// E57 physical layer: CRC-32C, paged reading and writing.
#include <algorithm>
#include <array>
#include <cstring>

#include "core/atomic_file.h"
#include "core/check.h"
#include "io/e57/e57_format.h"

#if defined(__x86_64__)
#include <nmmintrin.h>
#endif

namespace candi::io::e57 {

namespace {

constexpr size_t kWindowPages = 1024;  // 1 MiB read at a time

std::array<uint32_t, 256> MakeCrcTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;  // reflected 0x1EDC6F41
    table[i] = c;
  }
  return table;
}

uint32_t PageCrc(const uint8_t* page) { return Crc32c(page, kPageData); }

void StoreCrc(uint8_t* page) {
  const uint32_t crc = PageCrc(page);
  page[kPageData] = static_cast<uint8_t>(crc >> 24);  // big-endian, as libE57Format stores it
  page[kPageData + 1] = static_cast<uint8_t>(crc >> 16);
  page[kPageData + 2] = static_cast<uint8_t>(crc >> 8);
  page[kPageData + 3] = static_cast<uint8_t>(crc);
}

uint32_t StoredCrc(const uint8_t* page) {
  const uint8_t* p = page + kPageData;
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
}

std::string Hex(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "0x%08X", v);
  return buf;
}

std::string EncodeHeader(const FileHeader& h) {
  uint8_t b[kFileHeaderSize];
  std::memcpy(b, "ASTM-E57", 8);
  StoreLE<uint32_t>(b + 8, h.major);
  StoreLE<uint32_t>(b + 12, h.minor);
  StoreLE<uint64_t>(b + 16, h.physical_length);
  StoreLE<uint64_t>(b + 24, h.xml_physical_offset);
  StoreLE<uint64_t>(b + 32, h.xml_logical_length);
  StoreLE<uint64_t>(b + 40, h.page_size);
  return std::string(reinterpret_cast<char*>(b), sizeof(b));
}

}  // namespace

uint32_t Crc32cPortable(const void* data, size_t size) {
  static const std::array<uint32_t, 256> table = MakeCrcTable();
  const uint8_t* p = static_cast<const uint8_t*>(data);
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) crc = table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

#if defined(__x86_64__)
bool HasCrc32cInstruction() {
  static const bool has = __builtin_cpu_supports("sse4.2");
  return has;
}

__attribute__((target("sse4.2"))) uint32_t Crc32cHardware(const void* data, size_t size) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  uint64_t crc = 0xFFFFFFFFu;
  for (; size >= 8; size -= 8, p += 8) crc = _mm_crc32_u64(crc, LoadLE<uint64_t>(p));
  uint32_t c = static_cast<uint32_t>(crc);
  for (; size > 0; --size, ++p) c = _mm_crc32_u8(c, *p);
  return ~c;
}
#else
bool HasCrc32cInstruction() { return false; }
uint32_t Crc32cHardware(const void* data, size_t size) { return Crc32cPortable(data, size); }
#endif

uint32_t Crc32c(const void* data, size_t size) {
  return HasCrc32cInstruction() ? Crc32cHardware(data, size) : Crc32cPortable(data, size);
}

int BitsForRange(int64_t minimum, int64_t maximum) {
  const uint64_t range = static_cast<uint64_t>(maximum) - static_cast<uint64_t>(minimum);
  return range == 0 ? 0 : 64 - __builtin_clzll(range);
}

// ---- PagedReader ----

PagedReader::PagedReader(const std::string& path) : file_(path) {
  const std::string head = file_.Peek(kPageSize);
  if (head.size() < kFileHeaderSize || head.compare(0, 8, "ASTM-E57") != 0) {
    throw InputError(path, "byte 0", "not an E57 file (no \"ASTM-E57\" signature)");
  }
  const uint8_t* b = reinterpret_cast<const uint8_t*>(head.data());
  header_.major = LoadLE<uint32_t>(b + 8);
  header_.minor = LoadLE<uint32_t>(b + 12);
  header_.physical_length = LoadLE<uint64_t>(b + 16);
  header_.xml_physical_offset = LoadLE<uint64_t>(b + 24);
  header_.xml_logical_length = LoadLE<uint64_t>(b + 32);
  header_.page_size = LoadLE<uint64_t>(b + 40);
  if (header_.major != 1) {
    throw InputError(path, "byte 8", "E57 version " + std::to_string(header_.major) + "." +
                                         std::to_string(header_.minor) + " is not supported (1.x)");
  }
  if (header_.page_size != kPageSize) {
    throw InputError(path, "byte 40", "E57 page size " + std::to_string(header_.page_size) +
                                          " is not supported (must be 1024)");
  }
  if (header_.physical_length != file_.size() || file_.size() % kPageSize != 0) {
    throw InputError(path, "byte 16",
                     "E57 header says the file is " + std::to_string(header_.physical_length) +
                         " bytes but it is " + std::to_string(file_.size()) +
                         " (truncated, or not a whole number of 1024-byte pages)");
  }
  pages_ = file_.size() / kPageSize;
  const uint64_t xml = header_.xml_physical_offset;
  if (!IsDataByte(xml) || xml < kFileHeaderSize ||
      header_.xml_logical_length > logical_length() - std::min(logical_length(), LogicalOf(xml))) {
    throw InputError(path, "byte 24",
                     "E57 XML section (physical offset " + std::to_string(xml) + ", " +
                         std::to_string(header_.xml_logical_length) + " bytes) lies outside the file");
  }
  Fetch(0, kFileHeaderSize, "file header");  // checks page 0's CRC
}

void PagedReader::Load(uint64_t first_page) {
  const uint64_t pages = std::min<uint64_t>(kWindowPages, pages_ - first_page);
  raw_.resize(pages * kPageSize);
  const uint64_t at = first_page * kPageSize;
  if (file_.ReadAt(at, raw_.data(), raw_.size()) != raw_.size()) {
    throw InputError(path(), ByteAt(at), "unexpected end of file");
  }
  window_.resize(pages * kPageData);
  for (uint64_t i = 0; i < pages; ++i) {
    const uint8_t* page = raw_.data() + i * kPageSize;
    const uint32_t crc = PageCrc(page), stored = StoredCrc(page);
    if (crc != stored) {
      throw InputError(path(), ByteAt(at + i * kPageSize),
                       "E57 page CRC-32C mismatch (stored " + Hex(stored) + ", computed " +
                           Hex(crc) + "): the file is corrupt");
    }
    std::memcpy(window_.data() + i * kPageData, page, kPageData);
  }
  window_start_ = first_page * kPageData;
  window_end_ = window_start_ + window_.size();
}

const uint8_t* PagedReader::Fetch(uint64_t offset, size_t n, const char* what) {
  CANDI_CHECK(n <= (kWindowPages - 1) * kPageData) << "Fetch of " << n << " bytes";
  if (offset > logical_length() || n > logical_length() - offset) {
    throw InputError(path(), ByteAt(PhysicalOf(std::min(offset, logical_length()))),
                     std::string(what) + " (" + std::to_string(n) + " bytes) lies beyond the end of the file");
  }
  if (offset < window_start_ || offset + n > window_end_) Load(offset / kPageData);
  return window_.data() + (offset - window_start_);
}

std::string PagedReader::ReadXml() {
  std::string xml;
  uint64_t at = LogicalOf(header_.xml_physical_offset);
  uint64_t left = header_.xml_logical_length;
  if (left > (uint64_t{1} << 31)) {
    throw InputError(path(), "byte 32", "E57 XML section of " + std::to_string(left) +
                                            " bytes is too large (limit 2 GiB)");
  }
  xml.reserve(left);
  while (left > 0) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(left, 512 * kPageData));
    xml.append(reinterpret_cast<const char*>(Fetch(at, n, "XML section")), n);
    at += n;
    left -= n;
  }
  return xml;
}

// ---- PagedWriter ----

PagedWriter::PagedWriter(const std::string& path) : file_(std::make_unique<AtomicFile>(path)) {
  Hold(0, kFileHeaderSize);
  const std::string placeholder(kFileHeaderSize, '\0');
  Write(placeholder.data(), placeholder.size());
}

PagedWriter::~PagedWriter() = default;

void PagedWriter::FlushPage() {
  auto held = held_.find(page_index_);
  if (held != held_.end()) held->second.assign(page_, page_ + kPageData);
  StoreCrc(page_);
  file_->Write(page_, kPageSize);
  ++page_index_;
  fill_ = 0;
  std::memset(page_, 0, sizeof(page_));
}

void PagedWriter::Write(const void* data, size_t size) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  while (size > 0) {
    const size_t n = std::min<size_t>(size, kPageData - fill_);
    std::memcpy(page_ + fill_, p, n);
    fill_ += n;
    p += n;
    size -= n;
    if (fill_ == kPageData) FlushPage();
  }
}

void PagedWriter::PadTo4() {
  static const uint8_t zeros[4] = {};
  const size_t pad = (4 - logical_position() % 4) % 4;
  Write(zeros, pad);
}

void PagedWriter::Hold(uint64_t offset, size_t size) {
  for (uint64_t page = offset / kPageData; page <= (offset + size - 1) / kPageData; ++page) {
    CANDI_CHECK(page >= page_index_) << "Hold of a page already written";
    held_.emplace(page, std::vector<uint8_t>(kPageData, 0));
  }
}

void PagedWriter::Patch(uint64_t offset, const void* data, size_t size) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < size; ++i) {
    const uint64_t page = (offset + i) / kPageData, within = (offset + i) % kPageData;
    if (page == page_index_) {
      page_[within] = p[i];
    } else {
      auto held = held_.find(page);
      CANDI_CHECK(held != held_.end()) << "Patch of page " << page << ", which is not held";
      held->second[within] = p[i];
    }
  }
}

void PagedWriter::Finish(const std::string& xml) {
  PadTo4();
  FileHeader header;
  header.xml_physical_offset = PhysicalOf(logical_position());
  header.xml_logical_length = xml.size();
  Write(xml.data(), xml.size());
  if (fill_ > 0) FlushPage();
  header.physical_length = page_index_ * kPageSize;
  const std::string encoded = EncodeHeader(header);
  Patch(0, encoded.data(), encoded.size());
  for (const auto& [page, data] : held_) {
    uint8_t full[kPageSize];
    std::memcpy(full, data.data(), kPageData);
    StoreCrc(full);
    file_->WriteAt(page * kPageSize, full, kPageSize);
  }
  file_->Commit();
}

}  // namespace candi::io::e57
