#include "reconstruction/photogrammetry/sfm/colmap_database.h"

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>

#include "core/check.h"

namespace candi::photogrammetry {

namespace {

constexpr int64_t kSiftDimensions = 128;

struct CloseDatabase {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct FinalizeStatement {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using Database = std::unique_ptr<sqlite3, CloseDatabase>;
using Statement = std::unique_ptr<sqlite3_stmt, FinalizeStatement>;

Statement Prepare(sqlite3* db, const std::string& path, const char* sql) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &raw, nullptr) != SQLITE_OK) {
    throw InputError(path, "", std::string("not a COLMAP database (") + sqlite3_errmsg(db) + ")");
  }
  return Statement(raw);
}

// Steps through a statement's rows; false at the end. Throws on an error.
bool Step(sqlite3* db, sqlite3_stmt* statement, const std::string& path) {
  const int rc = sqlite3_step(statement);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  throw InputError(path, "", std::string("cannot read the database: ") + sqlite3_errmsg(db));
}

Database Open(const std::string& path, int flags) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path, "", "no such database file");
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, flags, nullptr);
  Database db(raw);
  if (rc != SQLITE_OK) {
    throw InputError(path, "", std::string("cannot open the database: ") +
                                   (raw != nullptr ? sqlite3_errmsg(raw) : sqlite3_errstr(rc)));
  }
  return db;
}

void Execute(sqlite3* db, const std::string& path, const std::string& sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message != nullptr ? message : sqlite3_errmsg(db);
    sqlite3_free(message);
    throw InputError(path, "", "cannot update the database (" + text + ")");
  }
}

int64_t Count(sqlite3* db, const std::string& path, const char* sql) {
  Statement s = Prepare(db, path, sql);
  return Step(db, s.get(), path) ? sqlite3_column_int64(s.get(), 0) : 0;
}

// COLMAP's pair id: image_id1 * 2147483647 + image_id2, image_id1 < image_id2.
constexpr int64_t kMaxImages = 2147483647;

std::map<int64_t, std::string> ImageNames(sqlite3* db, const std::string& path) {
  std::map<int64_t, std::string> names;
  Statement s = Prepare(db, path, "SELECT image_id, name FROM images");
  while (Step(db, s.get(), path)) {
    const unsigned char* name = sqlite3_column_text(s.get(), 1);
    names[sqlite3_column_int64(s.get(), 0)] = name != nullptr ? reinterpret_cast<const char*>(name) : "";
  }
  return names;
}

// Calls `visit(name1, name2, inliers, rows)` for every pair COLMAP's verification kept, by pair id
// (image_id1 < image_id2; inliers are rows x 2 keypoint indices, nullptr unless `with_data`).
void ForEachVerifiedPair(const std::string& path, bool with_data,
                         const std::function<void(const std::string&, const std::string&, const uint32_t*, int64_t)>& visit) {
  Database db = Open(path, SQLITE_OPEN_READONLY);
  std::map<int64_t, std::string> names = ImageNames(db.get(), path);
  Statement s = Prepare(db.get(), path, with_data ? "SELECT pair_id, rows, cols, data FROM two_view_geometries "
                                                    "WHERE rows > 0 AND config >= 2 ORDER BY pair_id"
                                                  : "SELECT pair_id FROM two_view_geometries "
                                                    "WHERE rows > 0 AND config >= 2 ORDER BY pair_id");
  std::vector<uint32_t> data;
  while (Step(db.get(), s.get(), path)) {
    const int64_t id = sqlite3_column_int64(s.get(), 0);
    const std::string& a = names[id / kMaxImages];
    const std::string& b = names[id % kMaxImages];
    if (!with_data) {
      visit(a, b, nullptr, 0);
      continue;
    }
    const int64_t rows = sqlite3_column_int64(s.get(), 1), cols = sqlite3_column_int64(s.get(), 2);
    const void* blob = sqlite3_column_blob(s.get(), 3);
    const int64_t bytes = sqlite3_column_bytes(s.get(), 3);
    if (cols != 2 || bytes != rows * cols * 4 || blob == nullptr) {
      throw InputError(path, "", "two_view_geometries pair " + std::to_string(id) + ": " + std::to_string(rows) + " x " +
                                     std::to_string(cols) + " inliers in a blob of " + std::to_string(bytes) + " bytes");
    }
    data.resize(static_cast<size_t>(rows * 2));
    std::memcpy(data.data(), blob, static_cast<size_t>(bytes));
    visit(a, b, data.data(), rows);
  }
}

}  // namespace

size_t CountVerifiedPairs(const std::string& path) {
  Database db = Open(path, SQLITE_OPEN_READONLY);
  return static_cast<size_t>(
      Count(db.get(), path, "SELECT COUNT(*) FROM two_view_geometries WHERE rows > 0 AND config >= 2"));
}

std::set<std::pair<std::string, std::string>> VerifiedPairNames(const std::string& path) {
  std::set<std::pair<std::string, std::string>> pairs;
  ForEachVerifiedPair(path, false, [&](const std::string& a, const std::string& b, const uint32_t*, int64_t) {
    pairs.insert(b < a ? std::make_pair(b, a) : std::make_pair(a, b));
  });
  return pairs;
}

std::set<std::pair<std::string, std::string>> MatchedPairNames(const std::string& path) {
  Database db = Open(path, SQLITE_OPEN_READONLY);
  std::map<int64_t, std::string> names = ImageNames(db.get(), path);
  std::set<std::pair<std::string, std::string>> pairs;
  Statement s = Prepare(db.get(), path, "SELECT pair_id FROM matches");
  while (Step(db.get(), s.get(), path)) {
    const int64_t id = sqlite3_column_int64(s.get(), 0);
    const std::string& a = names[id / kMaxImages];
    const std::string& b = names[id % kMaxImages];
    pairs.insert(b < a ? std::make_pair(b, a) : std::make_pair(a, b));
  }
  return pairs;
}

void RemoveMatches(const std::string& path, const std::set<std::pair<std::string, std::string>>& pairs) {
  Database db = Open(path, SQLITE_OPEN_READWRITE);
  std::map<std::string, int64_t> ids;
  for (const auto& [id, name] : ImageNames(db.get(), path)) ids[name] = id;
  Execute(db.get(), path, "BEGIN IMMEDIATE");
  try {
    Statement matches = Prepare(db.get(), path, "DELETE FROM matches WHERE pair_id = ?");
    Statement geometries = Prepare(db.get(), path, "DELETE FROM two_view_geometries WHERE pair_id = ?");
    for (const auto& [a, b] : pairs) {
      const auto ia = ids.find(a), ib = ids.find(b);
      if (ia == ids.end() || ib == ids.end() || ia->second == ib->second) continue;
      const int64_t lo = std::min(ia->second, ib->second), hi = std::max(ia->second, ib->second);
      for (sqlite3_stmt* statement : {matches.get(), geometries.get()}) {
        sqlite3_bind_int64(statement, 1, lo * kMaxImages + hi);
        Step(db.get(), statement, path);
        sqlite3_reset(statement);
      }
    }
  } catch (...) {
    sqlite3_exec(db.get(), "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  Execute(db.get(), path, "COMMIT");
}

std::vector<PairMatches> ReadVerifiedMatches(const std::string& path,
                                             const std::function<bool(const std::string&, const std::string&)>& want) {
  std::vector<PairMatches> pairs;
  ForEachVerifiedPair(path, true, [&](const std::string& a, const std::string& b, const uint32_t* data, int64_t rows) {
    if (want && !want(a, b)) return;
    PairMatches m{a, b, {}};
    m.matches.reserve(static_cast<size_t>(rows));
    for (int64_t r = 0; r < rows; ++r) m.matches.push_back({data[2 * r], data[2 * r + 1]});
    pairs.push_back(std::move(m));
  });
  return pairs;
}

void ClearMatches(const std::string& path) {
  Database db = Open(path, SQLITE_OPEN_READWRITE);
  Execute(db.get(), path, "BEGIN IMMEDIATE; DELETE FROM matches; DELETE FROM two_view_geometries; COMMIT;");
}

bool RenumberImagesByName(const std::string& path) {
  Database db = Open(path, SQLITE_OPEN_READWRITE);
  if (Count(db.get(), path, "SELECT COUNT(*) FROM matches") > 0 ||
      Count(db.get(), path, "SELECT COUNT(*) FROM two_view_geometries") > 0) {
    throw InputError(path, "", "holds matches already; images can be renumbered only before matching");
  }
  struct Row {
    int64_t image_id, camera_id;
    std::string name;
  };
  std::vector<Row> rows;
  {
    Statement s = Prepare(db.get(), path, "SELECT image_id, camera_id, name FROM images ORDER BY name");
    while (Step(db.get(), s.get(), path)) {
      const unsigned char* name = sqlite3_column_text(s.get(), 2);
      rows.push_back({sqlite3_column_int64(s.get(), 0), sqlite3_column_int64(s.get(), 1),
                      name != nullptr ? reinterpret_cast<const char*>(name) : ""});
    }
  }
  std::vector<int64_t> cameras;
  {
    Statement s = Prepare(db.get(), path, "SELECT camera_id FROM cameras ORDER BY camera_id");
    while (Step(db.get(), s.get(), path)) cameras.push_back(sqlite3_column_int64(s.get(), 0));
  }
  // New camera ids: by first use in name order, then the unused ones in their old order.
  std::map<int64_t, int64_t> camera_ids;
  for (const Row& r : rows) {
    if (std::find(cameras.begin(), cameras.end(), r.camera_id) == cameras.end()) {
      throw InputError(path, "", "image " + r.name + " names camera " + std::to_string(r.camera_id) +
                                     ", which is not in the cameras table");
    }
    camera_ids.emplace(r.camera_id, static_cast<int64_t>(camera_ids.size()) + 1);
  }
  for (const int64_t c : cameras) camera_ids.emplace(c, static_cast<int64_t>(camera_ids.size()) + 1);
  bool changed = false;
  for (size_t i = 0; i < rows.size(); ++i) changed |= rows[i].image_id != static_cast<int64_t>(i) + 1;
  for (const auto& [old_id, new_id] : camera_ids) changed |= old_id != new_id;
  if (!changed) return false;
  // Two steps, through ids above every old and new one, so that no key collides on the way
  // (COLMAP's schema allows ids 0 .. 2^31 - 2 only).
  int64_t top = static_cast<int64_t>(std::max(rows.size(), camera_ids.size()));
  for (const Row& r : rows) top = std::max(top, r.image_id);
  for (const int64_t c : cameras) top = std::max(top, c);
  const std::string shift = std::to_string(top + 1);
  if (2 * top + 2 >= (int64_t{1} << 31) - 1) throw InputError(path, "", "image or camera ids too large to renumber");
  std::string sql = "BEGIN IMMEDIATE;";
  for (const char* table : {"images", "keypoints", "descriptors"}) {
    sql += std::string("UPDATE ") + table + " SET image_id = image_id + " + shift + ";";
  }
  sql += "UPDATE cameras SET camera_id = camera_id + " + shift + "; UPDATE images SET camera_id = camera_id + " +
         shift + ";";
  for (size_t i = 0; i < rows.size(); ++i) {
    const std::string from = std::to_string(rows[i].image_id + top + 1), to = std::to_string(i + 1);
    for (const char* table : {"images", "keypoints", "descriptors"}) {
      sql += std::string("UPDATE ") + table + " SET image_id = " + to + " WHERE image_id = " + from + ";";
    }
  }
  for (const auto& [old_id, new_id] : camera_ids) {
    const std::string from = std::to_string(old_id + top + 1), to = std::to_string(new_id);
    sql += "UPDATE cameras SET camera_id = " + to + " WHERE camera_id = " + from + ";";
    sql += "UPDATE images SET camera_id = " + to + " WHERE camera_id = " + from + ";";
  }
  sql += "COMMIT;";
  try {
    Execute(db.get(), path, sql);
  } catch (const InputError&) {
    sqlite3_exec(db.get(), "ROLLBACK;", nullptr, nullptr, nullptr);
    throw;
  }
  return true;
}

std::vector<DatabaseImage> ReadColmapDescriptors(const std::string& path) {
  Database db = Open(path, SQLITE_OPEN_READONLY);
  std::map<int64_t, std::pair<int64_t, int64_t>> cameras;  // id -> width, height
  {
    Statement s = Prepare(db.get(), path, "SELECT camera_id, width, height FROM cameras");
    while (Step(db.get(), s.get(), path)) {
      cameras[sqlite3_column_int64(s.get(), 0)] = {sqlite3_column_int64(s.get(), 1), sqlite3_column_int64(s.get(), 2)};
    }
  }
  std::map<int64_t, DatabaseImage> images;
  {
    Statement s = Prepare(db.get(), path, "SELECT image_id, name, camera_id FROM images");
    while (Step(db.get(), s.get(), path)) {
      DatabaseImage image;
      image.image_id = sqlite3_column_int64(s.get(), 0);
      const unsigned char* name = sqlite3_column_text(s.get(), 1);
      image.name = name != nullptr ? reinterpret_cast<const char*>(name) : "";
      image.camera_id = sqlite3_column_int64(s.get(), 2);
      const auto camera = cameras.find(image.camera_id);
      if (camera == cameras.end()) {
        throw InputError(path, "", "image " + image.name + " names camera " + std::to_string(image.camera_id) +
                                       ", which is not in the cameras table");
      }
      image.width = camera->second.first;
      image.height = camera->second.second;
      images[image.image_id] = std::move(image);
    }
  }
  // One blob table: rows x cols elements of `element_bytes` each, checked.
  const auto read_blobs = [&](const char* table, int64_t element_bytes, const auto& store) {
    Statement s = Prepare(db.get(), path, (std::string("SELECT image_id, rows, cols, data FROM ") + table).c_str());
    while (Step(db.get(), s.get(), path)) {
      const int64_t id = sqlite3_column_int64(s.get(), 0);
      const int64_t rows = sqlite3_column_int64(s.get(), 1), cols = sqlite3_column_int64(s.get(), 2);
      const std::string where = std::string(table) + " of image_id " + std::to_string(id);
      auto it = images.find(id);
      if (it == images.end()) throw InputError(path, "", where + ": no such image in the images table");
      if (rows < 0 || cols < 0 || rows > (int64_t{1} << 31) || cols > 1024) {
        throw InputError(path, "", where + ": absurd size " + std::to_string(rows) + " x " + std::to_string(cols));
      }
      const void* blob = sqlite3_column_blob(s.get(), 3);
      const int64_t bytes = sqlite3_column_bytes(s.get(), 3);
      if (bytes != rows * cols * element_bytes || (bytes > 0 && blob == nullptr)) {
        throw InputError(path, "", where + ": the blob holds " + std::to_string(bytes) + " bytes, not rows x cols x " +
                                       std::to_string(element_bytes) + " = " + std::to_string(rows * cols * element_bytes));
      }
      store(&it->second, rows, cols, static_cast<const uint8_t*>(blob), where);
    }
  };
  read_blobs("descriptors", 1, [&](DatabaseImage* image, int64_t rows, int64_t cols, const uint8_t* data,
                                   const std::string& where) {
    if (rows > 0 && cols != kSiftDimensions) {
      throw InputError(path, "", where + ": " + std::to_string(rows) + " x " + std::to_string(cols) +
                                     "; expected 128-byte SIFT descriptors");
    }
    image->rows = rows;
    image->descriptors.assign(data, data + rows * cols);
  });
  read_blobs("keypoints", 4, [&](DatabaseImage* image, int64_t rows, int64_t cols, const uint8_t* data,
                                 const std::string& where) {
    if (rows > 0 && cols < 2) throw InputError(path, "", where + ": " + std::to_string(cols) + " columns, fewer than x, y");
    image->xy.resize(static_cast<size_t>(2 * rows));
    image->scale.assign(static_cast<size_t>(rows), 0.0f);
    for (int64_t r = 0; r < rows; ++r) {
      float f[6] = {0, 0, 0, 0, 0, 0};
      std::memcpy(f, data + 4 * r * cols, static_cast<size_t>(std::min<int64_t>(cols, 6)) * sizeof(float));
      image->xy[2 * r] = f[0];
      image->xy[2 * r + 1] = f[1];
      // COLMAP's keypoint rows: x y, x y scale orientation, or x y and the affine shape a11 a12 a21 a22.
      if (cols == 4) image->scale[r] = f[2];
      if (cols >= 6) image->scale[r] = std::sqrt(std::abs(f[2] * f[5] - f[3] * f[4]));
    }
  });
  for (const auto& [id, image] : images) {
    if (image.xy.size() != static_cast<size_t>(2 * image.rows)) {
      throw InputError(path, "", "image " + image.name + ": " + std::to_string(image.xy.size() / 2) + " keypoints but " +
                                     std::to_string(image.rows) + " descriptors");
    }
  }
  std::vector<DatabaseImage> out;
  out.reserve(images.size());
  for (auto& [id, image] : images) out.push_back(std::move(image));
  return out;
}

}  // namespace candi::photogrammetry
