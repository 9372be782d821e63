#include "view/publish.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>
#include <zlib.h>

#include <tbb/task_arena.h>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/timer.h"
#include "render/archive.h"
#include "view/source.h"
#include "view/web_assets.h"

namespace candi::view {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kSiteFormat = "candi site";
constexpr int kPointBytes = 8;

// How a byte plane is deflated: stored when its bytes are near-random (the low bits of the
// positions: Huffman coding would save a few per cent at the cost of most of the time), runs when
// few values dominate it (a layer's one colour), Huffman codes otherwise.
struct PlaneCoding {
  int level;
  int strategy;
};
// (Levels do not matter to run-length and Huffman coding; 1 is deflate's fastest setup.)
PlaneCoding CodingOf(const char* plane, size_t n) {
  constexpr int level = 1;
  uint64_t count[256] = {};
  for (size_t i = 0; i < n; ++i) ++count[static_cast<uint8_t>(plane[i])];
  double bits = 0;
  for (uint64_t c : count) {
    if (c) bits -= static_cast<double>(c) * std::log2(static_cast<double>(c) / static_cast<double>(n));
  }
  const double entropy = n ? bits / static_cast<double>(n) : 0;  // bits a byte
  if (entropy > 7.5) return {0, Z_DEFAULT_STRATEGY};
  if (entropy < 2) return {level, Z_RLE};
  return {level, Z_HUFFMAN_ONLY};
}

// The 8 byte planes of `words`, gzip-compressed (RFC 1952: DecompressionStream("gzip") reads it).
// The coding of each plane (CodingOf) is deflate's own choice of block type; any gzip reader
// reads the stream.
std::string GzipPlanes(const std::vector<uint64_t>& words, const std::string& name) {
  const size_t n = words.size();
  std::string planes(n * kPointBytes, '\0');
  for (int j = 0; j < kPointBytes; ++j) {
    char* out = planes.data() + j * n;
    for (size_t i = 0; i < n; ++i) out[i] = static_cast<char>((words[i] >> (8 * j)) & 0xff);
  }
  z_stream z;
  std::memset(&z, 0, sizeof(z));
  // windowBits 15 + 16: a gzip header and trailer (CRC-32 and length) around the deflate stream.
  const PlaneCoding first = CodingOf(planes.data(), n);
  if (deflateInit2(&z, first.level, Z_DEFLATED, 15 + 16, 8, first.strategy) != Z_OK) {
    throw std::runtime_error(name + ": zlib's deflateInit2 failed");
  }
  // Room for the worst case of every coding: stored blocks add 5 bytes each 16 KB or so.
  std::string out(deflateBound(&z, planes.size()) + planes.size() / 1000 + 1024, '\0');
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  int rc = Z_OK;
  for (int j = 0; j < kPointBytes && rc == Z_OK; ++j) {
    if (j > 0) {
      const PlaneCoding c = CodingOf(planes.data() + j * n, n);
      if (deflateParams(&z, c.level, c.strategy) != Z_OK) rc = Z_STREAM_ERROR;
    }
    z.next_in = reinterpret_cast<Bytef*>(planes.data() + j * n);
    z.avail_in = static_cast<uInt>(n);
    if (rc == Z_OK) rc = deflate(&z, j + 1 == kPointBytes ? Z_FINISH : Z_NO_FLUSH);
    if (rc == Z_OK && z.avail_in != 0) rc = Z_BUF_ERROR;
  }
  const size_t written = z.total_out;
  deflateEnd(&z);
  if (rc != Z_STREAM_END) throw std::runtime_error(name + ": zlib's deflate failed (" + std::to_string(rc) + ")");
  out.resize(written);
  return out;
}

void WriteFile(const std::string& path, const void* data, size_t bytes) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) throw InputError(path, "", std::string("cannot write: ") + std::strerror(errno));
  const bool ok = std::fwrite(data, 1, bytes, f) == bytes;
  const int err = errno;
  if (std::fclose(f) != 0 || !ok) {
    throw InputError(path, "", std::string("cannot write: ") + std::strerror(ok ? errno : err));
  }
}

std::string PageName(size_t group, int page) {
  char name[64];
  std::snprintf(name, sizeof(name), "data/%zu/%d.bin", group, page);
  return name;
}

// The page's files a site holds: all of view/web/ but viewer.js (candi view's backend, the
// server page's entry module; site.js takes its place).
std::vector<std::string> PageFiles() {
  std::vector<std::string> names;
  for (size_t i = 0; i < WebAssetCount(); ++i) {
    const std::string name = std::string(WebAssetAt(i).path).substr(1);
    if (name != "viewer.js") names.push_back(name);
  }
  return names;
}

// The files publish writes at the top of a site: the page's, then site.json (renamed into place
// last, so a visitor's new index names pages that are there).
std::vector<std::string> TopFiles() {
  std::vector<std::string> names = PageFiles();
  names.push_back(kSiteIndex);
  return names;
}

// What loads the site's scripts in index.html: the entry module site.js, with every other module
// preloaded beside it (else a module's imports are found only once it has arrived, a round trip
// for each level of imports). site_worker.js is a worker's script, not a module.
std::string SiteScripts() {
  std::string html;
  for (const std::string& name : PageFiles()) {
    const bool module = name.size() > 3 && name.compare(name.size() - 3, 3, ".js") == 0;
    if (module && name != "site.js" && name != "site_worker.js") {
      html += "<link rel=\"modulepreload\" href=\"" + name + "\">\n";
    }
  }
  return html + "<script type=\"module\" src=\"site.js\"></script>";
}

// The paths under an earlier site's data/ that its site.json does not list (data/<g> and
// data/<g>/<k>.bin of its groups and pages): someone else's, which replacing data/ would delete.
std::vector<std::string> UnlistedDataPaths(const fs::path& site) {
  std::set<std::string> listed;
  try {
    const json j = json::parse(ReadFileToString((site / kSiteIndex).string()));
    const json& groups = j.at("data").at("groups");
    for (size_t g = 0; g < groups.size(); ++g) {
      listed.insert("data/" + std::to_string(g));
      const size_t pages = groups[g].at("pages").size();
      for (size_t k = 0; k < pages; ++k) listed.insert(PageName(g, static_cast<int>(k)));
    }
  } catch (const std::exception&) {
    // A damaged index lists nothing: every file under data/ is named.
  }
  std::vector<std::string> unlisted;
  std::error_code ec;
  const fs::path data = site / "data";
  if (!fs::exists(fs::symlink_status(data, ec))) return unlisted;
  if (!fs::is_directory(fs::symlink_status(data, ec))) return {"data"};
  for (fs::recursive_directory_iterator it(data, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string rel = it->path().lexically_relative(site).generic_string();
    const fs::file_status st = it->symlink_status(ec);
    const bool ours =
        listed.count(rel) &&
        (rel.size() > 4 && rel.compare(rel.size() - 4, 4, ".bin") == 0 ? fs::is_regular_file(st)
                                                                       : fs::is_directory(st));
    if (!ours) {
      unlisted.push_back(rel);
      if (fs::is_directory(st)) it.disable_recursion_pending();
    }
  }
  if (ec) unlisted.push_back("data (cannot be read: " + ec.message() + ")");
  return unlisted;
}

std::string ListSome(const std::vector<std::string>& names) {
  std::string text;
  for (size_t i = 0; i < names.size() && i < 5; ++i) text += (i ? ", " : "") + names[i];
  if (names.size() > 5) text += " and " + std::to_string(names.size() - 5) + " more";
  return text;
}

// Where the site goes, the link followed: `site_dir` absolute, without a trailing separator.
fs::path SiteTarget(const std::string& site_dir) {
  fs::path out = fs::absolute(site_dir).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();
  std::error_code ec;
  if (!fs::is_symlink(out, ec)) return out;
  const fs::path linked = fs::canonical(out, ec);
  if (ec) {
    throw InputError(site_dir, "",
                     "is a symbolic link to " + fs::read_symlink(out, ec).string() +
                         ", which does not exist; create that folder or give another");
  }
  return linked;
}

// Earlier publishes' build folders inside `site` whose process is gone (killed before it could
// remove them): publish's own, removed.
void RemoveStaleBuildFolders(const fs::path& site) {
  std::error_code ec;
  const std::string prefix = ".candi-publish-";
  for (fs::directory_iterator it(site, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid <= 0 || pid == getpid() || kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)
      continue;
    std::error_code removed;
    fs::remove_all(it->path(), removed);
    LogWarning(it->path().string() + ": " +
               (removed ? "an interrupted publish's build folder; could not remove it (" +
                              removed.message() + ")"
                        : "removed an interrupted publish's build folder"));
  }
}

// Moves the new site's files from `temp` (a folder inside `site`) into `site`, each file renamed
// over its old self (atomic per file) and data/ exchanged whole, so nothing else in `site` is
// touched: a .git folder, CNAME, .nojekyll or any file of the owner's stays. The old data/ ends
// in `temp`, which the caller removes.
void MoveIntoPlace(const fs::path& temp, const fs::path& site) {
  auto move = [&](const fs::path& from, const fs::path& to) {
    std::error_code ec;
    fs::rename(from, to, ec);
    if (ec)
      throw InputError(to.string(), "",
                       "cannot move the new site's file into place: " + ec.message());
  };
  const fs::path data = site / "data", fresh = temp / "data";
  std::error_code ec;
  if (fs::exists(fs::symlink_status(data, ec))) {
    if (renameat2(AT_FDCWD, fresh.c_str(), AT_FDCWD, data.c_str(), RENAME_EXCHANGE) != 0) {
      // A filesystem without the exchange: the old data/ aside first, put back if the new fails.
      move(data, temp / "data.old");
      std::error_code failed;
      fs::rename(fresh, data, failed);
      if (failed) {
        fs::rename(temp / "data.old", data, ec);
        throw InputError(data.string(), "",
                         "cannot move the new site's data into place: " + failed.message());
      }
    }
  } else {
    move(fresh, data);
  }
  for (const std::string& name : TopFiles()) move(temp / name, site / name);
}

}  // namespace

void PublishOptions::Check() const {
  CANDI_CHECK_OPTION_IN(repeat_level, 0, 1000);
  CANDI_CHECK_OPTION(group_points >= 1 && group_points <= (uint64_t{1} << 28), group_points, "in [1, 2^28]");
  CANDI_CHECK_OPTION_IN(memory_mb, 16, 65536);
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
}

bool IsSite(const std::string& path) {
  std::error_code ec;
  const fs::path index = fs::path(path) / kSiteIndex;
  if (!fs::is_regular_file(index, ec)) return false;
  try {
    const json j = json::parse(ReadFileToString(index.string()));
    return j.is_object() && j.value("format", "") == kSiteFormat;
  } catch (const std::exception&) {
    return false;
  }
}

PublishStats PublishSite(const PublishOptions& options, const std::string& input, const std::string& site_dir,
                         const render::Orientation& orientation, const ProgressCallback& progress) {
  options.Check();
  Stopwatch watch;
  const std::string archive_dir = render::FindArchive(input);
  if (archive_dir.empty()) {
    throw InputError(input, "", "neither a build directory (archive.json and archive/), a demo's output holding one "
                                "in archive/, nor a render archive (manifest.json)");
  }
  const ViewerSource source = OpenViewerSource(input, orientation);
  const render::Archive archive(source.archive_dir);
  const render::ArchiveManifest& m = archive.manifest();
  const int L = options.repeat_level > 0 ? options.repeat_level
                                         : std::clamp(source.settings.spbr.repeat_level, 1, 1000);
  const uint64_t seed = source.settings.spbr.seed;

  // Refuse early what the moves would refuse late. A folder holding an earlier site (or an empty
  // one) is updated in place; a symbolic link is followed to the folder it names.
  const fs::path out = SiteTarget(site_dir);
  std::error_code ec;
  const bool in_place = fs::exists(out, ec);
  if (in_place) {
    if (!fs::is_directory(out, ec))
      throw InputError(site_dir, "", "exists and is not a folder; not overwriting it");
    if (!IsSite(out.string()) && !fs::is_empty(out, ec)) {
      throw InputError(site_dir, "", "exists and is not a candi site; not overwriting it");
    }
    for (const std::string& name : TopFiles()) {
      const fs::file_status st = fs::symlink_status(out / name, ec);
      if (fs::exists(st) && !fs::is_regular_file(st)) {
        throw InputError((out / name).string(), "",
                         "is not a file; the site's own file goes there");
      }
    }
    const std::vector<std::string> unlisted = UnlistedDataPaths(out);
    if (!unlisted.empty()) {
      throw InputError(site_dir, "",
                       "its data/ holds what the earlier site.json does not list (" +
                           ListSome(unlisted) +
                           "); publish replaces data/ whole: move them out of data/ first");
    }
    if (::access(out.c_str(), W_OK) != 0) throw InputError(site_dir, "", "is not writable");
    RemoveStaleBuildFolders(out);
  } else {
    CheckOutputFolder(out.string());
  }

  // Groups: runs of consecutive chunks of at most group_points points (a chunk larger than that
  // is a group of its own).
  std::vector<std::pair<size_t, size_t>> groups;
  for (size_t c = 0; c < m.chunks.size();) {
    size_t end = c + 1;
    uint64_t points = m.chunks[c].count;
    while (end < m.chunks.size() && points + m.chunks[end].count <= options.group_points) {
      points += m.chunks[end++].count;
    }
    groups.push_back({c, end});
    c = end;
  }

  // Built inside the folder it updates (the same filesystem, whatever is mounted where), or beside
  // a new one.
  const std::string temp = in_place
                               ? (out / (".candi-publish-" + std::to_string(getpid()))).string()
                               : out.string() + ".candi-tmp-" + std::to_string(getpid());
  fs::remove_all(temp, ec);
  // Created and registered in one step: an interrupt removes it, or comes before it exists.
  const int interrupt_id = CreateTempDirectory(temp, &ec);
  if (interrupt_id < 0) throw InputError(temp, "", "cannot create the site's build folder: " + ec.message());
  TempFolder cleanup(temp, interrupt_id);
  if (!fs::create_directory(fs::path(temp) / "data", ec) || ec) {
    throw InputError(temp, "", "cannot create the site's build folder: " + ec.message());
  }

  // Page files, in parallel over (group, page) in group order (a group's chunks are released
  // once its last page is written): the same bytes for any thread count.
  for (size_t g = 0; g < groups.size(); ++g) fs::create_directories(fs::path(temp) / "data" / std::to_string(g));
  using Page = std::pair<uint64_t, uint64_t>;  // bytes, points
  std::vector<std::vector<Page>> pages(groups.size(), std::vector<Page>(L));
  std::unique_ptr<std::atomic<int>[]> pages_done(new std::atomic<int>[groups.size()]);
  for (size_t g = 0; g < groups.size(); ++g) pages_done[g] = 0;
  std::atomic<uint64_t> done{0};
  std::mutex progress_mutex;
  auto body = [&](size_t task) {
    const size_t g = task / static_cast<size_t>(L);
    const int k = static_cast<int>(task % static_cast<size_t>(L));
    std::vector<uint64_t> words;
    std::vector<render::PointRun> runs;
    for (size_t c = groups[g].first; c < groups[g].second; ++c) {
      const render::ArchiveChunk& chunk = m.chunks[c];
      const uint64_t* data = archive.ChunkWords(c, /*verify=*/true);
      runs.clear();
      render::EnsembleSlices(chunk.count, chunk.first, L, seed, k, 1.0, &runs);
      for (const render::PointRun& r : runs) words.insert(words.end(), data + r.begin, data + r.end);
    }
    const std::string name = PageName(g, k);
    const std::string bytes = GzipPlanes(words, name);
    WriteFile(temp + "/" + name, bytes.data(), bytes.size());
    pages[g][k] = {bytes.size(), words.size()};
    const uint64_t now = done += words.size();
    if (++pages_done[g] == L) {
      std::vector<size_t> released;
      for (size_t c = groups[g].first; c < groups[g].second; ++c) released.push_back(c);
      archive.Release(released);
    }
    if (progress) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      progress(now, m.points);
    }
  };
  const size_t tasks = groups.size() * static_cast<size_t>(L);
  if (options.threads == 1) {
    for (size_t t = 0; t < tasks; ++t) body(t);
  } else {
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
    arena.execute([&] { ParallelFor(size_t{0}, tasks, body); });
  }

  PublishStats stats;
  stats.points = m.points;
  stats.chunks = m.chunks.size();
  stats.groups = groups.size();
  stats.repeat_level = L;

  // The index: compact arrays, one per chunk and one per group.
  json chunks = json::array();
  for (size_t g = 0; g < groups.size(); ++g) {
    for (size_t c = groups[g].first; c < groups[g].second; ++c) {
      const render::ArchiveChunk& k = m.chunks[c];
      const render::ChunkQuantizer& q = k.quantizer;
      chunks.push_back({k.layer, k.count, k.first, g, q.box.min.x(), q.box.min.y(), q.box.min.z(), q.box.max.x(),
                        q.box.max.y(), q.box.max.z(), q.step[0], q.step[1], q.step[2], q.bits[0], q.bits[1],
                        q.bits[2]});
    }
  }
  json groups_json = json::array();
  for (size_t g = 0; g < groups.size(); ++g) {
    json files = json::array();
    for (int k = 0; k < L; ++k) {
      files.push_back({pages[g][k].first, pages[g][k].second});
      stats.data_bytes += pages[g][k].first;
      if (k == 0) stats.first_image_bytes += pages[g][k].first;
      ++stats.files;
    }
    groups_json.push_back({{"chunks", {groups[g].first, groups[g].second}}, {"pages", files}});
  }
  json site = {
      {"format", kSiteFormat},
      {"version", kSiteVersion},
      {"scene", json::parse(source.ToJson(m))},
      {"data",
       {{"repeat_level", L},
        {"seed", seed},
        {"memory_mb", options.memory_mb},
        {"point_bytes", kPointBytes},
        {"pages", "data/<group>/<page>.bin: page k of a group holds, chunk by chunk, the slice ensemble k draws "
                  "at this repeat_level and seed (EnsembleSlices of the render archive)"},
        {"encoding", "the render archive's 8-byte points (bits 0-23 colour 0xRRGGBB, then bx, by, bz bits of x, y, "
                     "z quantized on the chunk's box: min + q * step) as 8 byte planes, gzip"},
        {"chunk_fields", {"layer", "count", "first", "group", "min_x", "min_y", "min_z", "max_x", "max_y", "max_z",
                          "step_x", "step_y", "step_z", "bits_x", "bits_y", "bits_z"}},
        {"chunks", chunks},
        {"group_fields", "chunks: [first, end) of the chunks; pages: per page [bytes, points]"},
        {"groups", groups_json}}}};
  const std::string index = site.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
  WriteFile(temp + "/" + kSiteIndex, index.data(), index.size());
  stats.first_image_bytes += index.size();

  // The page: the viewer's files, its index.html loading the WebGL2 renderer instead of the
  // server's protocol.
  for (const std::string& name : PageFiles()) {
    const WebAsset& a = *FindWebAsset("/" + name);
    std::string content(reinterpret_cast<const char*>(a.data), a.size);
    if (name == "index.html") {
      const std::string from = "<script type=\"module\" src=\"viewer.js\"></script>";
      const size_t at = content.find(from);
      CANDI_CHECK(at != std::string::npos) << "index.html has no " << from;
      content.replace(at, from.size(), SiteScripts());
      const std::string body = "<body>";
      const size_t b = content.find(body);
      CANDI_CHECK(b != std::string::npos) << "index.html has no <body>";
      content.replace(b, body.size(), "<body class=\"site\">");
    }
    WriteFile(temp + "/" + name, content.data(), content.size());
    stats.first_image_bytes += content.size();
  }
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(temp)) {
    if (e.is_regular_file()) stats.site_bytes += e.file_size();
  }

  if (in_place) {
    CommitTempPath(cleanup.id(), [&] { MoveIntoPlace(temp, out); });
    // The build folder now holds the old data/ (and nothing of the new site).
    cleanup.Keep();
    std::error_code removed;
    fs::remove_all(temp, removed);
    if (removed || fs::exists(temp, ec)) {
      LogWarning(site_dir +
                 ": the new site is in place, but the old site's data could not be removed: it is "
                 "left in " +
                 temp + " (" + (removed ? removed.message() : std::string("still there")) +
                 "); remove it by hand");
    }
  } else {
    CommitTempPath(cleanup.id(), [&] {
      fs::rename(temp, out, ec);
      if (ec)
        throw InputError(site_dir, "", "cannot rename the new site into place: " + ec.message());
      cleanup.Keep();
    });
  }
  stats.seconds = watch.Seconds();
  return stats;
}

}  // namespace candi::view
