// The file half of dense_workspace.h (uses colmap_model.h's readers and writers).
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "core/atomic_file.h"
#include "core/check.h"
#include "io/image/jpeg_io.h"

namespace candi::photogrammetry {

namespace fs = std::filesystem;

StereoInput ReadDenseModel(const std::string& workspace) {
  const std::string sparse = (fs::path(workspace) / "sparse").string();
  const ColmapModel model = ReadColmapModel(sparse);
  if (model.images.empty()) throw InputError(sparse, "", "the model has no images");
  StereoInput in;
  std::map<uint32_t, int> index;
  for (const auto& [id, image] : model.images) {
    const auto camera = model.cameras.find(image.camera_id);
    if (camera == model.cameras.end())
      throw InputError(sparse, "image " + std::to_string(id),
                       "camera " + std::to_string(image.camera_id) + " is not in the model");
    StereoImage s;
    s.name = image.name;
    s.camera = ToPinholeCamera(camera->second, image, sparse);
    index[id] = static_cast<int>(in.images.size());
    in.images.push_back(std::move(s));
  }
  bool tracks = false;
  for (const auto& [id, point] : model.points3d) {
    if (!point.xyz.allFinite()) continue;
    in.sparse_points.push_back(point.xyz);
    std::vector<int> views;
    for (const ColmapTrackElement& e : point.track) {
      const auto it = index.find(e.image_id);
      if (it != index.end()) views.push_back(it->second);
    }
    tracks = tracks || !views.empty();
    in.point_views.push_back(std::move(views));
  }
  if (!tracks) in.point_views.clear();
  return in;
}

Image8 ReadStereoImage(const std::string& workspace, const StereoImage& image) {
  const std::string path = (fs::path(workspace) / "images" / image.name).string();
  Image8 pixels = io::ReadImageRgb8(path);
  if (pixels.width() != image.camera.width || pixels.height() != image.camera.height)
    throw InputError(path, "", "image is " + std::to_string(pixels.width()) + "x" + std::to_string(pixels.height()) +
                                   ", its camera " + std::to_string(image.camera.width) + "x" +
                                   std::to_string(image.camera.height));
  return pixels;
}

StereoInput ReadDenseWorkspace(const std::string& workspace) {
  StereoInput in = ReadDenseModel(workspace);
  for (StereoImage& s : in.images) s.image = ReadStereoImage(workspace, s);
  return in;
}

namespace {

constexpr char kMapMagic[8] = {'C', 'A', 'N', 'D', 'I', 'D', 'M', '1'};

template <typename T>
void Append(std::string* out, const T* data, size_t n) {
  out->append(reinterpret_cast<const char*>(data), n * sizeof(T));
}

}  // namespace

void WriteDepthMapFile(const DepthNormalMap& map, bool with_cost, const std::string& path) {
  const uint32_t w = map.depth.width(), h = map.depth.height();
  CANDI_CHECK(map.normal.width() == static_cast<int>(w) && map.normal.height() == static_cast<int>(h) &&
              map.normal.channels() == 3 && map.color.width() == static_cast<int>(w) &&
              map.color.height() == static_cast<int>(h) && map.color.channels() == 3 &&
              (!with_cost || (map.cost.width() == static_cast<int>(w) && map.cost.height() == static_cast<int>(h))))
      << path << ": the map's layers differ in size";
  uint64_t valid = 0;
  for (float d : map.depth.values()) valid += d > 0;
  const uint32_t header[6] = {w, h, static_cast<uint32_t>(map.source_views.size()), 2u | (with_cost ? 1u : 0u),
                              static_cast<uint32_t>(valid), static_cast<uint32_t>(valid >> 32)};
  std::string out(kMapMagic, sizeof(kMapMagic));
  Append(&out, header, 6);
  for (int s : map.source_views) {
    const int32_t v = s;
    Append(&out, &v, 1);
  }
  Append(&out, map.depth.data(), map.depth.values().size());
  Append(&out, map.normal.data(), map.normal.values().size());
  if (with_cost) Append(&out, map.cost.data(), map.cost.values().size());
  Append(&out, map.color.data(), map.color.values().size());
  CreateParentFolder(path);
  WriteFileAtomic(path, out);
}

void CreateParentFolder(const std::string& path) {
  std::error_code ec;
  const fs::path parent = fs::path(path).parent_path();
  fs::create_directories(parent, ec);  // names may hold sub-folders
  if (ec) throw InputError(parent.string(), "", "cannot create the folder: " + ec.message());
}

namespace {

struct MapHeader {
  uint32_t width = 0, height = 0, sources = 0, flags = 0;
  uint64_t valid = 0;
  uint64_t FileBytes() const {
    const uint64_t pixels = static_cast<uint64_t>(width) * height;
    return 8 + 24 + 4ull * sources + pixels * (4 + 12 + ((flags & 1) ? 4 : 0) + ((flags & 2) ? 3 : 0));
  }
};

// The header of a map file, checked against the camera and the file's size.
MapHeader CheckedHeader(const std::string& path, const std::string& head, uint64_t file_bytes,
                        const PinholeCamera& camera) {
  uint32_t raw[6];
  if (head.size() < 8 + sizeof(raw) || head.compare(0, 8, kMapMagic, 8) != 0)
    throw InputError(path, "", "not a candi depth-map file (no CANDIDM1 header)");
  std::memcpy(raw, head.data() + 8, sizeof(raw));
  MapHeader h{raw[0], raw[1], raw[2], raw[3], raw[4] | (static_cast<uint64_t>(raw[5]) << 32)};
  if (static_cast<int>(h.width) != camera.width || static_cast<int>(h.height) != camera.height || h.sources > 64 ||
      h.flags > 3)
    throw InputError(path, "header", "a " + std::to_string(h.width) + "x" + std::to_string(h.height) + " map with " +
                                         std::to_string(h.sources) + " sources (flags " + std::to_string(h.flags) +
                                         "), the camera is " + std::to_string(camera.width) + "x" +
                                         std::to_string(camera.height));
  if (file_bytes != h.FileBytes())
    throw InputError(path, "", std::to_string(file_bytes) + " bytes, a complete map has " + std::to_string(h.FileBytes()));
  return h;
}

}  // namespace

uint64_t DepthMapFileValidPixels(const std::string& path, const PinholeCamera& camera) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot be opened");
  std::string head(32, '\0');
  in.read(head.data(), 32);
  head.resize(static_cast<size_t>(in.gcount()));
  std::error_code ec;
  const uint64_t bytes = fs::file_size(path, ec);
  if (ec) throw InputError(path, "", ec.message());
  return CheckedHeader(path, head, bytes, camera).valid;
}

DepthNormalMap ReadDepthMapFile(const std::string& path, const PinholeCamera& camera) {
  const std::string bytes = ReadFileToString(path);
  const MapHeader header = CheckedHeader(path, bytes, bytes.size(), camera);
  const uint32_t w = header.width, h = header.height, n = header.sources, flags = header.flags;
  const uint64_t pixels = static_cast<uint64_t>(w) * h;
  DepthNormalMap m;
  m.camera = camera;
  const char* p = bytes.data() + 32;
  for (uint32_t k = 0; k < n; ++k, p += 4) {
    int32_t v;
    std::memcpy(&v, p, 4);
    m.source_views.push_back(v);
  }
  auto take = [&p](auto* image, size_t count) {
    std::memcpy(image->data(), p, count * sizeof(*image->data()));
    p += count * sizeof(*image->data());
  };
  m.depth = ImageF(w, h, 1);
  take(&m.depth, pixels);
  m.normal = ImageF(w, h, 3);
  take(&m.normal, 3 * pixels);
  m.cost = ImageF(w, h, 1, 2.0f);
  if (flags & 1) take(&m.cost, pixels);
  m.color = Image8(w, h, 3);
  if (flags & 2) take(&m.color, 3 * pixels);
  return m;
}

void WriteDepthNormalMaps(const std::vector<DepthNormalMap>& maps,
                          const std::vector<std::string>& names, const std::string& workspace) {
  CANDI_CHECK(maps.size() == names.size()) << maps.size() << " maps, " << names.size() << " names";
  const fs::path stereo = fs::path(workspace) / "stereo";
  for (size_t k = 0; k < maps.size(); ++k) {
    const fs::path depth = stereo / "depth_maps" / (names[k] + ".geometric.bin");
    const fs::path normal = stereo / "normal_maps" / (names[k] + ".geometric.bin");
    fs::create_directories(depth.parent_path());  // names may hold sub-folders
    fs::create_directories(normal.parent_path());
    WriteColmapArray(DepthArray(maps[k]), depth.string());
    WriteColmapArray(NormalArray(maps[k]), normal.string());
  }
}

}  // namespace candi::photogrammetry
