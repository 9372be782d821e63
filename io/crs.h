// Coordinate reference systems, through PROJ (Debian's libproj): naming, comparing and
// transforming between the CRSs point files and scenes state. candi has no projection code of
// its own; every CRS string is anything PROJ accepts ("EPSG:32749", OGC WKT 1 or 2, PROJJSON,
// a PROJ string).
//
// Axis order: coordinates are always (easting, northing, height) or (longitude, latitude,
// height) in degrees — the order point files store them in (LAS X is the easting or longitude) —
// whatever order the CRS's authority defines (PROJ's "normalized for visualization").
// Heights pass through unchanged unless both CRSs are 3-D (e.g. EPSG:4979 to a compound CRS).
//
// Failure: a string PROJ cannot read throws InputError(where, "", "...PROJ's reason"); a
// transform PROJ cannot build likewise. Thread-safety: a CrsTransform is used by one thread at a
// time; the free functions are thread-safe (each uses its own PROJ context).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace candi::io {

struct CrsDescription {
  std::string name;     // PROJ's name, e.g. "WGS 84 / UTM zone 49S"
  std::string id;       // "EPSG:32749" when PROJ identifies it (confidence >= 70 %), else ""
  std::string type;     // "projected", "geographic 2D", "geographic 3D", "compound", ...
  bool geographic = false;  // degrees of longitude/latitude
};

// Throws InputError naming `where` (a file or a scene's JSON path) when PROJ cannot read it.
CrsDescription DescribeCrs(const std::string& definition, const std::string& where);
// "WGS 84 / UTM zone 49S (EPSG:32749)"; the definition itself (shortened) when PROJ cannot read it.
std::string CrsLabel(const std::string& definition);
// True when PROJ finds the two equivalent (axis order of geographic CRSs aside).
bool SameCrs(const std::string& a, const std::string& b);
// OGC WKT 1 (GDAL flavour, what LAS readers expect) of the CRS; the definition unchanged when it
// is WKT already and PROJ cannot write it as WKT 1.
std::string CrsAsWkt1(const std::string& definition, const std::string& where);

class CrsTransform {
 public:
  // The best transformation PROJ knows from `from` to `to` (where: for error messages).
  CrsTransform(const std::string& from, const std::string& to, const std::string& where);
  ~CrsTransform();
  CrsTransform(const CrsTransform&) = delete;
  CrsTransform& operator=(const CrsTransform&) = delete;

  // Transforms in place. Points PROJ cannot transform (outside the domain) become NaN; the
  // return value counts them.
  size_t Apply(std::vector<Eigen::Vector3d>* points) const;
  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const;
  // PROJ's description of the operation it used last (before any Apply: the one it would use
  // for the middle of the source CRS's area of use) and its stated accuracy (metres; < 0: unknown).
  const std::string& operation() const { return operation_; }
  double accuracy() const { return accuracy_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  void DescribeLastOperation() const;
  mutable std::string operation_;
  mutable double accuracy_ = -1;
};

}  // namespace candi::io
