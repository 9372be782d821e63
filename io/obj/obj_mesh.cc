#include "io/obj/obj_mesh.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string_view>

#include "core/check.h"
#include "io/shift_sidecar.h"

namespace candi::io {

namespace {

std::string_view NextToken(std::string_view& rest) {
  size_t b = 0;
  while (b < rest.size() && (rest[b] == ' ' || rest[b] == '\t' || rest[b] == '\r')) ++b;
  size_t e = b;
  while (e < rest.size() && rest[e] != ' ' && rest[e] != '\t' && rest[e] != '\r') ++e;
  const std::string_view token = rest.substr(b, e - b);
  rest = rest.substr(e);
  return token;
}

bool ParseNumber(std::string_view token, double& value) {
  // std::from_chars for double is in GCC 12's libstdc++.
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

}  // namespace

TriMesh ReadObjMesh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot be opened");
  TriMesh mesh;
  PointCloud& v = mesh.vertices;
  std::vector<Rgb8> colours;
  bool all_coloured = true;
  std::string line;
  uint64_t number = 0;
  auto fail = [&](const std::string& what) {
    throw InputError(path, "line " + std::to_string(number), what);
  };
  std::vector<uint32_t> polygon;
  while (std::getline(in, line)) {
    ++number;
    std::string_view rest(line);
    const std::string_view keyword = NextToken(rest);
    if (keyword == "v") {
      double x[7];
      int count = 0;
      for (std::string_view t = NextToken(rest); !t.empty(); t = NextToken(rest)) {
        if (count == 7) fail("a vertex has more than 7 numbers");
        if (!ParseNumber(t, x[count])) fail("'" + std::string(t) + "' is not a number");
        ++count;
      }
      if (count < 3) fail("a vertex needs x y z");
      const Eigen::Vector3d p(x[0], x[1], x[2]);
      if (!p.allFinite()) fail("a vertex position is not finite");
      v.positions.push_back(p);
      if (count == 6 || count == 7) {
        auto channel = [&](double c) {
          return static_cast<uint8_t>(std::lround(std::clamp(c, 0.0, 1.0) * 255.0));
        };
        const int o = count == 7 ? 4 : 3;
        colours.push_back({channel(x[o]), channel(x[o + 1]), channel(x[o + 2])});
      } else {
        all_coloured = false;
      }
    } else if (keyword == "f") {
      polygon.clear();
      for (std::string_view t = NextToken(rest); !t.empty(); t = NextToken(rest)) {
        const std::string_view index_text = t.substr(0, t.find('/'));
        long long index = 0;
        const auto [end, error] =
            std::from_chars(index_text.data(), index_text.data() + index_text.size(), index);
        if (error != std::errc() || end != index_text.data() + index_text.size() || index == 0) {
          fail("'" + std::string(t) + "' is not a vertex index (1-based, or negative: relative)");
        }
        const long long count = static_cast<long long>(v.positions.size());
        const long long zero_based = index > 0 ? index - 1 : count + index;
        if (zero_based < 0 || zero_based >= count) {
          fail("vertex index " + std::to_string(index) + " out of range (" +
               std::to_string(count) + " vertices so far)");
        }
        polygon.push_back(static_cast<uint32_t>(zero_based));
      }
      if (polygon.size() < 3) fail("a face needs at least 3 vertices");
      for (size_t k = 1; k + 1 < polygon.size(); ++k) {
        mesh.faces.push_back({polygon[0], polygon[k], polygon[k + 1]});
      }
    }
  }
  if (in.bad()) throw InputError(path, "", "read error");
  if (all_coloured && !colours.empty()) {
    PointSchema schema = v.schema;
    schema.colors = true;
    v.SetSchema(schema);
    v.colors = colours;
  }
  if (const auto frame = ReadShiftSidecar(path)) v.frame = *frame;
  return mesh;
}

}  // namespace candi::io
