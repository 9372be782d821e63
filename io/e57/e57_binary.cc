// E57 CompressedVector sections: data packets and the bitPackCodec, reading and writing.
//
// bitPackCodec (ASTM E2807 section 9): a field's values form one bytestream that continues from
// packet to packet. Float fields store IEEE values (4 or 8 bytes, little-endian); Integer and
// ScaledInteger fields store value - minimum in ceil(log2(maximum - minimum + 1)) bits, packed
// least significant bit first, so a value may straddle bytes and packets.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/check.h"
#include "io/e57/e57_format.h"

namespace candi::io::e57 {

namespace {

constexpr size_t kPad = 16;  // zero bytes after a queue's data: unaligned 64-bit loads stay inside

// Word size libE57Format packs a field in: packets carry whole words except the last.
size_t WordBytes(const FieldDesc& f) {
  if (f.kind == FieldKind::kFloat) return 4;
  if (f.kind == FieldKind::kDouble) return 8;
  return f.bits <= 8 ? 1 : f.bits <= 16 ? 2 : f.bits <= 32 ? 4 : 8;
}

std::string KindName(FieldKind k) {
  switch (k) {
    case FieldKind::kInteger: return "Integer";
    case FieldKind::kScaledInteger: return "ScaledInteger";
    case FieldKind::kFloat: return "Float single";
    case FieldKind::kDouble: return "Float double";
  }
  return "?";
}

}  // namespace

// ---- SectionReader ----

uint64_t SectionReader::Queue::Available(int bits) const {
  return bits == 0 ? UINT64_MAX : (uint64_t{size} * 8 - bit) / static_cast<uint64_t>(bits);
}

void SectionReader::Queue::Append(const uint8_t* data, size_t n) {
  bytes.resize(size + n + kPad);
  std::memcpy(bytes.data() + size, data, n);
  size += n;
  std::memset(bytes.data() + size, 0, kPad);
}

void SectionReader::Queue::Compact() {
  const size_t consumed = static_cast<size_t>(bit / 8);
  if (consumed < (1 << 16) || consumed * 2 < size) return;
  std::memmove(bytes.data(), bytes.data() + consumed, size - consumed + kPad);
  size -= consumed;
  bit -= uint64_t{consumed} * 8;
  bytes.resize(size + kPad);
}

SectionReader::SectionReader(PagedReader* file, const ScanDesc& scan, std::vector<bool> wanted,
                             size_t max_queued_bytes)
    : file_(file), scan_(scan), wanted_(std::move(wanted)), max_queued_(max_queued_bytes),
      queues_(scan.fields.size()), records_left_(scan.record_count) {
  CANDI_CHECK_EQ(wanted_.size(), scan.fields.size());
  for (Queue& q : queues_) q.bytes.assign(kPad, 0);
  const std::string where = scan.element + "/points @fileOffset";
  const uint64_t at = scan.section_offset;
  if (!IsDataByte(at) || at >= file->header().physical_length) {
    throw InputError(file->path(), ByteAt(at),
                     "CompressedVector section of " + where + " lies outside the file's data");
  }
  const uint64_t start = LogicalOf(at);
  const uint8_t* h = file->Fetch(start, kSectionHeaderSize, "CompressedVector section header");
  const uint64_t length = LoadLE<uint64_t>(h + 8), data = LoadLE<uint64_t>(h + 16);
  if (h[0] != 1) {
    throw InputError(file->path(), ByteAt(at),
                     "expected a CompressedVector section (id 1) for " + where + ", found id " +
                         std::to_string(h[0]));
  }
  if (length < kSectionHeaderSize || length > file->logical_length() - start) {
    throw InputError(file->path(), ByteAt(at + 8),
                     "section length " + std::to_string(length) + " runs past the end of the file");
  }
  section_end_ = start + length;
  next_packet_ = LogicalOf(data);
  if (records_left_ > 0 && (!IsDataByte(data) || next_packet_ < start + kSectionHeaderSize ||
                            next_packet_ >= section_end_)) {
    throw InputError(file->path(), ByteAt(at + 16),
                     "data offset " + std::to_string(data) + " lies outside its section");
  }
}

void SectionReader::ReadPacket() {
  const uint64_t at = PhysicalOf(next_packet_);
  if (next_packet_ + 4 > section_end_) {
    throw InputError(file_->path(), ByteAt(at),
                     scan_.element + ": section ends with " + std::to_string(records_left_) +
                         " of " + std::to_string(scan_.record_count) + " records still to read");
  }
  const uint8_t* p = file_->Fetch(next_packet_, 4, "packet header");
  const uint8_t type = p[0];
  const size_t length = size_t{LoadLE<uint16_t>(p + 2)} + 1;
  if (next_packet_ + length > section_end_) {
    throw InputError(file_->path(), ByteAt(at), "packet of " + std::to_string(length) +
                                                    " bytes runs past the end of its section");
  }
  if (type > 2) {
    throw InputError(file_->path(), ByteAt(at), "unknown packet type " + std::to_string(type));
  }
  p = file_->Fetch(next_packet_, length, "data packet");
  next_packet_ += length;
  if (type != 1) return;  // index (0) and empty (2) packets carry no records
  const size_t count = length >= 6 ? LoadLE<uint16_t>(p + 4) : 0;
  if (length < 6 || count != queues_.size() || 6 + 2 * count > length) {
    throw InputError(file_->path(), ByteAt(at),
                     "data packet has " + std::to_string(count) + " bytestreams; the prototype of " +
                         scan_.element + " has " + std::to_string(queues_.size()) + " fields");
  }
  size_t offset = 6 + 2 * count, queued = 0;
  for (size_t f = 0; f < count; ++f) {
    const size_t n = LoadLE<uint16_t>(p + 6 + 2 * f);
    if (offset + n > length) {
      throw InputError(file_->path(), ByteAt(at), "bytestream buffers (" +
                                                      std::to_string(offset + n) +
                                                      " bytes) overrun the packet");
    }
    if (wanted_[f]) {
      queues_[f].Compact();
      queues_[f].Append(p + offset, n);
    }
    offset += n;
    queued += queues_[f].size;
  }
  if (queued > max_queued_) {
    throw InputError(file_->path(), ByteAt(at),
                     "the bytestreams of " + scan_.element + " are too badly interleaved: " +
                         std::to_string(queued) + " bytes buffered (limit " +
                         std::to_string(max_queued_) + ")");
  }
}

size_t SectionReader::Next(size_t max_records, std::vector<std::vector<double>>* columns) {
  if (records_left_ == 0 || max_records == 0) return 0;
  uint64_t available = 0;
  for (;;) {
    available = records_left_;
    for (size_t f = 0; f < queues_.size(); ++f) {
      if (wanted_[f]) available = std::min(available, queues_[f].Available(scan_.fields[f].bits));
    }
    if (available > 0) break;
    ReadPacket();
  }
  const size_t n = static_cast<size_t>(std::min<uint64_t>(available, max_records));
  columns->resize(queues_.size());
  for (size_t f = 0; f < queues_.size(); ++f) {
    if (!wanted_[f]) continue;
    (*columns)[f].resize(n);
    Decode(f, n, (*columns)[f].data());
  }
  records_left_ -= n;
  return n;
}

void SectionReader::Decode(size_t f, size_t n, double* out) {
  const FieldDesc& d = scan_.fields[f];
  Queue& q = queues_[f];
  const int bits = d.bits;
  const uint8_t* base = q.bytes.data();
  if (d.kind == FieldKind::kFloat || d.kind == FieldKind::kDouble) {
    const uint8_t* p = base + q.bit / 8;  // float streams stay byte aligned
    if (d.kind == FieldKind::kFloat) {
      for (size_t i = 0; i < n; ++i) out[i] = LoadLE<float>(p + 4 * i);
    } else {
      std::memcpy(out, p, n * sizeof(double));
    }
    q.bit += uint64_t{n} * static_cast<uint64_t>(bits);
    return;
  }
  const double scale = d.kind == FieldKind::kScaledInteger ? d.scale : 1.0;
  const double offset = d.kind == FieldKind::kScaledInteger ? d.offset : 0.0;
  const uint64_t min = static_cast<uint64_t>(d.minimum);
  auto value = [&](uint64_t raw) {
    return static_cast<double>(static_cast<int64_t>(raw + min)) * scale + offset;
  };
  uint64_t bit = q.bit;
  if (bits == 8 && bit % 8 == 0) {  // colours: one byte a value
    const uint8_t* p = base + bit / 8;
    for (size_t i = 0; i < n; ++i) out[i] = value(p[i]);
  } else {
    const uint64_t mask = bits == 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
    for (size_t i = 0; i < n; ++i, bit += static_cast<uint64_t>(bits)) {
      const uint8_t* p = base + bit / 8;
      const unsigned shift = static_cast<unsigned>(bit % 8);
      uint64_t raw = LoadLE<uint64_t>(p) >> shift;
      if (shift + static_cast<unsigned>(bits) > 64) raw |= uint64_t{p[8]} << (64 - shift);
      out[i] = value(raw & mask);
    }
  }
  q.bit += uint64_t{n} * static_cast<uint64_t>(bits);
}

// ---- SectionWriter ----

void SectionWriter::Encoder::Put(uint64_t value, int bits) {
  if (acc_bits + bits > 64) {  // 0 < acc_bits < 8 here
    acc |= value << acc_bits;
    for (int k = 0; k < 8; ++k) bytes.push_back(static_cast<uint8_t>(acc >> (8 * k)));
    acc = value >> (64 - acc_bits);
    acc_bits += bits - 64;
  } else {
    if (acc_bits < 64) acc |= value << acc_bits;
    acc_bits += bits;
  }
  while (acc_bits >= 8) {
    bytes.push_back(static_cast<uint8_t>(acc));
    acc = acc_bits == 8 ? 0 : acc >> 8;
    acc_bits -= 8;
  }
}

SectionWriter::SectionWriter(PagedWriter* out, std::vector<FieldDesc> fields,
                             size_t packet_records)
    : out_(out), fields_(std::move(fields)), encoders_(fields_.size()) {
  CANDI_CHECK(!fields_.empty() && fields_.size() < 4096) << fields_.size() << " fields";
  size_t bits = 0, slack = 0;
  for (const FieldDesc& f : fields_) {
    bits += static_cast<size_t>(f.bits);
    slack += WordBytes(f) + 2;  // a partial word carried over, and the buffer length
  }
  const size_t room = kMaxPacketBytes - 16 - slack;  // header and padding
  CANDI_CHECK(room * 8 > bits) << "records of " << bits << " bits do not fit a packet";
  packet_records_ = bits == 0 ? (size_t{1} << 20) : room * 8 / bits;
  if (packet_records > 0) packet_records_ = std::min(packet_records_, packet_records);
  out_->PadTo4();
  start_ = out_->logical_position();
  out_->Hold(start_, kSectionHeaderSize);
  uint8_t header[kSectionHeaderSize] = {1};
  out_->Write(header, sizeof(header));
  first_packet_ = out_->logical_position();
}

void SectionWriter::Encode(size_t f, const double* values, size_t n) {
  const FieldDesc& d = fields_[f];
  Encoder& e = encoders_[f];
  if (d.kind == FieldKind::kFloat || d.kind == FieldKind::kDouble) {
    const size_t size = d.kind == FieldKind::kFloat ? 4 : 8;
    const size_t at = e.bytes.size();
    e.bytes.resize(at + n * size);
    uint8_t* p = e.bytes.data() + at;
    for (size_t i = 0; i < n; ++i, p += size) {
      if (size == 4) StoreLE<float>(p, static_cast<float>(values[i]));
      else StoreLE<double>(p, values[i]);
    }
    return;
  }
  const bool scaled = d.kind == FieldKind::kScaledInteger;
  for (size_t i = 0; i < n; ++i) {
    const double v = scaled ? (values[i] - d.offset) / d.scale : values[i];
    const double r = std::nearbyint(v);
    if (!(r >= static_cast<double>(d.minimum) && r <= static_cast<double>(d.maximum))) {
      throw std::invalid_argument("E57 field " + d.name + " (" + KindName(d.kind) + " " +
                                  std::to_string(d.minimum) + ".." + std::to_string(d.maximum) +
                                  "): value " + std::to_string(values[i]) + " is out of range");
    }
    const int64_t raw = std::clamp(static_cast<int64_t>(r), d.minimum, d.maximum);
    if (d.bits > 0) e.Put(static_cast<uint64_t>(raw) - static_cast<uint64_t>(d.minimum), d.bits);
  }
}

void SectionWriter::Append(const std::vector<const double*>& columns, size_t n) {
  CANDI_CHECK(!finished_) << "SectionWriter::Append after Finish";
  CANDI_CHECK_EQ(columns.size(), fields_.size());
  for (size_t done = 0; done < n;) {
    const size_t k = std::min(n - done, packet_records_ - pending_);
    for (size_t f = 0; f < fields_.size(); ++f) Encode(f, columns[f] + done, k);
    pending_ += k;
    done += k;
    records_ += k;
    if (pending_ == packet_records_) FlushPacket(false);
  }
}

void SectionWriter::FlushPacket(bool last) {
  const size_t count = fields_.size();
  std::vector<size_t> take(count);
  size_t total = 6 + 2 * count;
  for (size_t f = 0; f < count; ++f) {
    Encoder& e = encoders_[f];
    if (last && e.acc_bits > 0) {
      e.bytes.push_back(static_cast<uint8_t>(e.acc));
      e.acc = 0, e.acc_bits = 0;
    }
    const size_t word = WordBytes(fields_[f]);
    take[f] = last ? e.bytes.size() : e.bytes.size() / word * word;
    total += take[f];
  }
  pending_ = 0;
  if (total == 6 + 2 * count) return;  // nothing to say
  const size_t padded = (total + 3) / 4 * 4;
  CANDI_CHECK(padded <= kMaxPacketBytes) << "E57 packet of " << padded << " bytes";
  std::vector<uint8_t> packet(padded, 0);
  packet[0] = 1;
  StoreLE<uint16_t>(packet.data() + 2, static_cast<uint16_t>(padded - 1));
  StoreLE<uint16_t>(packet.data() + 4, static_cast<uint16_t>(count));
  size_t at = 6 + 2 * count;
  for (size_t f = 0; f < count; ++f) {
    StoreLE<uint16_t>(packet.data() + 6 + 2 * f, static_cast<uint16_t>(take[f]));
    std::vector<uint8_t>& bytes = encoders_[f].bytes;
    if (take[f] > 0) std::memcpy(packet.data() + at, bytes.data(), take[f]);
    bytes.erase(bytes.begin(), bytes.begin() + static_cast<ptrdiff_t>(take[f]));
    at += take[f];
  }
  out_->Write(packet.data(), packet.size());
}

void SectionWriter::Finish() {
  CANDI_CHECK(!finished_) << "SectionWriter::Finish twice";
  finished_ = true;
  FlushPacket(true);
  uint8_t header[kSectionHeaderSize] = {1};
  StoreLE<uint64_t>(header + 8, out_->logical_position() - start_);
  StoreLE<uint64_t>(header + 16, PhysicalOf(first_packet_));
  StoreLE<uint64_t>(header + 24, 0);  // no index packets
  out_->Patch(start_, header, sizeof(header));
}

}  // namespace candi::io::e57
