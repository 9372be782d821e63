// Writes the small seed inputs of the point, DXF, COLMAP and scene targets with candi's own
// writers and the test fixtures' DXF builder: `fuzz_make_seeds OUT` fills OUT/<target>/
// (fuzz/corpus/ holds its output, committed; a few hundred bytes to a few KiB each; the archive
// seed is hand-made). Multi-file inputs are joined with kFuzzPartSeparator as the harnesses expect.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "fuzz/fuzz_util.h"
#include "io/ply/ply_io.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "tests/util/dxf_text.h"

namespace {

namespace fs = std::filesystem;
using candi::fuzz::kFuzzPartSeparator;
using candi::fuzz::WriteScratchFile;

candi::PointCloud SmallCloud(bool colors, bool normals, bool scalar, size_t n = 5) {
  candi::PointCloud cloud;
  candi::PointSchema schema;
  schema.colors = colors;
  schema.normals = normals;
  cloud.SetSchema(schema);
  if (scalar) cloud.AddScalarField("intensity");
  cloud.Resize(n);
  for (size_t i = 0; i < n; ++i) {
    cloud.positions[i] = {0.5 * i, 1.25 - i, 0.125 * i * i};
    if (colors) cloud.colors[i] = {static_cast<uint8_t>(40 * i), 200, static_cast<uint8_t>(255 - i)};
    if (normals) cloud.normals[i] = {0, 0, 1};
    if (scalar) cloud.scalars[0].Set(i, 3.0 * i);
  }
  return cloud;
}

std::string Read(const std::string& path) { return candi::ReadFileToString(path); }

class Seeds {
 public:
  explicit Seeds(std::string out) : out_(std::move(out)) {}
  void Put(const std::string& target, const std::string& name, const std::string& bytes) {
    fs::create_directories(out_ + "/" + target);
    WriteScratchFile(out_ + "/" + target + "/" + name, bytes);
    std::printf("%s/%s: %zu bytes\n", target.c_str(), name.c_str(), bytes.size());
  }
  std::string Tmp(const std::string& name) const { return candi::fuzz::ScratchDir() + "/" + name; }

 private:
  std::string out_;
};

void PointSeeds(Seeds& seeds) {
  using candi::io::PlyEncoding;
  struct Ply {
    const char* name;
    io::PlyEncoding encoding;
    bool colors, normals, scalar;
  };
  for (const Ply& p : {Ply{"ascii.ply", io::PlyEncoding::kAscii, true, true, true},
                       Ply{"binary_le.ply", io::PlyEncoding::kBinaryLittleEndian, true, false, true},
                       Ply{"binary_be.ply", io::PlyEncoding::kBinaryBigEndian, false, true, false}}) {
    candi::io::PointWriteOptions options;
    options.ply_encoding = p.encoding;
    candi::PointCloud cloud = SmallCloud(p.colors, p.normals, p.scalar);
    if (p.encoding == io::PlyEncoding::kBinaryBigEndian) cloud.frame.origin = {500000, 9000000, 200};
    candi::io::WritePointCloud(seeds.Tmp("seed.ply"), cloud, options);
    seeds.Put("ply", p.name, Read(seeds.Tmp("seed.ply")));
  }
  candi::TriMesh mesh;
  mesh.vertices = SmallCloud(true, false, false, 4);
  mesh.faces = {{0, 1, 2}, {1, 3, 2}};
  candi::io::PointWriteOptions ascii;
  ascii.ply_encoding = io::PlyEncoding::kAscii;
  candi::io::WritePlyMesh(seeds.Tmp("mesh.ply"), mesh, ascii);
  seeds.Put("ply", "mesh_ascii.ply", Read(seeds.Tmp("mesh.ply")));
  candi::io::WritePlyMesh(seeds.Tmp("mesh.ply"), mesh);
  seeds.Put("ply", "mesh_binary.ply", Read(seeds.Tmp("mesh.ply")));

  struct Las {
    const char* name;
    int minor, format;
    bool colors, normals, scalar;
  };
  for (const Las& l : {Las{"f0_v12.las", 2, 0, false, false, true},
                       Las{"f3_v12.las", 2, 3, true, false, false},
                       Las{"f7_v14.las", 4, 7, true, false, false},
                       Las{"f6_extra_v14.las", 4, 6, false, true, true}}) {
    candi::io::PointWriteOptions options;
    options.las_version_minor = l.minor;
    options.las_point_format = l.format;
    candi::io::WritePointCloud(seeds.Tmp("seed.las"), SmallCloud(l.colors, l.normals, l.scalar, 3),
                           options);
    seeds.Put("las", l.name, Read(seeds.Tmp("seed.las")));
  }

  candi::io::WritePointCloud(seeds.Tmp("seed.xyz"), SmallCloud(true, false, true));
  seeds.Put("xyz", "xyzirgb.xyz", Read(seeds.Tmp("seed.xyz")));
  candi::io::WritePointCloud(seeds.Tmp("seed.xyz"), SmallCloud(false, true, false));
  seeds.Put("xyz", "xyz_normals.xyz", Read(seeds.Tmp("seed.xyz")));
  candi::io::WritePointCloud(seeds.Tmp("seed.pts"), SmallCloud(true, false, true));
  seeds.Put("xyz", "leica.pts", Read(seeds.Tmp("seed.pts")));
  seeds.Put("xyz", "commented.csv",
            "# x;y;z\nX;Y;Z\n1,5; 2; 3\n// note\n4;5;6\r\n\n7;8;9\n");
  seeds.Put("xyz", "sections.pts", "2\n1 2 3 10 255 0 0\n4 5 6 20 0 255 0\n1\n7 8 9 30 0 0 255\n");
}

void DxfSeeds(Seeds& seeds) {
  using V = Eigen::Vector2d;
  candi::testing::DxfText metres(6);
  metres.LwPolyline("A", {V(0, 0), V(1, 0), V(1, 1), V(0, 1)}, {0, 0.5, 0, -1}, true)
      .Polyline("B", {V(0, 0), V(2, 0), V(2, 3)})
      .Line("C", V(0, 0), V(0, 5))
      .Spline("D", {V(0, 0), V(1, 2), V(3, 3)})
      .Spline("E", {}, {V(0, 0), V(1, 1), V(2, 0), V(3, 1)})
      .Circle("F", V(1, 1), 2);
  seeds.Put("dxf", "entities.dxf", metres.str());
  candi::testing::DxfText mm(4);
  mm.Polyline("MESH", {V(0, 0), V(1, 0), V(1, 1)}, false, 64).Lines("L", {V(0, 0), V(10, 0), V(10, 10)});
  seeds.Put("dxf", "millimetres.dxf", mm.str());
  candi::testing::DxfText unitless(-1);
  unitless.LwPolyline("P", {V(0, 0), V(100, 0), V(100, 50)}, {1e9, 0, 0});
  seeds.Put("dxf", "unitless.dxf", unitless.str());
}

std::string Join(const std::vector<std::string>& parts) {
  std::string out;
  for (size_t k = 0; k < parts.size(); ++k) {
    if (k > 0) out += kFuzzPartSeparator;
    out += parts[k];
  }
  return out;
}

void ColmapSeeds(Seeds& seeds) {
  namespace pg = candi::photogrammetry;
  pg::ColmapModel model;
  model.cameras[1] = {1, "SIMPLE_RADIAL", 64, 48, {50, 32, 24, 0.01}};
  model.cameras[2] = {2, "PINHOLE", 80, 60, {70, 71, 40, 30}};
  for (uint32_t id = 1; id <= 2; ++id) {
    pg::ColmapImage image;
    image.image_id = id;
    image.camera_id = id;
    image.name = "img " + std::to_string(id) + ".jpg";
    image.cam_from_world_translation = {0.1 * id, 0, 1};
    image.points2d = {{10.5, 20.25}, {30, 40}, {1, 2}};
    image.point3d_ids = {7, 8, pg::kInvalidPoint3dId};
    model.images[id] = image;
  }
  for (uint64_t id = 7; id <= 8; ++id) {
    pg::ColmapPoint3d point;
    point.point3d_id = id;
    point.xyz = {1.0 * id, -2, 3.5};
    point.rgb = {10, 20, 30};
    point.error = 0.5;
    point.track = {{1, static_cast<uint32_t>(id - 7)}, {2, static_cast<uint32_t>(id - 7)}};
    model.points3d[id] = point;
  }
  const std::string dir = seeds.Tmp("model");
  pg::WriteColmapModelBinary(model, dir);
  seeds.Put("colmap_bin", "model.bin",
            Join({Read(dir + "/cameras.bin"), Read(dir + "/images.bin"), Read(dir + "/points3D.bin")}));
  pg::WriteColmapModelText(model, dir);
  seeds.Put("colmap_text", "model.txt",
            Join({Read(dir + "/cameras.txt"), Read(dir + "/images.txt"), Read(dir + "/points3D.txt")}));

  pg::ColmapArray depth{4, 3, 1, {}};
  for (int i = 0; i < 12; ++i) depth.data.push_back(0.5f + i);
  pg::WriteColmapArray(depth, seeds.Tmp("depth.bin"));
  seeds.Put("colmap_array", "depth.bin", Read(seeds.Tmp("depth.bin")));
  pg::ColmapArray normal{2, 2, 3, std::vector<float>(12, 0.0f)};
  for (int i = 8; i < 12; ++i) normal.data[i] = 1.0f;
  pg::WriteColmapArray(normal, seeds.Tmp("normal.bin"));
  seeds.Put("colmap_array", "normal.bin", Read(seeds.Tmp("normal.bin")));
}

void SceneSeeds(Seeds& seeds) {
  seeds.Put("scene", "minimal.json", R"({"candi_scene": 1, "layers": []})");
  seeds.Put("scene", "full.json", R"({
  "candi_scene": 1, "name": "site", "origin": [500000, 9000000, 200], "seed": 7,
  "render": {"repeat_level": 10, "width": 64, "height": 48, "background": [0, 0, 0],
             "brightness": 1.5},
  "views": [{"name": "v", "opaque": true, "layers": ["a"], "focus": true, "focus_opacity": 0.9,
             "dim": 0.3, "opacity": {"a": 0.2}, "point_size": 2,
             "camera": {"eye": [0, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0],
                        "fov_y_deg": 60}}],
  "layers": [
    {"name": "a", "kind": "points", "file": "scene.json", "columns": "xyz", "opacity": 0.5,
     "color": [255, 0, 0], "highlight": true,
     "world_from_layer": {"scale": 2, "rotation_deg": [0, 0, 90], "translation": [1, 2, 3]}},
    {"name": "b", "kind": "foundation", "dxf": "scene.json", "sections": ["A"], "count": 1000,
     "mode": "blend", "world_from_layer": {"matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}},
    {"name": "c", "kind": "relief", "panels": [{"id": "P01", "points": "scene.json"}],
     "placement": "scene.json", "width_m": 2.0},
    {"name": "d", "kind": "photogrammetry", "dense": "scene.json", "targets": "scene.json"}]
}
)");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds OUT\n");
    return 1;
  }
  Seeds seeds(argv[1]);
  PointSeeds(seeds);
  DxfSeeds(seeds);
  ColmapSeeds(seeds);
  SceneSeeds(seeds);
  return 0;
}
