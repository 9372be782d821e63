#include "io/las/las_crs_internal.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/binary_file.h"

namespace candi::io {
namespace {

// A GeoKeyDirectory (GeoTIFF 1.0): header, then (id, location 0, count 1, value) per key.
LasVlr GeoKeys(const std::vector<std::pair<uint16_t, uint16_t>>& keys) {
  std::vector<uint16_t> shorts = {1, 1, 0, static_cast<uint16_t>(keys.size())};
  for (const auto& [id, value] : keys) shorts.insert(shorts.end(), {id, 0, 1, value});
  LasVlr vlr;
  vlr.user_id = "LASF_Projection";
  vlr.record_id = 34735;
  vlr.data.resize(2 * shorts.size());
  for (size_t i = 0; i < shorts.size(); ++i) StoreLE<uint16_t>(reinterpret_cast<uint8_t*>(vlr.data.data()) + 2 * i, shorts[i]);
  return vlr;
}

TEST(LasCrs, GeoTiffKeysGiveEpsgCodes) {
  EXPECT_EQ(LasCrsOf({GeoKeys({{1024, 1}, {3072, 32749}})}), "EPSG:32749");
  EXPECT_EQ(LasCrsOf({GeoKeys({{1024, 2}, {2048, 4326}})}), "EPSG:4326");
  EXPECT_EQ(LasCrsOf({GeoKeys({{3072, 26910}, {4096, 5703}})}), "EPSG:26910+5703");
  std::string note;
  EXPECT_EQ(LasCrsOf({GeoKeys({{3072, 32767}})}, &note), "");
  EXPECT_NE(note.find("user-defined"), std::string::npos);
  LasVlr truncated = GeoKeys({{3072, 32749}});
  truncated.data.resize(10);  // promises a key it does not hold
  EXPECT_EQ(LasCrsOf({truncated}, &note), "");
  EXPECT_NE(note.find("malformed"), std::string::npos);
  EXPECT_EQ(LasCrsOf({}), "");
}

TEST(LasCrs, WktIsPreferredAndRoundTrips) {
  const LasVlr wkt = LasWktVlr("GEOGCS[\"WGS 84\"]");
  EXPECT_EQ(wkt.data.back(), '\0');  // NUL-terminated, as LAS 1.4 asks
  EXPECT_EQ(LasCrsOf({GeoKeys({{3072, 32749}}), wkt}), "GEOGCS[\"WGS 84\"]");
  EXPECT_TRUE(HasLasCrsRecord({wkt}));
  LasVlr other = wkt;
  other.user_id = "liblas";
  EXPECT_FALSE(HasLasCrsRecord({other}));
}

}  // namespace
}  // namespace candi::io
