#include "core/point_cloud.h"

#include <algorithm>
#include <array>
#include <limits>

#include "core/check.h"
#include "core/parallel.h"

namespace candi {

int PointSchema::ScalarIndex(const std::string& name) const {
  for (size_t i = 0; i < scalars.size(); ++i) {
    if (scalars[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

bool PointSchema::operator==(const PointSchema& o) const {
  return colors == o.colors && alphas == o.alphas && normals == o.normals && layers == o.layers &&
         scalars == o.scalars && position_type == o.position_type;
}

void PointCloud::SetSchema(const PointSchema& new_schema) {
  CANDI_CHECK(!new_schema.alphas || new_schema.colors) << "alphas need colors";
  const size_t n = size();
  std::vector<ScalarField> fields;
  for (const ScalarFieldSpec& spec : new_schema.scalars) {
    ScalarField* existing = FindScalar(spec.name);
    if (existing != nullptr && existing->spec.type == spec.type) {
      fields.push_back(std::move(*existing));
    } else {
      ScalarField field;
      field.spec = spec;
      field.Resize(n);
      if (existing != nullptr) {
        for (size_t i = 0; i < n; ++i) field.Set(i, existing->Get(i));
      }
      fields.push_back(std::move(field));
    }
  }
  scalars = std::move(fields);
  schema = new_schema;
  if (!schema.colors) colors.clear();
  if (!schema.alphas) alphas.clear();
  if (!schema.normals) normals.clear();
  if (!schema.layers) layers.clear();
  Resize(n);
}

void PointCloud::Resize(size_t n) {
  positions.resize(n);
  if (schema.colors) colors.resize(n);
  if (schema.alphas) alphas.resize(n, 255);
  if (schema.normals) normals.resize(n, Eigen::Vector3f::Zero());
  if (schema.layers) layers.resize(n);
  for (ScalarField& f : scalars) f.Resize(n);
}

size_t PointCloud::Keep(const std::vector<uint8_t>& keep) {
  CANDI_CHECK(keep.size() == size()) << keep.size() << " flags for " << size() << " points";
  size_t kept = 0;
  for (size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    if (kept != i) {  // compact every present array
      positions[kept] = positions[i];
      if (schema.colors) colors[kept] = colors[i];
      if (schema.alphas) alphas[kept] = alphas[i];
      if (schema.normals) normals[kept] = normals[i];
      if (schema.layers) layers[kept] = layers[i];
      for (ScalarField& f : scalars) f.Set(kept, f.Get(i));
    }
    ++kept;
  }
  const size_t removed = size() - kept;
  Resize(kept);
  return removed;
}

void PointCloud::Reserve(size_t n) {
  positions.reserve(n);
  if (schema.colors) colors.reserve(n);
  if (schema.alphas) alphas.reserve(n);
  if (schema.normals) normals.reserve(n);
  if (schema.layers) layers.reserve(n);
  for (ScalarField& f : scalars) {
    if (f.spec.type == ScalarType::kFloat32) f.f32.reserve(n); else f.f64.reserve(n);
  }
}

void PointCloud::Clear() { Resize(0); }

int PointCloud::AddScalarField(const std::string& name, ScalarType type) {
  CANDI_CHECK(!name.empty()) << "scalar field name is empty";
  CANDI_CHECK(schema.ScalarIndex(name) < 0) << "scalar field '" << name << "' exists";
  schema.scalars.push_back({name, type});
  ScalarField field;
  field.spec = {name, type};
  field.Resize(size());
  scalars.push_back(std::move(field));
  return static_cast<int>(scalars.size()) - 1;
}

ScalarField* PointCloud::FindScalar(const std::string& name) {
  for (ScalarField& f : scalars) {
    if (f.spec.name == name) return &f;
  }
  return nullptr;
}

const ScalarField* PointCloud::FindScalar(const std::string& name) const {
  return const_cast<PointCloud*>(this)->FindScalar(name);
}

void PointCloud::AppendFrom(const PointCloud& other, size_t i) {
  CANDI_CHECK(other.schema.colors == schema.colors && other.schema.normals == schema.normals &&
              other.schema.alphas == schema.alphas && other.schema.layers == schema.layers &&
              other.schema.scalars == schema.scalars)
      << "AppendFrom: schemas differ";
  if (other.frame == frame) {
    positions.push_back(other.positions[i]);
  } else {
    positions.push_back(frame.ToLocal(other.WorldPosition(i)));
  }
  if (schema.colors) colors.push_back(other.colors[i]);
  if (schema.alphas) alphas.push_back(other.alphas[i]);
  if (schema.normals) normals.push_back(other.normals[i]);
  if (schema.layers) layers.push_back(other.layers[i]);
  for (size_t k = 0; k < scalars.size(); ++k) {
    if (scalars[k].spec.type == ScalarType::kFloat32) {
      scalars[k].f32.push_back(other.scalars[k].f32[i]);
    } else {
      scalars[k].f64.push_back(other.scalars[k].f64[i]);
    }
  }
}

void PointCloud::Append(const PointCloud& other) {
  CANDI_CHECK(other.schema.colors == schema.colors && other.schema.normals == schema.normals &&
              other.schema.alphas == schema.alphas && other.schema.layers == schema.layers &&
              other.schema.scalars == schema.scalars)
      << "Append: schemas differ";
  const size_t n = size();
  if (other.frame == frame) {
    positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  } else {
    positions.reserve(n + other.size());
    for (size_t i = 0; i < other.size(); ++i) positions.push_back(frame.ToLocal(other.WorldPosition(i)));
  }
  auto append = [](auto& dst, const auto& src) { dst.insert(dst.end(), src.begin(), src.end()); };
  if (schema.colors) append(colors, other.colors);
  if (schema.alphas) append(alphas, other.alphas);
  if (schema.normals) append(normals, other.normals);
  if (schema.layers) append(layers, other.layers);
  for (size_t k = 0; k < scalars.size(); ++k) {
    append(scalars[k].f32, other.scalars[k].f32);
    append(scalars[k].f64, other.scalars[k].f64);
  }
}

Box3d PointCloud::LocalBounds() const {
  // Blocks in parallel, each with local accumulators (the compiler keeps them in registers; Box3d
  // members may alias the data); min and max do not depend on the order they are combined in.
  constexpr size_t kBlock = size_t{1} << 16;
  const size_t n = positions.size(), blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::array<double, 6>> part(blocks);
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[3] = {-lo[0], -lo[1], -lo[2]};
    const Eigen::Vector3d* p = positions.data() + b * kBlock;
    const size_t m = std::min(kBlock, n - b * kBlock);
    for (size_t i = 0; i < m; ++i) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = p[i][k] < lo[k] ? p[i][k] : lo[k];
        hi[k] = p[i][k] > hi[k] ? p[i][k] : hi[k];
      }
    }
    part[b] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  });
  Box3d box;
  for (size_t b = 0; b < blocks; ++b) {
    for (int k = 0; k < 3; ++k) {
      if (b == 0 || part[b][k] < box.min[k]) box.min[k] = part[b][k];
      if (b == 0 || part[b][3 + k] > box.max[k]) box.max[k] = part[b][3 + k];
    }
  }
  return box;
}

void PointCloud::Rebase(const LocalFrame& new_frame) {
  if (new_frame == frame) return;
  // (local + old) - new, evaluated as world then local so integer shifts stay exact.
  for (Eigen::Vector3d& p : positions) p = (p + frame.origin) - new_frame.origin;
  frame = new_frame;
}

void PointCloud::CheckConsistent() const {
  const size_t n = size();
  CANDI_CHECK(!schema.colors || colors.size() == n) << "colors " << colors.size() << " != " << n;
  CANDI_CHECK(!schema.alphas || alphas.size() == n) << "alphas " << alphas.size() << " != " << n;
  CANDI_CHECK(!schema.normals || normals.size() == n) << "normals " << normals.size() << " != " << n;
  CANDI_CHECK(!schema.layers || layers.size() == n) << "layers " << layers.size() << " != " << n;
  CANDI_CHECK(scalars.size() == schema.scalars.size()) << "scalar fields differ from schema";
  for (size_t k = 0; k < scalars.size(); ++k) {
    CANDI_CHECK(scalars[k].spec == schema.scalars[k]) << "scalar field " << k << " differs";
    CANDI_CHECK(scalars[k].size() == n) << "scalar field '" << scalars[k].spec.name << "' size";
  }
}

}  // namespace candi
