#include "io/las/las_crs_internal.h"

#include <cstring>

#include "core/binary_file.h"

namespace candi::io {

namespace {

constexpr const char* kProjection = "LASF_Projection";
constexpr uint16_t kWktRecord = 2112;
constexpr uint16_t kGeoKeyDirectory = 34735;
constexpr uint16_t kGeographicTypeKey = 2048;
constexpr uint16_t kProjectedCsTypeKey = 3072;
constexpr uint16_t kVerticalCsTypeKey = 4096;
constexpr uint16_t kUserDefined = 32767;

bool IsProjection(const LasVlr& vlr, uint16_t record) {
  return vlr.user_id == kProjection && vlr.record_id == record;
}

std::string Trimmed(const std::string& data) {
  std::string s(data.c_str());  // up to the first NUL
  while (!s.empty() && (s.back() == ' ' || s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

// The value of a short-valued key (TIFFTagLocation 0) of a GeoKeyDirectory, or 0 when absent.
// The directory: a 4-short header (version, revision, minor, number of keys), then 4 shorts a key
// (id, location, count, value).
uint16_t GeoKey(const std::string& data, uint16_t id, bool* malformed) {
  const size_t shorts = data.size() / 2;
  auto at = [&](size_t i) { return LoadLE<uint16_t>(reinterpret_cast<const uint8_t*>(data.data()) + 2 * i); };
  if (shorts < 4) {
    *malformed = true;
    return 0;
  }
  const size_t keys = at(3);
  if (4 + 4 * keys > shorts) *malformed = true;
  for (size_t k = 0; k < keys && 4 + 4 * k + 3 < shorts; ++k) {
    const size_t i = 4 + 4 * k;
    if (at(i) == id && at(i + 1) == 0) return at(i + 3);
  }
  return 0;
}

std::string GeoTiffCrs(const std::string& data, std::string* note) {
  bool malformed = false;
  const uint16_t projected = GeoKey(data, kProjectedCsTypeKey, &malformed);
  const uint16_t geographic = GeoKey(data, kGeographicTypeKey, &malformed);
  const uint16_t vertical = GeoKey(data, kVerticalCsTypeKey, &malformed);
  if (malformed) {
    if (note) *note = "GeoTIFF key directory is malformed; not interpreted";
    return "";
  }
  const uint16_t horizontal = projected != 0 ? projected : geographic;
  if (horizontal == 0 || horizontal == kUserDefined) {
    if (note) *note = "GeoTIFF keys with a user-defined CRS (no EPSG code); not interpreted";
    return "";
  }
  std::string crs = "EPSG:" + std::to_string(horizontal);
  if (vertical != 0 && vertical != kUserDefined) crs += "+" + std::to_string(vertical);
  return crs;
}

}  // namespace

std::string LasCrsOf(const std::vector<LasVlr>& vlrs, std::string* note) {
  if (note) note->clear();
  for (const LasVlr& vlr : vlrs) {
    if (!IsProjection(vlr, kWktRecord)) continue;
    const std::string wkt = Trimmed(vlr.data);
    if (!wkt.empty()) return wkt;
  }
  for (const LasVlr& vlr : vlrs) {
    if (IsProjection(vlr, kGeoKeyDirectory)) return GeoTiffCrs(vlr.data, note);
  }
  return "";
}

bool HasLasCrsRecord(const std::vector<LasVlr>& vlrs) {
  for (const LasVlr& vlr : vlrs) {
    if (IsProjection(vlr, kWktRecord) || IsProjection(vlr, kGeoKeyDirectory)) return true;
  }
  return false;
}

LasVlr LasWktVlr(const std::string& wkt) {
  LasVlr vlr;
  vlr.user_id = kProjection;
  vlr.record_id = kWktRecord;
  vlr.description = "OGC WKT coordinate system";
  vlr.data = wkt + std::string(1, '\0');
  return vlr;
}

}  // namespace candi::io
