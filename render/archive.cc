#include "render/archive.h"

#include <fcntl.h>
#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/rng.h"

namespace candi::render {

namespace {

constexpr uint64_t kP1 = 0x9E3779B185EBCA87ULL, kP2 = 0xC2B2AE3D27D4EB4FULL, kP3 = 0x165667B19E3779F9ULL,
                   kP4 = 0x85EBCA77C2B2AE63ULL, kP5 = 0x27D4EB2F165667C5ULL;

inline uint64_t Round(uint64_t acc, uint64_t input) { return Rotl(acc + input * kP2, 31) * kP1; }
inline uint64_t MergeRound(uint64_t acc, uint64_t v) { return (acc ^ Round(0, v)) * kP1 + kP4; }
inline uint64_t Load64(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

std::string Hex(uint64_t v) {
  char buffer[17];
  std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(v));
  return buffer;
}

uint64_t ParseHex(const std::string& text, const std::string& path, const std::string& field) {
  if (text.size() != 16 || text.find_first_not_of("0123456789abcdef") != std::string::npos) {
    throw InputError(path, field, "expected 16 lower-case hex digits, got '" + text + "'");
  }
  return std::stoull(text, nullptr, 16);
}

}  // namespace

namespace {

// xxHash64's end for an input of `bytes` bytes: its four lanes merged (v: null for an input of
// fewer than 32 bytes), the tail [p, end) and the avalanche.
uint64_t Finish(const uint64_t* v, const uint8_t* p, const uint8_t* end, uint64_t bytes,
                uint64_t seed) {
  uint64_t h;
  if (v != nullptr) {
    h = Rotl(v[0], 1) + Rotl(v[1], 7) + Rotl(v[2], 12) + Rotl(v[3], 18);
    for (int k = 0; k < 4; ++k) h = MergeRound(h, v[k]);
  } else {
    h = seed + kP5;
  }
  h += bytes;
  for (; p + 8 <= end; p += 8) h = Rotl(h ^ Round(0, Load64(p)), 27) * kP1 + kP4;
  if (p + 4 <= end) {
    uint32_t w;
    std::memcpy(&w, p, 4);
    h = Rotl(h ^ (static_cast<uint64_t>(w) * kP1), 23) * kP2 + kP3;
    p += 4;
  }
  for (; p < end; ++p) h = Rotl(h ^ (*p * kP5), 11) * kP1;
  h ^= h >> 33;
  h *= kP2;
  h ^= h >> 29;
  h *= kP3;
  h ^= h >> 32;
  return h;
}

#if defined(__x86_64__)
// The lanes of four inputs after `stripes` stripes of 32 bytes each (seed 0), v[4 * k + lane]
// for input k, each input's four lanes in one register (vpmullq of AVX-512DQ on 256 bits). One
// input's lanes are a chain of two dependent multiplications a stripe, so one input at a time
// waits on them; four at a time keep the multipliers busy (2.5x the bytes a second, mapped
// pages included, on the project's Zen 4 VM).
__attribute__((target("avx512f,avx512dq,avx512vl"))) void Lanes4Avx512(const uint8_t* const* in,
                                                                       size_t stripes,
                                                                       uint64_t* v) {
  const __m256i p1 = _mm256_set1_epi64x(static_cast<long long>(kP1));
  const __m256i p2 = _mm256_set1_epi64x(static_cast<long long>(kP2));
  const __m256i start =
      _mm256_setr_epi64x(static_cast<long long>(kP1 + kP2), static_cast<long long>(kP2), 0,
                         static_cast<long long>(0 - kP1));
  __m256i acc[4] = {start, start, start, start};
  const uint8_t* const i0 = in[0];
  const uint8_t* const i1 = in[1];
  const uint8_t* const i2 = in[2];
  const uint8_t* const i3 = in[3];
  for (size_t s = 0; s < stripes; ++s) {
    const size_t o = 32 * s;
    const __m256i x[4] = {_mm256_loadu_si256(reinterpret_cast<const __m256i*>(i0 + o)),
                          _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i1 + o)),
                          _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i2 + o)),
                          _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i3 + o))};
    for (int k = 0; k < 4; ++k) {
      acc[k] = _mm256_mullo_epi64(
          _mm256_rol_epi64(_mm256_add_epi64(acc[k], _mm256_mullo_epi64(x[k], p2)), 31), p1);
    }
  }
  for (int k = 0; k < 4; ++k) _mm256_storeu_si256(reinterpret_cast<__m256i*>(v + 4 * k), acc[k]);
}

bool HasAvx512DqVl() {
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                          __builtin_cpu_supports("avx512vl");
  return has;
}
#else
void Lanes4Avx512(const uint8_t* const*, size_t, uint64_t*) {}
bool HasAvx512DqVl() { return false; }
#endif

}  // namespace

uint64_t ArchiveHash(const void* data, size_t bytes, uint64_t seed) {
  // xxHash64 (Yann Collet's algorithm, reimplemented), so a chunk hashes at memory speed.
  const uint8_t* p = static_cast<const uint8_t*>(data);
  const uint8_t* end = p + bytes;
  if (bytes < 32) return Finish(nullptr, p, end, bytes, seed);
  uint64_t v[4] = {seed + kP1 + kP2, seed + kP2, seed, seed - kP1};
  const uint8_t* limit = end - 32;
  do {
    v[0] = Round(v[0], Load64(p));
    v[1] = Round(v[1], Load64(p + 8));
    v[2] = Round(v[2], Load64(p + 16));
    v[3] = Round(v[3], Load64(p + 24));
    p += 32;
  } while (p <= limit);
  return Finish(v, p, end, bytes, seed);
}

void ArchiveHashBlocks(const uint8_t* const* blocks, int count, size_t bytes, uint64_t* out) {
  CANDI_CHECK(count >= 0 && count <= 4) << "ArchiveHashBlocks: " << count << " blocks";
  if (count < 2 || bytes < 32 || !HasAvx512DqVl()) {
    for (int k = 0; k < count; ++k) out[k] = ArchiveHash(blocks[k], bytes);
    return;
  }
  const uint8_t* in[4];
  for (int k = 0; k < 4; ++k)
    in[k] = blocks[k < count ? k : 0];  // a block twice: read from the cache
  const size_t stripes = bytes / 32;
  uint64_t v[16];
  Lanes4Avx512(in, stripes, v);
  for (int k = 0; k < count; ++k)
    out[k] = Finish(&v[4 * k], in[k] + 32 * stripes, in[k] + bytes, bytes, 0);
}

ChunkQuantizer ChunkQuantizer::ForBox(const Box3d& box) {
  CANDI_CHECK(!box.IsEmpty()) << "ChunkQuantizer::ForBox of an empty box";
  ChunkQuantizer q;
  q.box = box;
  const Eigen::Vector3d extent = box.Extent();
  int left = kArchivePositionBits;
  auto step_of = [&](int a, int bits) { return extent[a] / (std::ldexp(1.0, bits) - 1.0); };
  for (int a = 0; a < 3; ++a) {
    CANDI_CHECK(std::isfinite(extent[a])) << "ChunkQuantizer::ForBox: box not finite";
    if (extent[a] > 0) q.bits[a] = 1, --left;
  }
  while (left > 0) {
    int best = -1;
    double best_step = 0;
    for (int a = 0; a < 3; ++a) {
      if (q.bits[a] == 0 || q.bits[a] >= kArchiveMaxAxisBits) continue;
      const double s = step_of(a, q.bits[a]);
      if (s > best_step) best = a, best_step = s;
    }
    if (best < 0) break;
    ++q.bits[best];
    --left;
  }
  for (int a = 0; a < 3; ++a) q.step[a] = q.bits[a] ? step_of(a, q.bits[a]) : 0.0;
  return q;
}

// ---- manifest -------------------------------------------------------------------------------

namespace {

using Json = nlohmann::json;

Json Vec(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

template <typename T>
T Get(const Json& j, const char* key, const std::string& path, const std::string& where) {
  if (!j.is_object() || !j.contains(key)) throw InputError(path, where, std::string("missing field '") + key + "'");
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    // Integers must be written as integers that fit: JSON numbers beyond 64 bits parse as double,
    // and converting those (or fractions) to an integer is undefined.
    const Json& v = j.at(key);
    const bool fits = std::is_unsigned_v<T>
                          ? v.is_number_unsigned() && v.get<uint64_t>() <= std::numeric_limits<T>::max()
                          : v.is_number_integer() && (v.is_number_unsigned()
                                                          ? v.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<T>::max())
                                                          : v.get<int64_t>() >= std::numeric_limits<T>::min() &&
                                                                v.get<int64_t>() <= std::numeric_limits<T>::max());
    if (!fits) throw InputError(path, where + "." + key, "expected an integer in [" + std::to_string(std::numeric_limits<T>::min()) + ", " + std::to_string(std::numeric_limits<T>::max()) + "], got " + v.dump());
  }
  try {
    return j.at(key).get<T>();
  } catch (const Json::exception& e) {
    throw InputError(path, where + "." + key, std::string("wrong type: ") + e.what());
  }
}

Eigen::Vector3d GetVec(const Json& j, const char* key, const std::string& path, const std::string& where) {
  const std::vector<double> v = Get<std::vector<double>>(j, key, path, where);
  if (v.size() != 3 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
    throw InputError(path, where + "." + key, "expected three finite numbers");
  }
  return {v[0], v[1], v[2]};
}

// The colouring by a field the points were packed in: what a legend needs (the field, the
// scale, the range, the classes present, the counts).
Json ColourByJson(const FieldLegend& l) {
  Json j = {{"field", l.field},   {"scale", FieldScaleName(l.scale)}, {"lo", l.lo},
            {"hi", l.hi},         {"count", l.count},                 {"outside", l.outside},
            {"undefined", l.undefined}};
  if (l.scale == FieldScale::kClasses) j["classes"] = l.classes;
  return j;
}

FieldLegend ParseColourBy(const Json& j, const std::string& path) {
  const std::string where = "colour_by";
  if (!j.is_object()) throw InputError(path, where, "expected an object");
  FieldLegend l;
  l.field = Get<std::string>(j, "field", path, where);
  if (l.field.empty()) throw InputError(path, where + ".field", "empty");
  const std::string scale = Get<std::string>(j, "scale", path, where);
  try {
    l.scale = ParseFieldScale(scale);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, where + ".scale", e.what());
  }
  if (l.scale == FieldScale::kAuto) throw InputError(path, where + ".scale", "a packed colouring has a resolved scale");
  l.lo = Get<double>(j, "lo", path, where);
  l.hi = Get<double>(j, "hi", path, where);
  if (!std::isfinite(l.lo) || !std::isfinite(l.hi) || (l.scale != FieldScale::kClasses && !(l.lo < l.hi))) {
    throw InputError(path, where, "expected finite lo < hi");
  }
  l.count = Get<uint64_t>(j, "count", path, where);
  l.outside = Get<uint64_t>(j, "outside", path, where);
  l.undefined = Get<uint64_t>(j, "undefined", path, where);
  if (l.scale == FieldScale::kClasses) l.classes = Get<std::vector<int>>(j, "classes", path, where);
  return l;
}

}  // namespace

std::string ArchiveManifest::ToJson() const {
  Json j;
  j["format"] = "candi render archive";
  j["version"] = version;
  j["frame_origin"] = Vec(frame.origin);
  j["bounds_min"] = Vec(bounds.min);
  j["bounds_max"] = Vec(bounds.max);
  j["points"] = points;
  j["chunk_points"] = chunk_points;
  j["shuffle_seed"] = shuffle_seed;
  j["encoding"] = "uint64 LE per point: bits 0-23 colour 0xRRGGBB, then x, y, z with bits[] bits each, "
                  "x = min + q * step; chunks of one layer each, in Morton order per layer; points in a "
                  "seeded random order within a chunk; hash = xxHash64 seed 0";
  Json l = Json::array();
  for (const ArchiveLayer& layer : layers) l.push_back({{"name", layer.name}, {"points", layer.points}});
  j["layers"] = l;
  Json s = Json::array();
  for (const ArchiveSource& src : sources) {
    s.push_back({{"path", src.path}, {"bytes", src.bytes}, {"hash", Hex(src.hash)}, {"points", src.points}});
  }
  j["sources"] = s;
  Json f = Json::array();
  for (const ArchiveFile& file : files) f.push_back({{"name", file.name}, {"bytes", file.bytes}});
  j["files"] = f;
  Json c = Json::array();
  for (const ArchiveChunk& ch : chunks) {
    c.push_back({{"file", ch.file},
                 {"offset", ch.offset},
                 {"count", ch.count},
                 {"first", ch.first},
                 {"layer", ch.layer},
                 {"min", Vec(ch.quantizer.box.min)},
                 {"max", Vec(ch.quantizer.box.max)},
                 {"bits", {ch.quantizer.bits[0], ch.quantizer.bits[1], ch.quantizer.bits[2]}},
                 {"step", {ch.quantizer.step[0], ch.quantizer.step[1], ch.quantizer.step[2]}},
                 {"hash", Hex(ch.hash)}});
  }
  j["chunks"] = c;
  if (colour_by) j["colour_by"] = ColourByJson(*colour_by);
  return j.dump(1) + "\n";
}

ArchiveManifest ArchiveManifest::FromJson(const std::string& text, const std::string& path) {
  Json j;
  try {
    j = Json::parse(text);
  } catch (const Json::exception& e) {
    throw InputError(path, "", std::string("not valid JSON: ") + e.what());
  }
  ArchiveManifest m;
  if (Get<std::string>(j, "format", path, "manifest") != "candi render archive") {
    throw InputError(path, "format", "not a candi render archive manifest");
  }
  m.version = Get<int>(j, "version", path, "manifest");
  if (m.version == 1) {
    throw InputError(path, "version", "archive version 1 (made before candi view: ensembles drawn by hash, no "
                                      "layers); this candi reads version " + std::to_string(kArchiveVersion) +
                                      ": pack the point files again with candi pack");
  }
  if (m.version != kArchiveVersion) {
    throw InputError(path, "version", "archive version " + std::to_string(m.version) + "; this candi reads version " +
                                          std::to_string(kArchiveVersion));
  }
  m.frame.origin = GetVec(j, "frame_origin", path, "manifest");
  m.bounds.min = GetVec(j, "bounds_min", path, "manifest");
  m.bounds.max = GetVec(j, "bounds_max", path, "manifest");
  m.points = Get<uint64_t>(j, "points", path, "manifest");
  m.chunk_points = Get<uint64_t>(j, "chunk_points", path, "manifest");
  m.shuffle_seed = Get<uint64_t>(j, "shuffle_seed", path, "manifest");
  for (const Json& l : Get<Json>(j, "layers", path, "manifest")) {
    ArchiveLayer layer;
    layer.name = Get<std::string>(l, "name", path, "layers");
    layer.points = Get<uint64_t>(l, "points", path, "layers");
    m.layers.push_back(layer);
  }
  if (m.layers.empty()) throw InputError(path, "layers", "an archive has at least one layer");
  std::vector<uint64_t> layer_points(m.layers.size(), 0);
  for (const Json& s : Get<Json>(j, "sources", path, "manifest")) {
    ArchiveSource src;
    src.path = Get<std::string>(s, "path", path, "sources");
    src.bytes = Get<uint64_t>(s, "bytes", path, "sources");
    src.hash = ParseHex(Get<std::string>(s, "hash", path, "sources"), path, "sources.hash");
    src.points = Get<uint64_t>(s, "points", path, "sources");
    m.sources.push_back(src);
  }
  for (const Json& f : Get<Json>(j, "files", path, "manifest")) {
    ArchiveFile file;
    file.name = Get<std::string>(f, "name", path, "files");
    if (file.name.empty() || file.name.find('/') != std::string::npos || file.name[0] == '.') {
      throw InputError(path, "files", "data file name '" + file.name + "' must be a plain file name");
    }
    file.bytes = Get<uint64_t>(f, "bytes", path, "files");
    m.files.push_back(file);
  }
  const Json& chunks = Get<Json>(j, "chunks", path, "manifest");
  m.chunks.reserve(chunks.size());
  uint64_t next = 0;
  for (size_t k = 0; k < chunks.size(); ++k) {
    const Json& c = chunks[k];
    const std::string where = "chunks[" + std::to_string(k) + "]";
    ArchiveChunk ch;
    ch.file = Get<int>(c, "file", path, where);
    ch.offset = Get<uint64_t>(c, "offset", path, where);
    ch.count = Get<uint64_t>(c, "count", path, where);
    ch.first = Get<uint64_t>(c, "first", path, where);
    ch.layer = Get<int>(c, "layer", path, where);
    if (ch.layer < 0 || static_cast<size_t>(ch.layer) >= m.layers.size()) {
      throw InputError(path, where + ".layer", "layer index " + std::to_string(ch.layer) + " out of range");
    }
    ch.quantizer.box.min = GetVec(c, "min", path, where);
    ch.quantizer.box.max = GetVec(c, "max", path, where);
    const Json& bits_json = Get<Json>(c, "bits", path, where);
    std::vector<int> bits;
    for (size_t a = 0; bits_json.is_array() && a < bits_json.size(); ++a) {
      if (!bits_json[a].is_number_unsigned() || bits_json[a].get<uint64_t>() > kArchiveMaxAxisBits)
        throw InputError(path, where + ".bits", "expected integers in [0, " + std::to_string(kArchiveMaxAxisBits) + "]");
      bits.push_back(bits_json[a].get<int>());
    }
    const std::vector<double> step = Get<std::vector<double>>(c, "step", path, where);
    if (bits.size() != 3 || step.size() != 3) throw InputError(path, where, "bits and step need 3 entries");
    int total = 0;
    for (int a = 0; a < 3; ++a) {
      if (bits[a] < 0 || bits[a] > kArchiveMaxAxisBits || !(step[a] >= 0) || !std::isfinite(step[a])) {
        throw InputError(path, where, "bad bits/step on axis " + std::to_string(a));
      }
      ch.quantizer.bits[a] = bits[a];
      ch.quantizer.step[a] = step[a];
      total += bits[a];
    }
    if (total > kArchivePositionBits) throw InputError(path, where, "more than 40 position bits");
    ch.hash = ParseHex(Get<std::string>(c, "hash", path, where), path, where + ".hash");
    if (ch.file < 0 || static_cast<size_t>(ch.file) >= m.files.size()) {
      throw InputError(path, where, "file index " + std::to_string(ch.file) + " out of range");
    }
    const uint64_t file_bytes = m.files[ch.file].bytes;
    if (ch.count == 0 || ch.first != next || ch.offset % 8 != 0 || ch.offset > file_bytes ||
        ch.count > (file_bytes - ch.offset) / 8) {
      throw InputError(path, where, "count/first/offset inconsistent with the file sizes and the chunks before");
    }
    next += ch.count;
    layer_points[ch.layer] += ch.count;
    m.chunks.push_back(ch);
  }
  for (size_t l = 0; l < m.layers.size(); ++l) {
    if (layer_points[l] != m.layers[l].points) {
      throw InputError(path, "layers[" + std::to_string(l) + "].points",
                       "the chunks of layer '" + m.layers[l].name + "' hold " + std::to_string(layer_points[l]) +
                           " points, the manifest says " + std::to_string(m.layers[l].points));
    }
  }
  if (next != m.points) {
    throw InputError(path, "points", "the chunks hold " + std::to_string(next) + " points, the manifest says " +
                                         std::to_string(m.points));
  }
  if (j.contains("colour_by")) m.colour_by = ParseColourBy(j["colour_by"], path);
  return m;
}

void EnsembleSlices(uint64_t n, uint64_t chunk_first, int L, uint64_t seed, int ensemble, double fraction,
                    std::vector<PointRun>* runs) {
  if (!(fraction > 0) || n == 0) return;
  const uint64_t r = HashIndex(seed, chunk_first, /*stream=*/0x5EED511CE) % static_cast<uint64_t>(L);
  // floor(s n / L) without overflow: n < 2^40 points, L <= 2^17.
  auto bound = [&](uint64_t s) {
    return static_cast<uint64_t>((static_cast<unsigned __int128>(s) * n) / static_cast<unsigned>(L));
  };
  for (int j = 0; j < static_cast<int>(std::ceil(fraction)) && j < L; ++j) {
    const uint64_t s = (static_cast<uint64_t>(ensemble) + r + static_cast<uint64_t>(j)) % static_cast<uint64_t>(L);
    const uint64_t begin = bound(s), end = bound(s + 1);
    const double share = std::min(1.0, fraction - j);
    uint64_t take = end - begin;
    if (share < 1.0) {
      // share x of the slice, rounded stochastically (seeded by the slice): unbiased even when
      // slices hold a point or two (small chunks, large L).
      const double x = share * static_cast<double>(end - begin);
      const double u = static_cast<double>(HashIndex(seed, chunk_first * 131 + s, 0xF4AC7) >> 11) * 0x1.0p-53;
      take = static_cast<uint64_t>(std::floor(x)) + ((x - std::floor(x)) > u ? 1 : 0);
    }
    if (take > 0) runs->push_back({begin, begin + take});
  }
}

bool IsArchive(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) return false;
  return stat((path + "/" + kArchiveManifest).c_str(), &st) == 0;
}

std::string FindArchive(const std::string& path) {
  for (const std::string& p : {path, path + "/archive", path + "/archive/archive"}) {
    if (IsArchive(p)) return p;
  }
  return "";
}

// ---- Archive --------------------------------------------------------------------------------

Archive::Archive(const std::string& directory) : directory_(directory) {
  const std::string manifest_path = directory + "/" + kArchiveManifest;
  struct stat st;
  if (stat(directory.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    throw InputError(directory, "", "not a directory (a render archive is a directory with manifest.json)");
  }
  manifest_ = ArchiveManifest::FromJson(ReadFileToString(manifest_path), manifest_path);
  verified_ = std::make_unique<std::atomic<uint8_t>[]>(manifest_.chunks.size());
  for (size_t k = 0; k < manifest_.chunks.size(); ++k) verified_[k].store(0);
  maps_.resize(manifest_.files.size());
  for (size_t f = 0; f < manifest_.files.size(); ++f) {
    const std::string path = directory + "/" + manifest_.files[f].name;
    const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
      throw InputError(path, "", std::string("cannot open archive data file: ") + std::strerror(errno));
    }
    struct stat fs;
    if (fstat(fd, &fs) != 0 || static_cast<uint64_t>(fs.st_size) != manifest_.files[f].bytes) {
      const uint64_t size = static_cast<uint64_t>(fs.st_size);
      close(fd);
      throw InputError(path, "", "archive data file has " + std::to_string(size) + " bytes; the manifest says " +
                                     std::to_string(manifest_.files[f].bytes) + " (truncated or replaced)");
    }
    if (fs.st_size > 0) {
      void* p = mmap(nullptr, fs.st_size, PROT_READ, MAP_SHARED, fd, 0);
      const int err = errno;
      close(fd);
      if (p == MAP_FAILED) throw InputError(path, "", std::string("cannot map: ") + std::strerror(err));
      madvise(p, fs.st_size, MADV_SEQUENTIAL);
      maps_[f] = {p, static_cast<size_t>(fs.st_size)};
    } else {
      close(fd);
    }
  }
}

Archive::~Archive() {
  for (const Mapping& m : maps_) {
    if (m.data) munmap(m.data, m.bytes);
  }
}

const uint64_t* Archive::ChunkWords(size_t chunk, bool verify) const {
  CANDI_CHECK_LT(chunk, manifest_.chunks.size());
  const ArchiveChunk& c = manifest_.chunks[chunk];
  const uint8_t* base = static_cast<const uint8_t*>(maps_[c.file].data) + c.offset;
  if (verify && !verified_[chunk].load(std::memory_order_acquire)) {
    const uint64_t h = ArchiveHash(base, 8 * c.count);
    if (h == c.hash) verified_[chunk].store(1, std::memory_order_release);
    if (h != c.hash) {
      throw InputError(directory_ + "/" + manifest_.files[c.file].name, "byte " + std::to_string(c.offset),
                       "chunk " + std::to_string(chunk) + " (" + std::to_string(c.count) +
                           " points) does not match its hash: the archive is corrupt");
    }
  }
  return reinterpret_cast<const uint64_t*>(base);
}

void Archive::Release(std::vector<size_t> chunks) const {
  const uint64_t page = static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
  std::sort(chunks.begin(), chunks.end(), [&](size_t a, size_t b) {
    const ArchiveChunk &x = manifest_.chunks[a], &y = manifest_.chunks[b];
    return std::make_pair(x.file, x.offset) < std::make_pair(y.file, y.offset);
  });
  // One call per run of adjacent chunks, over the whole pages inside it (a page shared with a
  // chunk outside the run stays).
  auto advise = [&](int file, uint64_t begin, uint64_t end) {
    begin = (begin + page - 1) / page * page;
    end = end / page * page;
    if (end > begin) madvise(static_cast<uint8_t*>(maps_[file].data) + begin, end - begin, MADV_DONTNEED);
  };
  int file = -1;
  uint64_t begin = 0, end = 0;
  for (size_t k : chunks) {
    CANDI_CHECK_LT(k, manifest_.chunks.size());
    const ArchiveChunk& c = manifest_.chunks[k];
    if (c.file == file && c.offset == end) {
      end += 8 * c.count;
      continue;
    }
    if (file >= 0) advise(file, begin, end);
    file = c.file, begin = c.offset, end = c.offset + 8 * c.count;
  }
  if (file >= 0) advise(file, begin, end);
}

void Archive::ReadChunk(size_t chunk, PointCloud* out, bool verify) const {
  const ArchiveChunk& c = manifest_.chunks[chunk];
  const uint64_t* words = ChunkWords(chunk, verify);
  PointSchema schema;
  schema.colors = true;
  out->SetSchema(schema);
  out->frame = manifest_.frame;
  out->Resize(c.count);
  for (uint64_t i = 0; i < c.count; ++i) {
    out->positions[i] = c.quantizer.Decode(words[i]);
    const uint32_t rgb = ChunkQuantizer::Color(words[i]);
    out->colors[i] = {static_cast<uint8_t>(rgb >> 16), static_cast<uint8_t>(rgb >> 8), static_cast<uint8_t>(rgb)};
  }
}

PointCloud Archive::ReadAll() const {
  PointCloud all, chunk;
  PointSchema schema;
  schema.colors = true;
  all.SetSchema(schema);
  all.frame = manifest_.frame;
  all.Reserve(manifest_.points);
  for (size_t k = 0; k < manifest_.chunks.size(); ++k) {
    ReadChunk(k, &chunk);
    all.positions.insert(all.positions.end(), chunk.positions.begin(), chunk.positions.end());
    all.colors.insert(all.colors.end(), chunk.colors.begin(), chunk.colors.end());
  }
  return all;
}

}  // namespace candi::render
