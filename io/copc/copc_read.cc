#include "io/copc/copc_read.h"

#include <set>
#include <utility>

#include "core/binary_file.h"
#include "core/check.h"

namespace candi::io {

namespace {

constexpr size_t kInfoBytes = 160, kEntryBytes = 32;
constexpr int32_t kMaxLevel = 30;  // a key's x, y, z are below 2^level in an int32

std::string Byte(uint64_t at) { return "byte " + std::to_string(at); }

// One hierarchy page's entries, checked against the file; child pages go to *pages.
void ReadPage(const BinaryFile& file, uint64_t offset, uint64_t size, CopcSummary* s,
              std::vector<std::pair<uint64_t, uint64_t>>* pages) {
  const std::string& path = file.path();
  if (size % kEntryBytes != 0) {
    throw InputError(
        path, Byte(offset),
        "COPC hierarchy page of " + std::to_string(size) + " bytes: not whole 32-byte entries");
  }
  if (offset > file.size() || size > file.size() - offset) {
    throw InputError(path, Byte(offset),
                     "COPC hierarchy page of " + std::to_string(size) +
                         " bytes runs past the file's end (" + std::to_string(file.size()) +
                         " bytes)");
  }
  std::string bytes(static_cast<size_t>(size), '\0');
  if (file.ReadAt(offset, bytes.data(), bytes.size()) != bytes.size()) {
    throw InputError(path, Byte(offset), "COPC hierarchy page cut short");
  }
  const std::vector<CopcEntry> entries = ParseCopcHierarchy(bytes);
  for (size_t i = 0; i < entries.size(); ++i) {
    const CopcEntry& e = entries[i];
    const std::string at = Byte(offset + i * kEntryBytes);
    const int32_t level = e.key.level;
    const int64_t side = level >= 0 && level <= kMaxLevel ? int64_t{1} << level : 0;
    auto outside = [side](int32_t v) { return v < 0 || v >= side; };
    if (side == 0 || outside(e.key.x) || outside(e.key.y) || outside(e.key.z)) {
      throw InputError(path, at,
                       "COPC hierarchy entry of key " + std::to_string(level) + "-" +
                           std::to_string(e.key.x) + "-" + std::to_string(e.key.y) + "-" +
                           std::to_string(e.key.z) + ": outside its level's cube");
    }
    if (e.points < -1 || e.bytes < 0) {
      throw InputError(path, at,
                       "COPC hierarchy entry with " + std::to_string(e.points) + " points and " +
                           std::to_string(e.bytes) + " bytes");
    }
    const uint64_t bytes_of = static_cast<uint64_t>(e.bytes);
    if (e.points != 0 && (e.offset > file.size() || bytes_of > file.size() - e.offset)) {
      throw InputError(path, at,
                       std::string(e.points == -1 ? "COPC hierarchy page" : "COPC node's chunk") +
                           " at byte " + std::to_string(e.offset) + " of " +
                           std::to_string(e.bytes) + " bytes runs past the file's end");
    }
    if (e.points == -1) {
      pages->emplace_back(e.offset, bytes_of);
      continue;
    }
    const size_t l = static_cast<size_t>(level);
    if (s->nodes_by_level.size() <= l) {
      s->nodes_by_level.resize(l + 1, 0);
      s->points_by_level.resize(l + 1, 0);
    }
    ++s->nodes;
    ++s->nodes_by_level[l];
    if (e.points == 0) ++s->empty_nodes;
    s->points += static_cast<uint64_t>(e.points);
    s->points_by_level[l] += static_cast<uint64_t>(e.points);
  }
}

}  // namespace

std::optional<CopcSummary> ReadCopcSummary(const std::string& path, const LasMetadata& las) {
  const LasVlr* info = nullptr;
  for (const LasVlr& v : las.vlrs) {
    if (!v.extended && v.user_id == kCopcUserId && v.record_id == kCopcInfoRecord) {
      info = &v;
      break;
    }
  }
  if (!info) return std::nullopt;
  if (info->data.size() != kInfoBytes) {
    throw InputError(path, "COPC info VLR",
                     std::to_string(info->data.size()) + " bytes where COPC 1.0 has 160");
  }
  CopcSummary s;
  s.info = ParseCopcInfo(info->data);
  const BinaryFile file(path);
  // The pages from the root, each at most once: a page that a page names again is refused, so
  // a malformed file cannot send the walk round in a loop.
  std::vector<std::pair<uint64_t, uint64_t>> pages = {
      {s.info.root_hier_offset, s.info.root_hier_size}};
  std::set<uint64_t> seen;
  while (!pages.empty()) {
    const auto [offset, size] = pages.back();
    pages.pop_back();
    if (!seen.insert(offset).second) {
      throw InputError(path, Byte(offset), "COPC hierarchy page reached twice");
    }
    ++s.pages;
    ReadPage(file, offset, size, &s, &pages);
  }
  return s;
}

}  // namespace candi::io
