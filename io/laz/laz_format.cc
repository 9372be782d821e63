#include "io/laz/laz_format.h"

#include <utility>

#include "core/check.h"

namespace candi::io::laz {

namespace {

uint16_t U16(const std::string& s, size_t at) {
  return static_cast<uint16_t>(static_cast<uint8_t>(s[at]) | static_cast<uint8_t>(s[at + 1]) << 8);
}
uint32_t U32(const std::string& s, size_t at) {
  return U16(s, at) | static_cast<uint32_t>(U16(s, at + 2)) << 16;
}
int64_t I64(const std::string& s, size_t at) {
  return static_cast<int64_t>(U32(s, at) | static_cast<uint64_t>(U32(s, at + 4)) << 32);
}

std::string CompressorName(uint16_t compressor) {
  switch (compressor) {
    case kNone: return "compressor 0 (none)";
    case kPointwise: return "compressor 1 (pointwise, not chunked; LASzip 1.x)";
    case kPointwiseChunked: return "pointwise chunked compressor (v2)";
    case kLayeredChunked: return "layered chunked compressor (v3)";
  }
  return "compressor " + std::to_string(compressor);
}

// The fixed size of an item type (0: any size, the extra bytes; -1: unknown or unsupported).
int ItemSize(uint16_t type) {
  switch (type) {
    case kPoint10: return 20;
    case kGpsTime11: return 8;
    case kRgb12: return 6;
    case kPoint14: return 30;
    case kRgb14: return 6;
    case kRgbNir14: return 8;
    case kByte:
    case kByte14: return 0;
  }
  return -1;
}

// The items LASzip writes for a point format, in record order, without the extra bytes.
std::vector<uint16_t> ExpectedItems(int point_format) {
  switch (point_format) {
    case 0: return {kPoint10};
    case 1: return {kPoint10, kGpsTime11};
    case 2: return {kPoint10, kRgb12};
    case 3: return {kPoint10, kGpsTime11, kRgb12};
    case 6: return {kPoint14};
    case 7: return {kPoint14, kRgb14};
    case 8: return {kPoint14, kRgbNir14};
  }
  return {};
}

// Throws for an item type or version candi does not decode with `compressor`.
void CheckItem(const Item& item, uint16_t compressor) {
  const std::string name = ItemTypeName(item.type);
  if (item.type == kWavepacket13 || item.type == kWavepacket14) {
    throw LazError("item " + name + " (waveform data) is not supported");
  }
  if (ItemSize(item.type) < 0) throw LazError("unknown " + name);
  const bool layered = item.type >= kPoint14;
  const uint16_t wanted = layered ? 3 : 2;
  if (layered != (compressor == kLayeredChunked)) {
    throw LazError("item " + name + " does not belong to the " + CompressorName(compressor));
  }
  if (item.version != wanted) {
    throw LazError("item " + name + " version " + std::to_string(item.version) +
                   (item.version == 1 ? " (LASzip 1.x)" : "") +
                   " is not supported; candi decodes version " + std::to_string(wanted));
  }
  const int size = ItemSize(item.type);
  if ((size > 0 && item.size != size) || item.size == 0) {
    throw LazError("item " + name + " has size " + std::to_string(item.size) +
                   (size > 0 ? "; it must be " + std::to_string(size) : "; it must be > 0"));
  }
}

}  // namespace

std::string ItemTypeName(uint16_t type) {
  switch (type) {
    case kByte: return "BYTE";
    case kPoint10: return "POINT10";
    case kGpsTime11: return "GPSTIME11";
    case kRgb12: return "RGB12";
    case kWavepacket13: return "WAVEPACKET13";
    case kPoint14: return "POINT14";
    case kRgb14: return "RGB14";
    case kRgbNir14: return "RGBNIR14";
    case kWavepacket14: return "WAVEPACKET14";
    case kByte14: return "BYTE14";
  }
  return "item type " + std::to_string(type);
}

int Vlr::record_length() const {
  int sum = 0;
  for (const Item& item : items) sum += item.size;
  return sum;
}

Vlr ParseVlr(const std::string& payload) {
  if (payload.size() < 34) {
    throw LazError("laszip VLR has " + std::to_string(payload.size()) +
                   " bytes; it needs at least 34");
  }
  Vlr vlr;
  vlr.compressor = U16(payload, 0);
  vlr.coder = U16(payload, 2);
  vlr.version_major = static_cast<uint8_t>(payload[4]);
  vlr.version_minor = static_cast<uint8_t>(payload[5]);
  vlr.revision = U16(payload, 6);
  vlr.options = U32(payload, 8);
  vlr.chunk_size = U32(payload, 12);
  vlr.special_evlr_count = I64(payload, 16);
  vlr.special_evlr_offset = I64(payload, 24);
  const size_t count = U16(payload, 32);
  if (payload.size() < 34 + 6 * count) {
    throw LazError("laszip VLR lists " + std::to_string(count) + " items (" +
                   std::to_string(34 + 6 * count) + " bytes) but has " +
                   std::to_string(payload.size()) + " bytes");
  }
  for (size_t i = 0; i < count; ++i) {
    const size_t at = 34 + 6 * i;
    vlr.items.push_back({U16(payload, at), U16(payload, at + 2), U16(payload, at + 4)});
  }
  return vlr;
}

std::string EncodeVlr(const Vlr& vlr) {
  std::string s;
  auto put = [&](uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) s.push_back(static_cast<char>(v >> (8 * i)));
  };
  // (value, bytes) in ParseVlr's order.
  const std::pair<uint64_t, int> fields[] = {
      {vlr.compressor, 2}, {vlr.coder, 2}, {vlr.version_major, 1}, {vlr.version_minor, 1},
      {vlr.revision, 2}, {vlr.options, 4}, {vlr.chunk_size, 4},
      {static_cast<uint64_t>(vlr.special_evlr_count), 8},
      {static_cast<uint64_t>(vlr.special_evlr_offset), 8}, {vlr.items.size(), 2}};
  for (const auto& [value, bytes] : fields) put(value, bytes);
  for (const Item& item : vlr.items) {
    put(item.type, 2);
    put(item.size, 2);
    put(item.version, 2);
  }
  return s;
}

Vlr WriterVlr(int point_format, int extra_bytes, uint32_t chunk_size) {
  const std::vector<uint16_t> types = ExpectedItems(point_format);
  CANDI_CHECK(!types.empty() && extra_bytes >= 0 && extra_bytes <= 65535 && chunk_size > 0)
      << "no LAZ items for point format " << point_format << " with " << extra_bytes
      << " extra bytes and chunks of " << chunk_size;
  const bool layered = point_format >= 6;
  Vlr vlr;
  vlr.compressor = layered ? kLayeredChunked : kPointwiseChunked;
  vlr.version_major = 3;
  vlr.version_minor = 4;
  vlr.revision = 3;
  vlr.chunk_size = chunk_size;
  const uint16_t version = layered ? 3 : 2;
  for (uint16_t type : types) {
    vlr.items.push_back({type, static_cast<uint16_t>(ItemSize(type)), version});
  }
  if (extra_bytes > 0) {
    const uint16_t type = layered ? kByte14 : kByte;
    vlr.items.push_back({type, static_cast<uint16_t>(extra_bytes), version});
  }
  return vlr;
}

void CheckSupported(const Vlr& vlr, int point_format, int record_length) {
  if (vlr.compressor != kPointwiseChunked && vlr.compressor != kLayeredChunked) {
    throw LazError(CompressorName(vlr.compressor) +
                   " is not supported; candi decodes the chunked compressors 2 and 3");
  }
  if (vlr.coder != 0) {
    throw LazError("coder " + std::to_string(vlr.coder) +
                   " is not supported; candi decodes the arithmetic coder (0)");
  }
  if (vlr.chunk_size == 0) throw LazError("laszip VLR states a chunk size of 0 points");
  for (const Item& item : vlr.items) CheckItem(item, vlr.compressor);
  const std::vector<uint16_t> expected = ExpectedItems(point_format);
  if (expected.empty()) {
    throw LazError("point format " + std::to_string(point_format) + " is not supported in LAZ");
  }
  const bool layered_format = point_format >= 6;
  if (layered_format != (vlr.compressor == kLayeredChunked)) {
    throw LazError("point format " + std::to_string(point_format) + " does not go with the " +
                   CompressorName(vlr.compressor));
  }
  const uint16_t byte_type = layered_format ? kByte14 : kByte;
  const size_t n = vlr.items.size();
  const bool order_ok = n >= expected.size() && n <= expected.size() + 1 &&
                        (n == expected.size() || vlr.items.back().type == byte_type);
  bool match = order_ok;
  for (size_t i = 0; match && i < expected.size(); ++i) match = vlr.items[i].type == expected[i];
  if (!match) {
    std::string listed;
    for (const Item& item : vlr.items) {
      listed += (listed.empty() ? "" : ", ") + ItemTypeName(item.type);
    }
    throw LazError("items " + listed + " do not match point format " +
                   std::to_string(point_format));
  }
  if (vlr.record_length() != record_length) {
    throw LazError("items fill " + std::to_string(vlr.record_length()) +
                   " bytes a point but the LAS record length is " +
                   std::to_string(record_length));
  }
}

std::string Describe(const Vlr& vlr) {
  std::string s = "LASzip " + std::to_string(vlr.version_major) + "." +
                  std::to_string(vlr.version_minor) + "r" + std::to_string(vlr.revision) + ", " +
                  CompressorName(vlr.compressor) + ", " +
                  (vlr.chunk_size == kVariableChunkSize
                       ? std::string("variable-size chunks")
                       : std::to_string(vlr.chunk_size) + "-point chunks") +
                  ", items";
  for (size_t i = 0; i < vlr.items.size(); ++i) {
    const Item& item = vlr.items[i];
    s += (i == 0 ? " " : ", ") + ItemTypeName(item.type) + " v" + std::to_string(item.version);
    if (item.type == kByte || item.type == kByte14) s += " (" + std::to_string(item.size) + " bytes)";
  }
  return s;
}

}  // namespace candi::io::laz
