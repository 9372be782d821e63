// Private to io/ply: a PLY vertex property as a column of the reader's records, and its
// decoding into a PointCloud, one value (ASCII) or a block of binary records at a time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/binary_file.h"
#include "core/point_cloud.h"
#include "io/ply/ply_header.h"

namespace candi::io::ply {

// What a vertex property becomes in the PointCloud.
enum class Role { kSkip, kX, kY, kZ, kR, kG, kB, kA, kNx, kNy, kNz, kLayer, kScalar };

struct Column {
  Role role = Role::kSkip;
  Type type = Type::kFloat32;
  int scalar = -1;    // index into the cloud's scalar fields (kScalar)
  size_t offset = 0;  // byte offset inside the compact record (binary)
};

template <typename T, typename F>
void LoopColumn(const uint8_t* base, size_t stride, size_t n, bool swap, F& f) {
  if (swap) {
    for (size_t i = 0; i < n; ++i) f(i, ByteSwap(LoadLE<T>(base + i * stride)));
  } else {
    for (size_t i = 0; i < n; ++i) f(i, LoadLE<T>(base + i * stride));
  }
}

// Calls f(i, value) for the n values of one column, dispatching on the type once per column.
template <typename F>
void DecodeColumn(Type type, const uint8_t* base, size_t stride, size_t n, bool swap, F&& f) {
  switch (type) {
    case Type::kInt8: LoopColumn<int8_t>(base, stride, n, swap, f); break;
    case Type::kUint8: LoopColumn<uint8_t>(base, stride, n, swap, f); break;
    case Type::kInt16: LoopColumn<int16_t>(base, stride, n, swap, f); break;
    case Type::kUint16: LoopColumn<uint16_t>(base, stride, n, swap, f); break;
    case Type::kInt32: LoopColumn<int32_t>(base, stride, n, swap, f); break;
    case Type::kUint32: LoopColumn<uint32_t>(base, stride, n, swap, f); break;
    case Type::kFloat32: LoopColumn<float>(base, stride, n, swap, f); break;
    case Type::kFloat64: LoopColumn<double>(base, stride, n, swap, f); break;
  }
}

// Colour channel from a property of any type: uchar as is, ushort scaled down, floats in [0, 1].
template <typename V>
uint8_t ToColor(V v, Type type) {
  double x = static_cast<double>(v);
  if (type == Type::kUint16) x = x / 257.0;
  else if (type == Type::kFloat32 || type == Type::kFloat64) x = x * 255.0;
  if (!(x > 0.0)) return 0;
  return x >= 255.0 ? 255 : static_cast<uint8_t>(x + 0.5);
}

inline uint16_t ToLayer(double v) {
  if (!(v > 0.0)) return 0;
  return v >= 65535.0 ? 65535 : static_cast<uint16_t>(v + 0.5);
}

// Stores value v of column c into point i of chunk.
template <typename V>
void Assign(const Column& c, size_t i, V v, PointCloud* chunk) {
  switch (c.role) {
    case Role::kSkip: break;
    case Role::kX: chunk->positions[i][0] = static_cast<double>(v); break;
    case Role::kY: chunk->positions[i][1] = static_cast<double>(v); break;
    case Role::kZ: chunk->positions[i][2] = static_cast<double>(v); break;
    case Role::kR: chunk->colors[i].r = ToColor(v, c.type); break;
    case Role::kG: chunk->colors[i].g = ToColor(v, c.type); break;
    case Role::kB: chunk->colors[i].b = ToColor(v, c.type); break;
    case Role::kA: chunk->alphas[i] = ToColor(v, c.type); break;
    case Role::kNx: chunk->normals[i][0] = static_cast<float>(v); break;
    case Role::kNy: chunk->normals[i][1] = static_cast<float>(v); break;
    case Role::kNz: chunk->normals[i][2] = static_cast<float>(v); break;
    case Role::kLayer: chunk->layers[i] = ToLayer(static_cast<double>(v)); break;
    case Role::kScalar: chunk->scalars[c.scalar].Set(i, static_cast<double>(v)); break;
  }
}

// Decodes column c of n records (stride bytes apart, byte-swapped when `swap`) into the chunk's
// points [first, first + n). The role switch sits outside the loops: each branch instantiates a
// tight loop per type.
void DecodeInto(const Column& c, const uint8_t* records, size_t stride, size_t n, bool swap,
                size_t first, PointCloud* chunk);

// The common layouts (x y z adjacent, same type, little endian; red green blue adjacent uchar)
// decoded record by record in one pass: the per-column loops, with runtime strides, cost several
// times more. Marks the columns it decoded in `done`.
void DecodeFastPaths(const std::vector<Column>& columns, const uint8_t* records, size_t stride,
                     size_t n, size_t first, PointCloud* chunk, std::vector<bool>* done);

}  // namespace candi::io::ply
