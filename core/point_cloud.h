// PointCloud: a struct of arrays holding positions in double and optional per-point attributes.
//
// Positions are in the cloud's local frame (metres): x_in_world = frame.ToWorld(positions[i]).
// Which optional attributes exist is recorded in `schema`; every present attribute array has
// exactly size() entries (CheckConsistent verifies). Colours are 8-bit sRGB; normals are unit
// vectors in float; scalar fields are named float (or double, where float would lose digits,
// e.g. GPS time); `layers` holds a layer id per point. Not thread-safe for writes.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/box.h"
#include "core/local_frame.h"

namespace candi {

struct Rgb8 {  // packed: three bytes (static_assert below)
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb8& o) const { return r == o.r && g == o.g && b == o.b; }
};

static_assert(sizeof(Rgb8) == 3, "Rgb8 must be three packed bytes");

enum class ScalarType : uint8_t { kFloat32, kFloat64 };

struct ScalarFieldSpec {
  std::string name;  // without a "scalar_" prefix; unique within a cloud
  ScalarType type = ScalarType::kFloat32;
  bool operator==(const ScalarFieldSpec& o) const { return name == o.name && type == o.type; }
};

struct PointSchema {
  bool colors = false;
  bool alphas = false;   // only with colors
  bool normals = false;
  bool layers = false;
  std::vector<ScalarFieldSpec> scalars;
  // Precision the positions were stored with at the source; writers keep it (lossless) unless a
  // shift or the target format asks otherwise.
  ScalarType position_type = ScalarType::kFloat64;

  int ScalarIndex(const std::string& name) const;  // -1 when absent
  bool operator==(const PointSchema& o) const;
  bool operator!=(const PointSchema& o) const { return !(*this == o); }
};

// One scalar field's values; exactly one of f32/f64 is used, according to spec.type.
struct ScalarField {
  ScalarFieldSpec spec;
  std::vector<float> f32;
  std::vector<double> f64;

  size_t size() const { return spec.type == ScalarType::kFloat32 ? f32.size() : f64.size(); }
  double Get(size_t i) const { return spec.type == ScalarType::kFloat32 ? f32[i] : f64[i]; }
  void Set(size_t i, double v) {
    if (spec.type == ScalarType::kFloat32) f32[i] = static_cast<float>(v); else f64[i] = v;
  }
  void Resize(size_t n) {
    if (spec.type == ScalarType::kFloat32) f32.resize(n); else f64.resize(n);
  }
};

// Format-specific metadata that a lossless rewrite needs (LAS scale/offset, VLRs, ...).
struct LasVlr {
  std::string user_id;       // up to 16 bytes
  uint16_t record_id = 0;
  std::string description;   // up to 32 bytes
  std::string data;          // payload bytes
  bool extended = false;     // EVLR (LAS 1.4), stored after the points
};

struct LasMetadata {
  bool present = false;  // true when the cloud came from a LAS file
  uint8_t version_minor = 2;
  uint8_t point_format = 0;
  Eigen::Vector3d scale = Eigen::Vector3d::Constant(0.001);
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  uint16_t file_source_id = 0;
  uint16_t global_encoding = 0;
  std::string system_identifier, generating_software;
  uint16_t creation_day = 0, creation_year = 0;
  bool color_16bit = true;  // colours were full 16-bit in the file (false: 8-bit values stored)
  std::vector<LasVlr> vlrs;  // VLRs and EVLRs, in file order (extra-bytes VLRs excluded)
};

struct PointCloudMeta {
  std::vector<std::string> comments;  // free-text comments (PLY comment lines)
  // The coordinate reference system the file states for its world coordinates, as found: OGC
  // WKT (LAS WKT VLR, E57 coordinateMetadata), "EPSG:n" (LAS GeoTIFF keys), or any string PROJ
  // accepts. Empty: the file states none.
  std::string crs;
  LasMetadata las;
};

struct PointCloud {
  PointSchema schema;
  LocalFrame frame;
  PointCloudMeta meta;

  std::vector<Eigen::Vector3d> positions;  // local frame, metres
  std::vector<Rgb8> colors;                // schema.colors
  std::vector<uint8_t> alphas;             // schema.alphas
  std::vector<Eigen::Vector3f> normals;    // schema.normals
  std::vector<uint16_t> layers;            // schema.layers
  std::vector<ScalarField> scalars;        // one per schema.scalars, same order

  size_t size() const { return positions.size(); }
  bool empty() const { return positions.empty(); }

  // Makes the attribute arrays match `schema` (adding or dropping arrays), keeping size().
  void SetSchema(const PointSchema& new_schema);
  void Resize(size_t n);   // every present array to n entries
  void Reserve(size_t n);
  // Keeps the points whose flag is non-zero (in order; keep.size() == size()); returns how many
  // were removed.
  size_t Keep(const std::vector<uint8_t>& keep);
  void Clear();            // size 0; schema, frame and meta kept
  // Adds a scalar field (zero-filled) and returns its index; throws if the name exists.
  int AddScalarField(const std::string& name, ScalarType type = ScalarType::kFloat32);
  ScalarField* FindScalar(const std::string& name);
  const ScalarField* FindScalar(const std::string& name) const;

  // Appends point i of `other` (same schema; positions re-expressed in this cloud's frame).
  void AppendFrom(const PointCloud& other, size_t i);
  // Appends all points of `other` (same schema), converting frames.
  void Append(const PointCloud& other);

  Eigen::Vector3d WorldPosition(size_t i) const { return frame.ToWorld(positions[i]); }
  Box3d LocalBounds() const;
  Box3d WorldBounds() const { return LocalBounds().Translated(frame.origin); }
  // Re-expresses positions in `new_frame` (world positions unchanged; exact for integer shifts).
  void Rebase(const LocalFrame& new_frame);

  // Throws InternalError when an attribute array's size differs from size().
  void CheckConsistent() const;
};

}  // namespace candi
