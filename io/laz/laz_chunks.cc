#include "io/laz/laz_chunks.h"


#include <algorithm>
#include <limits>
#include <utility>

#include "core/check.h"
#include "core/parallel.h"

namespace candi::io {

namespace {

constexpr uint64_t kMaxChunkDecodedBytes = uint64_t{1} << 30;
constexpr uint64_t kRunDecodedBytes = uint64_t{64} << 20;

std::string Byte(uint64_t at) { return "byte " + std::to_string(at); }

int64_t ReadI64At(const BinaryFile& file, uint64_t at, const std::string& what) {
  uint8_t b[8];
  if (at > file.size() || file.size() - at < 8 || file.ReadAt(at, b, 8) != 8) {
    throw InputError(file.path(), Byte(at), "file ends inside " + what);
  }
  return LoadLE<int64_t>(b);
}

// The table's file offset, from the int64 before the first chunk (or the file's last 8 bytes).
uint64_t ChunkTableOffset(const BinaryFile& file, uint64_t point_data_offset) {
  int64_t table = ReadI64At(file, point_data_offset, "the LAZ chunk table offset");
  if (table == -1 && file.size() >= 8) {
    table = ReadI64At(file, file.size() - 8, "the LAZ chunk table offset");
  }
  const uint64_t first_chunk = point_data_offset + 8;
  if (table < 0 || static_cast<uint64_t>(table) < first_chunk ||
      static_cast<uint64_t>(table) > file.size() - 8) {
    throw InputError(file.path(), Byte(point_data_offset),
                     "LAZ chunk table offset " + std::to_string(table) +
                         " lies outside the point data (bytes " + std::to_string(first_chunk) +
                         " to " + std::to_string(file.size()) +
                         "): the file is truncated or was written without a chunk table, which "
                         "candi needs to locate the chunks");
  }
  return static_cast<uint64_t>(table);
}

struct TableEntries {
  std::vector<uint32_t> bytes, points;  // points: variable chunk size only
};

// Decodes the entries: each value coded against the previous one of its kind (context 0 for
// point counts, 1 for byte sizes).
TableEntries DecodeTableEntries(const BinaryFile& file, uint64_t at, uint32_t chunks,
                                bool variable) {
  // A coded 32-bit value takes at most ~6 bytes; read no more than the table can need.
  const uint64_t wanted = 64 + uint64_t{12} * chunks;
  std::vector<uint8_t> data(static_cast<size_t>(std::min<uint64_t>(wanted, file.size() - at)));
  const size_t got = file.ReadAt(at, data.data(), data.size());
  laz::ArithmeticDecoder decoder;
  decoder.Init(data.data(), data.data() + got);
  laz::IntegerCoder ic(32, 2);
  ic.Init();
  TableEntries e;
  e.bytes.resize(chunks);
  if (variable) e.points.resize(chunks);
  for (uint32_t i = 0; i < chunks; ++i) {
    if (variable) e.points[i] = ic.Decompress(&decoder, i ? e.points[i - 1] : 0, 0);
    e.bytes[i] = ic.Decompress(&decoder, i ? e.bytes[i - 1] : 0, 1);
    if (decoder.overrun()) break;
  }
  if (decoder.overrun()) {
    throw InputError(file.path(), Byte(at),
                     "LAZ chunk table: the file ends inside the table of " +
                         std::to_string(chunks) + " chunks");
  }
  return e;
}

// Chunk offsets and point counts from the entries, each checked against the file and the header.
std::vector<LazChunk> BuildChunks(const BinaryFile& file, const laz::Vlr& vlr,
                                  const TableEntries& e, uint64_t first_chunk, uint64_t table,
                                  uint64_t count, size_t record_length) {
  const bool variable = vlr.chunk_size == laz::kVariableChunkSize;
  auto fail = [&](size_t i, const std::string& what) {
    throw InputError(file.path(), Byte(table),
                     "LAZ chunk table: chunk " + std::to_string(i) + " of " +
                         std::to_string(e.bytes.size()) + " " + what);
  };
  std::vector<LazChunk> chunks(e.bytes.size());
  uint64_t offset = first_chunk, point = 0;
  for (size_t i = 0; i < chunks.size(); ++i) {
    LazChunk& c = chunks[i];
    c.offset = offset;
    c.bytes = e.bytes[i];
    c.first_point = point;
    c.points = variable ? e.points[i]
                        : static_cast<uint32_t>(std::min<uint64_t>(vlr.chunk_size, count - point));
    if (c.points == 0 || c.points > count - point) {
      fail(i, "has " + std::to_string(c.points) + " points; the header promises " +
                  std::to_string(count) + " in all, " + std::to_string(point) + " before it");
    }
    if (c.bytes < record_length || c.bytes > table - offset) {
      fail(i, "has " + std::to_string(c.bytes) + " bytes at byte " + std::to_string(offset) +
                  "; it needs at least " + std::to_string(record_length) +
                  " and must end before the table");
    }
    if (uint64_t{c.points} * record_length > kMaxChunkDecodedBytes) {
      fail(i, "has " + std::to_string(c.points) + " points, more than candi decodes in a chunk (" +
                  std::to_string(kMaxChunkDecodedBytes / record_length) + ")");
    }
    offset += c.bytes;
    point += c.points;
  }
  if (point != count) {
    throw InputError(file.path(), Byte(table),
                     "LAZ chunk table: " + std::to_string(chunks.size()) + " chunks hold " +
                         std::to_string(point) + " points but the header promises " +
                         std::to_string(count));
  }
  return chunks;
}

}  // namespace

std::vector<LazChunk> ReadLazChunkTable(const BinaryFile& file, const laz::Vlr& vlr,
                                        uint64_t point_data_offset, uint64_t count,
                                        size_t record_length) {
  if (count == 0) return {};
  const uint64_t table = ChunkTableOffset(file, point_data_offset);
  const uint64_t first_chunk = point_data_offset + 8;
  const uint64_t head = static_cast<uint64_t>(ReadI64At(file, table, "the LAZ chunk table"));
  const uint32_t version = static_cast<uint32_t>(head);
  const uint32_t chunks = static_cast<uint32_t>(head >> 32);
  if (version != 0) {
    throw InputError(file.path(), Byte(table),
                     "LAZ chunk table version " + std::to_string(version) + " is unknown (0)");
  }
  const bool variable = vlr.chunk_size == laz::kVariableChunkSize;
  // Fixed-size chunks: exactly enough for the count; each chunk at least one record long.
  const uint64_t expected = variable ? chunks : (count - 1) / vlr.chunk_size + 1;
  const uint64_t room = (table - first_chunk) / record_length;
  if (chunks == 0 || chunks != expected || chunks > room || chunks > count) {
    throw InputError(
        file.path(), Byte(table),
        "LAZ chunk table lists " + std::to_string(chunks) + " chunks; the header promises " +
            std::to_string(count) + " points" +
            (variable ? std::string() : " in chunks of " + std::to_string(vlr.chunk_size) +
                                            " (" + std::to_string(expected) + " chunks)") +
            " and " + std::to_string(table - first_chunk) + " bytes hold at most " +
            std::to_string(room));
  }
  const TableEntries entries = DecodeTableEntries(file, table + 8, chunks, variable);
  return BuildChunks(file, vlr, entries, first_chunk, table, count, record_length);
}

LazPointData::LazPointData(const BinaryFile* file, laz::Vlr vlr, std::vector<LazChunk> chunks,
                           size_t record_length)
    : file_(file), vlr_(std::move(vlr)), chunks_(std::move(chunks)),
      record_length_(record_length) {}

size_t LazPointData::ChunkOf(uint64_t point) const {
  const auto it = std::upper_bound(
      chunks_.begin(), chunks_.end(), point,
      [](uint64_t p, const LazChunk& c) { return p < c.first_point; });
  CANDI_CHECK(it != chunks_.begin()) << "point " << point;
  return static_cast<size_t>(it - chunks_.begin()) - 1;
}

const uint8_t* LazPointData::Records(uint64_t point, uint64_t want_end, size_t* available) {
  CANDI_CHECK(!chunks_.empty() && point < want_end) << "LazPointData::Records(" << point << ")";
  if (point < decoded_first_ || point >= decoded_end_) {
    const size_t first = ChunkOf(point);
    const size_t last = ChunkOf(std::min(want_end, chunks_.back().first_point +
                                                       chunks_.back().points) - 1);
    // A run: as many chunks as the memory budget holds, whatever the thread count. A file that
    // fits in one run is decoded once even when the 8/16-bit colour scan went through all of it
    // before the first Read (a cap of a few chunks a thread made that scan decode it twice).
    size_t count = 1;
    uint64_t bytes = uint64_t{chunks_[first].points} * record_length_;
    while (first + count <= last) {
      const uint64_t more = uint64_t{chunks_[first + count].points} * record_length_;
      if (bytes + more > kRunDecodedBytes) break;
      bytes += more;
      ++count;
    }
    DecodeRun(first, count);
  }
  *available = static_cast<size_t>(decoded_end_ - point);
  return decoded_.data() + (point - decoded_first_) * record_length_;
}

// Reads the run's bytes in one go (the chunks are contiguous), then decodes its chunks in
// parallel. The first failing chunk (in file order) is reported, whatever the thread count.
void LazPointData::DecodeRun(size_t first, size_t count) {
  const LazChunk& a = chunks_[first];
  const LazChunk& b = chunks_[first + count - 1];
  decoded_first_ = decoded_end_ = 0;
  compressed_.resize(static_cast<size_t>(b.offset + b.bytes - a.offset));
  if (file_->ReadAt(a.offset, compressed_.data(), compressed_.size()) != compressed_.size()) {
    throw InputError(file_->path(), Byte(a.offset), "file ends inside the LAZ point data");
  }
  decoded_.resize(static_cast<size_t>((b.first_point + b.points - a.first_point) * record_length_));
  std::vector<std::string> errors(count);
  ParallelFor(size_t{0}, count, [&](size_t j) {
    const LazChunk& c = chunks_[first + j];
    const uint8_t* data = compressed_.data() + (c.offset - a.offset);
    uint8_t* out = decoded_.data() + (c.first_point - a.first_point) * record_length_;
    try {
      if (vlr_.compressor == laz::kLayeredChunked) {
        laz::DecodeLayeredChunk(vlr_.items, data, c.bytes, c.points, out);
      } else {
        laz::DecodePointwiseChunk(vlr_.items, data, c.bytes, c.points, out);
      }
    } catch (const laz::LazError& e) {
      errors[j] = e.what();
    }
  });
  for (size_t j = 0; j < count; ++j) {
    if (errors[j].empty()) continue;
    throw InputError(file_->path(), Byte(chunks_[first + j].offset),
                     "LAZ chunk " + std::to_string(first + j) + " of " +
                         std::to_string(chunks_.size()) + ": " + errors[j]);
  }
  decoded_first_ = a.first_point;
  decoded_end_ = b.first_point + b.points;
}

// ---- Writing ----

std::vector<uint8_t> EncodeLazChunkTable(const std::vector<uint32_t>& chunk_bytes,
                                         const std::vector<uint32_t>& chunk_points) {
  CANDI_CHECK(chunk_points.empty() || chunk_points.size() == chunk_bytes.size())
      << chunk_points.size() << " chunk point counts for " << chunk_bytes.size() << " chunks";
  std::vector<uint8_t> table(8, 0);
  StoreLE<uint32_t>(table.data() + 4, static_cast<uint32_t>(chunk_bytes.size()));
  if (chunk_bytes.empty()) return table;
  laz::ArithmeticEncoder encoder;
  laz::IntegerCoder ic(32, 2);
  ic.Init();
  for (size_t i = 0; i < chunk_bytes.size(); ++i) {
    if (!chunk_points.empty()) {
      ic.Compress(&encoder, static_cast<int32_t>(i ? chunk_points[i - 1] : 0),
                  static_cast<int32_t>(chunk_points[i]), 0);
    }
    ic.Compress(&encoder, static_cast<int32_t>(i ? chunk_bytes[i - 1] : 0),
                static_cast<int32_t>(chunk_bytes[i]), 1);
  }
  encoder.Done();
  table.insert(table.end(), encoder.data(), encoder.data() + encoder.size());
  return table;
}

LazChunkWriter::LazChunkWriter(laz::Vlr vlr, size_t record_length, Sink sink)
    : vlr_(std::move(vlr)), record_length_(record_length), sink_(std::move(sink)) {
  CANDI_CHECK(vlr_.chunk_size != laz::kVariableChunkSize && vlr_.chunk_size > 0)
      << "LazChunkWriter writes fixed-size chunks";
  CANDI_CHECK(record_length_ == static_cast<size_t>(vlr_.record_length()))
      << "record length " << record_length_ << " vs LAZ items " << vlr_.record_length();
}

void LazChunkWriter::Add(const uint8_t* records, size_t n) {
  const size_t batch = kBatchChunks * vlr_.chunk_size;
  while (n > 0) {
    const size_t held = pending_.size() / record_length_;
    const size_t take = std::min(n, batch - held);
    pending_.insert(pending_.end(), records, records + take * record_length_);
    records += take * record_length_;
    n -= take;
    if (held + take == batch) CompressBatch(batch);
  }
}

// Compresses the first `points` pending records as ceil(points / chunk_size) chunks in parallel,
// then hands them to the sink in order.
void LazChunkWriter::CompressBatch(size_t points) {
  const size_t chunk = vlr_.chunk_size;
  const size_t count = (points + chunk - 1) / chunk;
  chunks_.resize(count);
  std::vector<std::string> errors(count);
  ParallelFor(size_t{0}, count, [&](size_t j) {
    const size_t first = j * chunk;
    const uint32_t n = static_cast<uint32_t>(std::min(chunk, points - first));
    chunks_[j].clear();
    const uint8_t* records = pending_.data() + first * record_length_;
    try {
      if (vlr_.compressor == laz::kLayeredChunked) {
        laz::EncodeLayeredChunk(vlr_.items, records, n, &chunks_[j]);
      } else {
        laz::EncodePointwiseChunk(vlr_.items, records, n, &chunks_[j]);
      }
    } catch (const laz::LazError& e) {
      errors[j] = e.what();
    }
  });
  for (size_t j = 0; j < count; ++j) {
    CANDI_CHECK(errors[j].empty()) << "LAZ chunk encoding: " << errors[j];
    CANDI_CHECK(chunks_[j].size() <= std::numeric_limits<uint32_t>::max())
        << "LAZ chunk of " << chunks_[j].size() << " bytes";
    sink_(chunks_[j].data(), chunks_[j].size());
    chunk_bytes_.push_back(static_cast<uint32_t>(chunks_[j].size()));
  }
  pending_.erase(pending_.begin(),
                 pending_.begin() + static_cast<std::ptrdiff_t>(points * record_length_));
}

std::vector<uint8_t> LazChunkWriter::Finish() {
  if (!pending_.empty()) CompressBatch(pending_.size() / record_length_);
  return EncodeLazChunkTable(chunk_bytes_);
}

}  // namespace candi::io
