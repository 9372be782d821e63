#include "io/crs.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/check.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using ::candi::testing::TempDir;

TEST(Crs, DescribesAndComparesThroughProj) {
  const CrsDescription utm = DescribeCrs("EPSG:32749", "test");
  EXPECT_EQ(utm.name, "WGS 84 / UTM zone 49S");
  EXPECT_EQ(utm.id, "EPSG:32749");
  EXPECT_EQ(utm.type, "projected");
  EXPECT_FALSE(utm.geographic);
  EXPECT_TRUE(DescribeCrs("EPSG:4326", "test").geographic);
  const std::string wkt = CrsAsWkt1("EPSG:32749", "test");
  EXPECT_EQ(wkt.find('\n'), std::string::npos);  // one line
  EXPECT_EQ(DescribeCrs(wkt, "test").id, "EPSG:32749");  // identified again from the WKT
  EXPECT_TRUE(SameCrs("EPSG:32749", wkt));
  EXPECT_FALSE(SameCrs("EPSG:32749", "EPSG:32750"));
  EXPECT_FALSE(SameCrs("EPSG:32749", "nonsense"));
  EXPECT_EQ(CrsLabel("EPSG:4326"), "WGS 84 (EPSG:4326)");
  try {
    DescribeCrs("EPSG:999999", "scene.json");
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("PROJ cannot read the CRS 'EPSG:999999'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(DescribeCrs("", "x"), InputError);
}

TEST(Crs, TransformRoundTripsAndMarksPointsOutsideTheDomain) {
  const CrsTransform to_utm("EPSG:4326", "EPSG:32749", "test"), back("EPSG:32749", "EPSG:4326", "test");
  // Longitude first whatever the authority's axis order; the zone's central meridian is 111 E,
  // where the easting is 500000 m exactly.
  const Eigen::Vector3d central = to_utm.Apply(Eigen::Vector3d(111.0, -7.6, 250.0));
  EXPECT_NEAR(central.x(), 500000.0, 1e-6);
  EXPECT_LT(central.y(), 10000000.0);  // south of the equator: false northing 10^7 m
  EXPECT_EQ(central.z(), 250.0);       // 2-D CRSs: the height passes through
  std::vector<Eigen::Vector3d> points = {{110.2038, -7.6079, 265.0}, {110.2, -7.61, 0.0}, {10.0, 95.0, 0.0}};
  const std::vector<Eigen::Vector3d> original = points;
  EXPECT_EQ(to_utm.Apply(&points), 1u);  // latitude 95 degrees does not exist
  EXPECT_TRUE(std::isnan(points[2].x()));
  EXPECT_FALSE(to_utm.operation().empty());
  points.pop_back();
  back.Apply(&points);
  for (size_t i = 0; i < points.size(); ++i) EXPECT_LT((points[i] - original[i]).norm(), 1e-9);
  EXPECT_THROW(CrsTransform("EPSG:4326", "EPSG:0", "test"), InputError);
}

TEST(Crs, LasAndPlyFilesCarryTheCrs) {
  TempDir dir;
  PointCloud c;
  c.SetSchema(c.schema);
  c.positions = {{416000.5, 9158900.25, 250.0}, {416001.5, 9158901.25, 251.0}};
  c.meta.crs = "EPSG:32749";
  for (const int version : {2, 4}) {
    PointWriteOptions o;
    o.las_version_minor = version;
    const std::string las = dir.File("v" + std::to_string(version) + ".las");
    WritePointCloud(las, c, o);
    const PointCloud back = ReadPointCloud(las);
    EXPECT_TRUE(SameCrs(back.meta.crs, "EPSG:32749")) << back.meta.crs;
    EXPECT_EQ((back.meta.las.global_encoding & 0x10) != 0, version == 4);  // WKT bit, 1.4 only
  }
  // PLY: one comment line, even for a multi-line WKT.
  c.meta.crs = "PROJCS[\"x\",\n  GEOGCS[\"WGS 84\"]]";
  WritePointCloud(dir.File("a.ply"), c);
  EXPECT_EQ(ReadPointCloud(dir.File("a.ply")).meta.crs, "PROJCS[\"x\",   GEOGCS[\"WGS 84\"]]");
  c.meta.crs.clear();
  WritePointCloud(dir.File("none.ply"), c);
  EXPECT_EQ(ReadPointCloud(dir.File("none.ply")).meta.crs, "");
}

}  // namespace
}  // namespace candi::io
