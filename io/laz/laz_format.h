// LASzip's description of a compressed LAS file (the "laszip encoded" VLR, user id "laszip
// encoded", record 22204) and the per-chunk decoders of its two compressors.
//
// A LAZ file is a LAS file whose point data holds compressed chunks: the point-format byte has
// bit 7 set, and the VLR lists the items each record is made of (POINT10, GPSTIME11, RGB12,
// BYTE for formats 0-3; POINT14, RGB14, RGBNIR14, BYTE14 for 6-8) with their versions. Chunk
// decoders turn one chunk's bytes into the raw LAS records (record_length = sum of item sizes,
// the layout the LAS reader decodes), so everything above the chunk is shared with plain LAS.
//
// Failure: a malformed VLR, an unsupported compressor/item/version or a corrupt chunk throws
// laz::LazError (io/laz/laz_arith.h) with a message naming the item; the reader adds the file and
// the byte offset. Thread-safety: the functions are pure; chunks decode in parallel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/laz/laz_arith.h"

namespace candi::io::laz {

enum ItemType : uint16_t {
  kByte = 0,
  kPoint10 = 6,
  kGpsTime11 = 7,
  kRgb12 = 8,
  kWavepacket13 = 9,
  kPoint14 = 10,
  kRgb14 = 11,
  kRgbNir14 = 12,
  kWavepacket14 = 13,
  kByte14 = 14,
};
std::string ItemTypeName(uint16_t type);  // "POINT10", ..., "item type 42"

struct Item {
  uint16_t type = 0;
  uint16_t size = 0;     // bytes of the record this item fills
  uint16_t version = 0;  // 2 for pointwise items, 3 for layered ones
};

enum Compressor : uint16_t {
  kNone = 0,
  kPointwise = 1,         // not chunked (LASzip 1.x); not supported
  kPointwiseChunked = 2,  // formats 0-5, items of version 1 or 2
  kLayeredChunked = 3,    // formats 6-10, items of version 3 (or 4)
};

constexpr uint32_t kVariableChunkSize = 0xFFFFFFFFu;

struct Vlr {
  uint16_t compressor = 0;
  uint16_t coder = 0;  // 0: arithmetic
  uint8_t version_major = 0, version_minor = 0;
  uint16_t revision = 0;
  uint32_t options = 0;
  uint32_t chunk_size = 0;  // points a chunk; kVariableChunkSize: the chunk table gives counts
  int64_t special_evlr_count = -1, special_evlr_offset = -1;
  std::vector<Item> items;
  int record_length() const;  // sum of the item sizes
};

// Parses the VLR payload (34 + 6 * items bytes); throws LazError naming the field.
Vlr ParseVlr(const std::string& payload);
// The payload ParseVlr reads.
std::string EncodeVlr(const Vlr& vlr);
// The VLR LASzip 3.4r3 writes for LAS point format 0-3 or 6-8 with `extra_bytes` bytes after the
// standard fields: compressor 2 with items of version 2 (formats 0-3) or compressor 3 with items
// of version 3 (6-8), fixed chunks of `chunk_size` points. CANDI_CHECK on another format.
Vlr WriterVlr(int point_format, int extra_bytes, uint32_t chunk_size);
// Checks that candi decodes every item (types and versions above) and that the items match
// the LAS point format and record length; throws LazError naming the first that does not.
void CheckSupported(const Vlr& vlr, int point_format, int record_length);
// E.g. "LASzip 2.2r0, pointwise chunked compressor (v2), 50000-point chunks, items POINT10 v2,
// GPSTIME11 v2, RGB12 v2".
std::string Describe(const Vlr& vlr);

// Decodes one chunk of `points` records from [data, data + size) into `out` (points *
// vlr.record_length() bytes). Pointwise: the first record raw, then one arithmetic stream.
// Layered: the first record raw, the chunk's point count, per-item layer sizes, the layers; a
// stored count different from `points` is an error.
void DecodePointwiseChunk(const std::vector<Item>& items, const uint8_t* data, size_t size,
                          uint32_t points, uint8_t* out);
void DecodeLayeredChunk(const std::vector<Item>& items, const uint8_t* data, size_t size,
                        uint32_t points, uint8_t* out);

// The inverse of the decoders: appends the chunk of `points` records (vlr.record_length() bytes
// each, at `records`) to `out`, byte for byte as LASzip writes it. Nothing for 0 points. Throws
// LazError, as the decoders, for an item set candi does not code.
void EncodePointwiseChunk(const std::vector<Item>& items, const uint8_t* records, uint32_t points,
                          std::vector<uint8_t>* out);
void EncodeLayeredChunk(const std::vector<Item>& items, const uint8_t* records, uint32_t points,
                        std::vector<uint8_t>* out);

}  // namespace candi::io::laz
