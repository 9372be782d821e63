#include "io/ply/ply_columns.h"

#include <cstring>

namespace candi::io::ply {

void DecodeInto(const Column& c, const uint8_t* records, size_t stride, size_t n, bool swap, size_t first,
                PointCloud* chunk) {
  const uint8_t* base = records + c.offset;
  auto run = [&](auto store) { DecodeColumn(c.type, base, stride, n, swap, store); };
  switch (c.role) {
    case Role::kSkip: break;
    case Role::kX: case Role::kY: case Role::kZ: {
      const int k = c.role == Role::kX ? 0 : c.role == Role::kY ? 1 : 2;
      Eigen::Vector3d* p = chunk->positions.data() + first;
      run([p, k](size_t i, auto v) { p[i][k] = static_cast<double>(v); });
      break;
    }
    case Role::kNx: case Role::kNy: case Role::kNz: {
      const int k = c.role == Role::kNx ? 0 : c.role == Role::kNy ? 1 : 2;
      Eigen::Vector3f* nrm = chunk->normals.data() + first;
      run([nrm, k](size_t i, auto v) { nrm[i][k] = static_cast<float>(v); });
      break;
    }
    case Role::kScalar: {
      ScalarField& field = chunk->scalars[c.scalar];
      if (field.spec.type == ScalarType::kFloat32) {
        float* out = field.f32.data() + first;
        run([out](size_t i, auto v) { out[i] = static_cast<float>(v); });
      } else {
        double* out = field.f64.data() + first;
        run([out](size_t i, auto v) { out[i] = static_cast<double>(v); });
      }
      break;
    }
    case Role::kR: case Role::kG: case Role::kB: case Role::kA: {
      // Byte offset of the channel inside Rgb8 (r, g, b), or the alpha array.
      uint8_t* out = c.role == Role::kA ? chunk->alphas.data() + first : &(chunk->colors.data() + first)->r;
      const size_t step = c.role == Role::kA ? 1 : sizeof(Rgb8);
      out += c.role == Role::kG ? 1 : c.role == Role::kB ? 2 : 0;
      const Type type = c.type;
      if (type == Type::kUint8) {
        for (size_t i = 0; i < n; ++i) out[i * step] = base[i * stride];
      } else {
        run([out, step, type](size_t i, auto v) { out[i * step] = ToColor(v, type); });
      }
      break;
    }
    default:
      run([&c, chunk, first](size_t i, auto v) { Assign(c, first + i, v, chunk); });
  }
}

namespace {

template <typename T>
void DecodeXyzRows(const uint8_t* base, size_t stride, size_t n, Eigen::Vector3d* out) {
  for (size_t i = 0; i < n; ++i) {
    T xyz[3];
    std::memcpy(xyz, base + i * stride, sizeof(xyz));
    out[i] = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  }
}

}  // namespace

void DecodeFastPaths(const std::vector<Column>& columns, const uint8_t* records, size_t stride,
                     size_t n, size_t first, PointCloud* chunk, std::vector<bool>* done) {
  auto find = [&](Role role) -> int {
    for (size_t k = 0; k < columns.size(); ++k) if (columns[k].role == role) return static_cast<int>(k);
    return -1;
  };
  auto adjacent = [&](int a, int b, int c, Type type) {
    const size_t size = ply::TypeSize(type);
    return a >= 0 && b >= 0 && c >= 0 && columns[a].type == type && columns[b].type == type &&
           columns[c].type == type && columns[b].offset == columns[a].offset + size &&
           columns[c].offset == columns[a].offset + 2 * size;
  };
  const int x = find(Role::kX), y = find(Role::kY), z = find(Role::kZ);
  if (adjacent(x, y, z, Type::kFloat32)) {
    DecodeXyzRows<float>(records + columns[x].offset, stride, n, chunk->positions.data() + first);
  } else if (adjacent(x, y, z, Type::kFloat64)) {
    DecodeXyzRows<double>(records + columns[x].offset, stride, n, chunk->positions.data() + first);
  }
  if (adjacent(x, y, z, Type::kFloat32) || adjacent(x, y, z, Type::kFloat64)) {
    (*done)[x] = (*done)[y] = (*done)[z] = true;
  }
  const int r = find(Role::kR), g = find(Role::kG), b = find(Role::kB);
  if (adjacent(r, g, b, Type::kUint8)) {
    const uint8_t* base = records + columns[r].offset;
    Rgb8* out = chunk->colors.data() + first;
    for (size_t i = 0; i < n; ++i) std::memcpy(&out[i], base + i * stride, 3);
    (*done)[r] = (*done)[g] = (*done)[b] = true;
  }
}

}  // namespace candi::io::ply
