// The point data of a LAZ file: its chunk table, and the decoding of runs of chunks into raw LAS
// point records (LASzip's layout: an int64 at the start of the point data gives the table's file
// offset, or -1 when LASzip wrote that offset in the last 8 bytes of the file; the chunks follow
// the int64; the table is u32 version 0, u32 chunk count, then the chunk byte sizes, and the
// point counts first when the chunk size is variable, each coded with an IntegerCoder(32,
// 2) against the previous one on one arithmetic stream).
//
// Internal to the LAS reader (io/las/las_reader.cc). Memory is bounded: the table (a few words a
// chunk, at most one chunk per record_length bytes of file) and one run of chunks, at most ~64 MiB
// of decoded records or one chunk; a single chunk may decode to at most 1 GiB.
//
// Failure: an absent, truncated or inconsistent chunk table (against the file size, the header's
// point count and the VLR's chunk size) throws InputError("<path>: byte <pos>: LAZ chunk table:
// ..."); a corrupt chunk throws InputError("<path>: byte <chunk offset>: LAZ chunk k of n: ...").
// Thread-safety: one object per reader; it decodes the chunks of a run in parallel (ParallelFor),
// with results independent of the thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/binary_file.h"
#include "io/laz/laz_format.h"

namespace candi::io {

struct LazChunk {
  uint64_t offset = 0;       // file offset of the chunk's first byte
  uint64_t bytes = 0;        // compressed size
  uint64_t first_point = 0;  // index of its first point in the file
  uint32_t points = 0;
};

// Reads and checks the chunk table. `count`: the header's point count (0: no table needed).
std::vector<LazChunk> ReadLazChunkTable(const BinaryFile& file, const laz::Vlr& vlr,
                                        uint64_t point_data_offset, uint64_t count,
                                        size_t record_length);

class LazPointData {
 public:
  // `file` must outlive this object.
  LazPointData(const BinaryFile* file, laz::Vlr vlr, std::vector<LazChunk> chunks,
               size_t record_length);
  // The decoded records of points [point, point + *available) (*available >= 1), for point <
  // the file's count. Decodes, when they are not at hand, the run of chunks from the one holding
  // `point` towards the one holding want_end - 1 (want_end > point).
  const uint8_t* Records(uint64_t point, uint64_t want_end, size_t* available);
  size_t chunk_count() const { return chunks_.size(); }

 private:
  size_t ChunkOf(uint64_t point) const;
  void DecodeRun(size_t first, size_t count);

  const BinaryFile* file_;
  laz::Vlr vlr_;
  std::vector<LazChunk> chunks_;
  size_t record_length_;
  std::vector<uint8_t> compressed_, decoded_;
  uint64_t decoded_first_ = 0, decoded_end_ = 0;  // points held in decoded_
};

// Compresses LAS point records into LAZ chunks of vlr.chunk_size points (the last one shorter)
// and hands the chunks, in order, to `sink`. The chunks of a batch (kBatchChunks chunks) are
// compressed in parallel (ParallelFor); chunk boundaries depend only on the point index, so the
// bytes are the same for any thread count. Memory: one batch of records and of chunks.
// Thread-safety: one object per file.
class LazChunkWriter {
 public:
  using Sink = std::function<void(const uint8_t* data, size_t size)>;
  static constexpr size_t kBatchChunks = 8;

  // CANDI_CHECK unless vlr has fixed chunks and record_length == vlr.record_length().
  LazChunkWriter(laz::Vlr vlr, size_t record_length, Sink sink);
  // Adds n records (record_length bytes each).
  void Add(const uint8_t* records, size_t n);
  // Compresses the records left and returns the chunk table (LASzip's layout, see above).
  std::vector<uint8_t> Finish();

 private:
  void CompressBatch(size_t points);

  laz::Vlr vlr_;
  size_t record_length_;
  Sink sink_;
  std::vector<uint8_t> pending_;  // records not yet compressed, less than a batch
  std::vector<std::vector<uint8_t>> chunks_;
  std::vector<uint32_t> chunk_bytes_;
};

// The chunk table for chunks of the given byte sizes: u32 version 0, u32 count, then the sizes
// coded on one arithmetic stream (the inverse of the reader's decoding). Variable-size chunks
// (COPC): chunk_points gives each chunk's point count, coded before its size.
std::vector<uint8_t> EncodeLazChunkTable(const std::vector<uint32_t>& chunk_bytes,
                                         const std::vector<uint32_t>& chunk_points = {});

}  // namespace candi::io
