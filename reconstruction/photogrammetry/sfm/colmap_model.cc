// COLMAP 3.8 sparse models: the byte layouts of src/base/reconstruction.cc
// (Read/Write{Cameras,Images,Points3D}{Binary,Text}). Dense arrays are in colmap_array.cc.
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string_view>

#include "core/atomic_file.h"
#include "core/check.h"
#include "reconstruction/photogrammetry/sfm/camera_projection.h"

namespace candi::photogrammetry {

namespace {

struct CameraModelInfo {
  int id;
  const char* name;
  int num_params;
};

// src/base/camera_models.h of COLMAP 3.8 (model ids as written in cameras.bin).
constexpr CameraModelInfo kCameraModels[] = {
    {0, "SIMPLE_PINHOLE", 3},        {1, "PINHOLE", 4},
    {2, "SIMPLE_RADIAL", 4},         {3, "RADIAL", 5},
    {4, "OPENCV", 8},                {5, "OPENCV_FISHEYE", 8},
    {6, "FULL_OPENCV", 12},          {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4}, {9, "RADIAL_FISHEYE", 5},
    {10, "THIN_PRISM_FISHEYE", 12},
};

// ---------------------------------------------------------------------------------------------
// Binary reading: the whole file in memory, every read bounds-checked.

class BinaryReader {
 public:
  explicit BinaryReader(const std::string& path) : path_(path), data_(ReadFileToString(path)) {}

  template <typename T>
  T Read(const char* what) {
    Need(sizeof(T), what);
    T value;
    std::memcpy(&value, data_.data() + pos_, sizeof(T));  // little-endian hosts only (CMake)
    pos_ += sizeof(T);
    return value;
  }
  double ReadFinite(const char* what) {
    const size_t at = pos_;
    const double value = Read<double>(what);
    if (!std::isfinite(value)) Fail(at, std::string("non-finite ") + what);
    return value;
  }
  std::string ReadName(const char* what) {
    const size_t end = data_.find('\0', pos_);
    if (end == std::string::npos) Fail(pos_, std::string("unterminated ") + what + " (truncated file)");
    std::string name = data_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return name;
  }
  // A count of records of at least `min_record_bytes` each: refused when the rest of the file
  // cannot hold them, before anything is allocated.
  uint64_t ReadCount(const char* what, size_t min_record_bytes) {
    const size_t at = pos_;
    const uint64_t count = Read<uint64_t>(what);
    if (count > Remaining() / min_record_bytes) {
      Fail(at, std::string(what) + " = " + std::to_string(count) + " does not fit in the " +
                   std::to_string(Remaining()) + " bytes left (truncated or corrupt file)");
    }
    return count;
  }
  void ExpectEnd() const {
    if (pos_ != data_.size()) {
      Fail(pos_, std::to_string(data_.size() - pos_) + " unexpected bytes after the last record");
    }
  }
  [[noreturn]] void Fail(size_t at, const std::string& message) const {
    throw InputError(path_, "byte " + std::to_string(at), message);
  }
  size_t pos() const { return pos_; }
  size_t Remaining() const { return data_.size() - pos_; }

 private:
  void Need(size_t n, const char* what) const {
    if (Remaining() < n) {
      Fail(pos_, std::string("unexpected end of file while reading ") + what + " (needed " +
                     std::to_string(n) + " bytes, " + std::to_string(Remaining()) + " left)");
    }
  }

  std::string path_, data_;
  size_t pos_ = 0;
};

void ReadCamerasBinary(const std::string& path, ColmapModel* model) {
  BinaryReader in(path);
  const uint64_t count = in.ReadCount("number of cameras", 4 + 4 + 8 + 8);
  for (uint64_t i = 0; i < count; ++i) {
    const size_t at = in.pos();
    ColmapCamera camera;
    camera.camera_id = in.Read<uint32_t>("camera_id");
    const size_t model_at = in.pos();
    const int32_t model_id = in.Read<int32_t>("model_id");
    camera.model = CameraModelName(model_id);
    if (camera.model.empty()) in.Fail(model_at, "unknown camera model id " + std::to_string(model_id));
    const uint64_t width = in.Read<uint64_t>("width"), height = in.Read<uint64_t>("height");
    if (width == 0 || height == 0 || width > (1u << 30) || height > (1u << 30)) {
      in.Fail(model_at + 4, "bad image size " + std::to_string(width) + "x" + std::to_string(height));
    }
    camera.width = static_cast<int>(width);
    camera.height = static_cast<int>(height);
    const int num_params = CameraModelNumParams(camera.model);
    for (int k = 0; k < num_params; ++k) camera.params.push_back(in.ReadFinite("camera parameter"));
    if (!model->cameras.emplace(camera.camera_id, camera).second) {
      in.Fail(at, "duplicate camera_id " + std::to_string(camera.camera_id));
    }
  }
  in.ExpectEnd();
}

void ReadImageRecordBinary(BinaryReader& in, ColmapImage* image) {
  image->image_id = in.Read<uint32_t>("image_id");
  double q[4];
  for (double& v : q) v = in.ReadFinite("quaternion");
  image->cam_from_world_rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  for (int k = 0; k < 3; ++k) image->cam_from_world_translation[k] = in.ReadFinite("translation");
  image->camera_id = in.Read<uint32_t>("camera_id");
  image->name = in.ReadName("image name");
  const uint64_t num_points = in.ReadCount("number of points2D", 8 + 8 + 8);
  image->points2d.resize(num_points);
  image->point3d_ids.resize(num_points);
  for (uint64_t j = 0; j < num_points; ++j) {
    image->points2d[j].x() = in.ReadFinite("point2D x");
    image->points2d[j].y() = in.ReadFinite("point2D y");
    image->point3d_ids[j] = in.Read<uint64_t>("point3D_id");
  }
}

void ReadImagesBinary(const std::string& path, ColmapModel* model) {
  BinaryReader in(path);
  const uint64_t count = in.ReadCount("number of images", 4 + 7 * 8 + 4 + 1 + 8);
  for (uint64_t i = 0; i < count; ++i) {
    const size_t at = in.pos();
    ColmapImage image;
    ReadImageRecordBinary(in, &image);
    const uint32_t id = image.image_id;
    if (!model->images.emplace(id, std::move(image)).second) {
      in.Fail(at, "duplicate image_id " + std::to_string(id));
    }
  }
  in.ExpectEnd();
}

void ReadPoints3dBinary(const std::string& path, ColmapModel* model) {
  BinaryReader in(path);
  const uint64_t count = in.ReadCount("number of points3D", 8 + 3 * 8 + 3 + 8 + 8);
  for (uint64_t i = 0; i < count; ++i) {
    const size_t at = in.pos();
    ColmapPoint3d point;
    point.point3d_id = in.Read<uint64_t>("point3D_id");
    for (int k = 0; k < 3; ++k) point.xyz[k] = in.ReadFinite("point coordinate");
    for (int k = 0; k < 3; ++k) point.rgb[k] = in.Read<uint8_t>("colour");
    point.error = in.ReadFinite("error");
    const uint64_t length = in.ReadCount("track length", 4 + 4);
    point.track.resize(length);
    for (ColmapTrackElement& element : point.track) {
      element.image_id = in.Read<uint32_t>("track image_id");
      element.point2d_idx = in.Read<uint32_t>("track point2D_idx");
    }
    const uint64_t id = point.point3d_id;
    if (!model->points3d.emplace(id, std::move(point)).second) {
      in.Fail(at, "duplicate point3D_id " + std::to_string(id));
    }
  }
  in.ExpectEnd();
}

// ---------------------------------------------------------------------------------------------
// Text reading: one line at a time, tokens separated by blanks.

class TextReader {
 public:
  explicit TextReader(const std::string& path) : path_(path), data_(ReadFileToString(path)) {}

  // The next line that is neither empty nor a comment; false at the end of the file.
  bool NextDataLine() {
    while (NextLine()) {
      const size_t first = line_.find_first_not_of(" \t\r");
      if (first != std::string_view::npos && line_[first] != '#') return true;
    }
    return false;
  }
  // The very next line (may be empty); false at the end of the file.
  bool NextLine() {
    if (pos_ >= data_.size()) return false;
    size_t end = data_.find('\n', pos_);
    if (end == std::string::npos) end = data_.size();
    line_ = std::string_view(data_).substr(pos_, end - pos_);
    pos_ = end + 1;
    ++line_number_;
    tokens_.clear();
    token_index_ = 0;
    for (size_t p = 0; p < line_.size();) {
      const size_t start = line_.find_first_not_of(" \t\r", p);
      if (start == std::string_view::npos) break;
      const size_t stop = std::min(line_.find_first_of(" \t\r", start), line_.size());
      tokens_.push_back(line_.substr(start, stop - start));
      p = stop;
    }
    return true;
  }
  bool HasToken() const { return token_index_ < tokens_.size(); }
  size_t TokensLeft() const { return tokens_.size() - token_index_; }
  std::string_view Token(const char* what) {
    if (!HasToken()) Fail(std::string("missing ") + what);
    return tokens_[token_index_++];
  }
  // The rest of the line after the tokens consumed so far, trimmed (image names).
  std::string Rest(const char* what) {
    if (!HasToken()) Fail(std::string("missing ") + what);
    const size_t start = static_cast<size_t>(tokens_[token_index_].data() - line_.data());
    std::string_view rest = line_.substr(start);
    while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\r' || rest.back() == '\t')) {
      rest.remove_suffix(1);
    }
    token_index_ = tokens_.size();
    return std::string(rest);
  }
  template <typename T>
  T Integer(const char* what) {
    const std::string_view token = Token(what);
    T value{};
    const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
    if (result.ec != std::errc() || result.ptr != token.data() + token.size()) {
      Fail(std::string("bad ") + what + " '" + std::string(token) + "'");
    }
    return value;
  }
  double Double(const char* what) {
    const std::string_view token = Token(what);
    double value = 0;
    const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
    if (result.ec != std::errc() || result.ptr != token.data() + token.size()) {
      Fail(std::string("bad ") + what + " '" + std::string(token) + "'");
    }
    if (!std::isfinite(value)) Fail(std::string("non-finite ") + what);
    return value;
  }
  void ExpectLineEnd() {
    if (HasToken()) Fail("unexpected '" + std::string(tokens_[token_index_]) + "' at the line's end");
  }
  [[noreturn]] void Fail(const std::string& message) const {
    throw InputError(path_, "line " + std::to_string(line_number_), message);
  }

 private:
  std::string path_, data_;
  size_t pos_ = 0;
  size_t line_number_ = 0;
  std::string_view line_;
  std::vector<std::string_view> tokens_;
  size_t token_index_ = 0;
};

void ReadCamerasText(const std::string& path, ColmapModel* model) {
  TextReader in(path);
  while (in.NextDataLine()) {
    ColmapCamera camera;
    camera.camera_id = in.Integer<uint32_t>("CAMERA_ID");
    camera.model = std::string(in.Token("MODEL"));
    const int num_params = CameraModelNumParams(camera.model);
    if (num_params == 0) in.Fail("unknown camera model '" + camera.model + "'");
    camera.width = in.Integer<int>("WIDTH");
    camera.height = in.Integer<int>("HEIGHT");
    if (camera.width <= 0 || camera.height <= 0) in.Fail("WIDTH and HEIGHT must be > 0");
    if (static_cast<int>(in.TokensLeft()) != num_params) {
      in.Fail(camera.model + " takes " + std::to_string(num_params) + " parameters, the line has " +
              std::to_string(in.TokensLeft()));
    }
    for (int k = 0; k < num_params; ++k) camera.params.push_back(in.Double("PARAMS"));
    if (!model->cameras.emplace(camera.camera_id, camera).second) {
      in.Fail("duplicate CAMERA_ID " + std::to_string(camera.camera_id));
    }
  }
}

void ReadPoints2dText(TextReader& in, ColmapImage* image) {
  if (in.TokensLeft() % 3 != 0) in.Fail("POINTS2D needs triples X Y POINT3D_ID");
  while (in.HasToken()) {
    const double x = in.Double("X");
    const double y = in.Double("Y");
    image->points2d.emplace_back(x, y);
    const std::string_view id = in.Token("POINT3D_ID");
    if (id == "-1") {
      image->point3d_ids.push_back(kInvalidPoint3dId);
    } else {
      uint64_t value = 0;
      const auto result = std::from_chars(id.data(), id.data() + id.size(), value);
      if (result.ec != std::errc() || result.ptr != id.data() + id.size()) {
        in.Fail("bad POINT3D_ID '" + std::string(id) + "'");
      }
      image->point3d_ids.push_back(value);
    }
  }
}

void ReadImagesText(const std::string& path, ColmapModel* model) {
  TextReader in(path);
  while (in.NextDataLine()) {
    ColmapImage image;
    image.image_id = in.Integer<uint32_t>("IMAGE_ID");
    double q[4];
    for (double& v : q) v = in.Double("quaternion");
    image.cam_from_world_rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    for (int k = 0; k < 3; ++k) image.cam_from_world_translation[k] = in.Double("translation");
    image.camera_id = in.Integer<uint32_t>("CAMERA_ID");
    image.name = in.Rest("NAME");
    if (!in.NextLine()) in.Fail("missing the POINTS2D line of image " + std::to_string(image.image_id));
    ReadPoints2dText(in, &image);
    const uint32_t id = image.image_id;
    if (!model->images.emplace(id, std::move(image)).second) {
      in.Fail("duplicate IMAGE_ID " + std::to_string(id));
    }
  }
}

void ReadPoints3dText(const std::string& path, ColmapModel* model) {
  TextReader in(path);
  while (in.NextDataLine()) {
    ColmapPoint3d point;
    point.point3d_id = in.Integer<uint64_t>("POINT3D_ID");
    for (int k = 0; k < 3; ++k) point.xyz[k] = in.Double("coordinate");
    for (int k = 0; k < 3; ++k) {
      const int c = in.Integer<int>("colour");
      if (c < 0 || c > 255) in.Fail("colour " + std::to_string(c) + " outside 0..255");
      point.rgb[k] = static_cast<uint8_t>(c);
    }
    point.error = in.Double("ERROR");
    if (in.TokensLeft() % 2 != 0) in.Fail("TRACK needs pairs IMAGE_ID POINT2D_IDX");
    while (in.HasToken()) {
      ColmapTrackElement element;
      element.image_id = in.Integer<uint32_t>("track IMAGE_ID");
      element.point2d_idx = in.Integer<uint32_t>("track POINT2D_IDX");
      point.track.push_back(element);
    }
    const uint64_t id = point.point3d_id;
    if (!model->points3d.emplace(id, std::move(point)).second) {
      in.Fail("duplicate POINT3D_ID " + std::to_string(id));
    }
  }
}

// Cross-file references: images name existing cameras, tracks name existing observations.
void CheckReferences(const ColmapModel& model, const std::string& images_path,
                     const std::string& points_path) {
  for (const auto& [id, image] : model.images) {
    if (model.cameras.count(image.camera_id) == 0) {
      throw InputError(images_path, "image " + std::to_string(id),
                       "camera_id " + std::to_string(image.camera_id) + " is not in the cameras file");
    }
  }
  for (const auto& [id, point] : model.points3d) {
    for (const ColmapTrackElement& element : point.track) {
      const auto it = model.images.find(element.image_id);
      if (it == model.images.end() || element.point2d_idx >= it->second.points2d.size()) {
        throw InputError(points_path, "point3D " + std::to_string(id),
                         "track element (" + std::to_string(element.image_id) + ", " +
                             std::to_string(element.point2d_idx) + ") names no observation");
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Writing.

class BinaryWriter {
 public:
  explicit BinaryWriter(const std::string& path) : file_(path) {}
  template <typename T>
  void Put(T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    buffer_.append(bytes, sizeof(T));
    if (buffer_.size() > (1 << 20)) Flush();
  }
  void PutName(const std::string& name) {
    buffer_.append(name);
    buffer_.push_back('\0');
  }
  void Commit() {
    Flush();
    file_.Commit();
  }

 private:
  void Flush() {
    file_.Write(buffer_);
    buffer_.clear();
  }
  AtomicFile file_;
  std::string buffer_;
};

// COLMAP writes doubles with std::ostream precision 17, i.e. "%.17g".
void AppendG17(std::string* out, double value) {
  char buf[40];
  const int n = std::snprintf(buf, sizeof(buf), "%.17g", value);
  out->append(buf, static_cast<size_t>(n));
}

size_t NumObservations(const ColmapModel& model) {
  size_t n = 0;
  for (const auto& [id, image] : model.images) {
    for (const uint64_t p : image.point3d_ids) n += p != kInvalidPoint3dId;
  }
  return n;
}

void CheckWritable(const ColmapModel& model) {
  for (const auto& [id, camera] : model.cameras) {
    CANDI_CHECK(CameraModelId(camera.model) >= 0) << "unknown camera model " << camera.model;
    CANDI_CHECK_EQ(static_cast<int>(camera.params.size()), CameraModelNumParams(camera.model));
  }
  for (const auto& [id, image] : model.images) {
    CANDI_CHECK_EQ(image.points2d.size(), image.point3d_ids.size());
  }
}

std::string CamerasText(const ColmapModel& model) {
  std::string out = "# Camera list with one line of data per camera:\n"
                    "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
                    "# Number of cameras: " + std::to_string(model.cameras.size()) + "\n";
  for (const auto& [id, camera] : model.cameras) {
    out += std::to_string(id) + " " + camera.model + " " + std::to_string(camera.width) + " " +
           std::to_string(camera.height);
    for (const double p : camera.params) {
      out += ' ';
      AppendG17(&out, p);
    }
    out += '\n';
  }
  return out;
}

std::string ImagesText(const ColmapModel& model) {
  std::string out = "# Image list with two lines of data per image:\n"
                    "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
                    "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
                    "# Number of images: " + std::to_string(model.images.size()) +
                    ", mean observations per image: ";
  AppendG17(&out, model.images.empty() ? 0.0
                                       : static_cast<double>(NumObservations(model)) /
                                             static_cast<double>(model.images.size()));
  out += '\n';
  for (const auto& [id, image] : model.images) {
    const Eigen::Quaterniond& q = image.cam_from_world_rotation;
    out += std::to_string(id);
    for (const double v : {q.w(), q.x(), q.y(), q.z(), image.cam_from_world_translation.x(),
                           image.cam_from_world_translation.y(), image.cam_from_world_translation.z()}) {
      out += ' ';
      AppendG17(&out, v);
    }
    out += " " + std::to_string(image.camera_id) + " " + image.name + "\n";
    for (size_t j = 0; j < image.points2d.size(); ++j) {
      if (j > 0) out += ' ';
      AppendG17(&out, image.points2d[j].x());
      out += ' ';
      AppendG17(&out, image.points2d[j].y());
      out += ' ';
      out += image.point3d_ids[j] == kInvalidPoint3dId ? "-1" : std::to_string(image.point3d_ids[j]);
    }
    out += '\n';
  }
  return out;
}

std::string Points3dText(const ColmapModel& model) {
  size_t track_sum = 0;
  for (const auto& [id, point] : model.points3d) track_sum += point.track.size();
  std::string out = "# 3D point list with one line of data per point:\n"
                    "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
                    "# Number of points: " + std::to_string(model.points3d.size()) +
                    ", mean track length: ";
  AppendG17(&out, model.points3d.empty() ? 0.0
                                         : static_cast<double>(track_sum) /
                                               static_cast<double>(model.points3d.size()));
  out += '\n';
  for (const auto& [id, point] : model.points3d) {
    out += std::to_string(id);
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      AppendG17(&out, point.xyz[k]);
    }
    for (int k = 0; k < 3; ++k) out += " " + std::to_string(point.rgb[k]);
    out += ' ';
    AppendG17(&out, point.error);
    out += ' ';  // COLMAP leaves this blank before the track (even an empty one)
    for (size_t t = 0; t < point.track.size(); ++t) {
      if (t > 0) out += ' ';
      out += std::to_string(point.track[t].image_id) + " " + std::to_string(point.track[t].point2d_idx);
    }
    out += '\n';
  }
  return out;
}

std::string Join(const std::string& dir, const char* name) {
  return (std::filesystem::path(dir) / name).string();
}

void CreateDirectory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir, "", "cannot create the folder: " + ec.message());
}

}  // namespace

int CameraModelId(const std::string& name) {
  for (const CameraModelInfo& m : kCameraModels) {
    if (name == m.name) return m.id;
  }
  return -1;
}

std::string CameraModelName(int id) {
  for (const CameraModelInfo& m : kCameraModels) {
    if (id == m.id) return m.name;
  }
  return "";
}

int CameraModelNumParams(const std::string& name) {
  for (const CameraModelInfo& m : kCameraModels) {
    if (name == m.name) return m.num_params;
  }
  return 0;
}

ColmapModel ReadColmapModel(const std::string& dir) {
  ColmapModel model;
  const bool binary = std::filesystem::exists(Join(dir, "cameras.bin"));
  const std::string ext = binary ? ".bin" : ".txt";
  const std::string cameras = Join(dir, ("cameras" + ext).c_str());
  const std::string images = Join(dir, ("images" + ext).c_str());
  const std::string points = Join(dir, ("points3D" + ext).c_str());
  if (!binary && !std::filesystem::exists(cameras)) {
    throw InputError(dir, "", "no COLMAP model here (neither cameras.bin nor cameras.txt)");
  }
  if (binary) {
    ReadCamerasBinary(cameras, &model);
    ReadImagesBinary(images, &model);
    ReadPoints3dBinary(points, &model);
  } else {
    ReadCamerasText(cameras, &model);
    ReadImagesText(images, &model);
    ReadPoints3dText(points, &model);
  }
  CheckReferences(model, images, points);
  return model;
}

void WriteColmapModelBinary(const ColmapModel& model, const std::string& dir) {
  CheckWritable(model);
  CreateDirectory(dir);
  BinaryWriter cameras(Join(dir, "cameras.bin"));
  cameras.Put<uint64_t>(model.cameras.size());
  for (const auto& [id, camera] : model.cameras) {
    cameras.Put<uint32_t>(id);
    cameras.Put<int32_t>(CameraModelId(camera.model));
    cameras.Put<uint64_t>(static_cast<uint64_t>(camera.width));
    cameras.Put<uint64_t>(static_cast<uint64_t>(camera.height));
    for (const double p : camera.params) cameras.Put<double>(p);
  }
  BinaryWriter images(Join(dir, "images.bin"));
  images.Put<uint64_t>(model.images.size());
  for (const auto& [id, image] : model.images) {
    const Eigen::Quaterniond& q = image.cam_from_world_rotation;
    images.Put<uint32_t>(id);
    for (const double v : {q.w(), q.x(), q.y(), q.z()}) images.Put<double>(v);
    for (int k = 0; k < 3; ++k) images.Put<double>(image.cam_from_world_translation[k]);
    images.Put<uint32_t>(image.camera_id);
    images.PutName(image.name);
    images.Put<uint64_t>(image.points2d.size());
    for (size_t j = 0; j < image.points2d.size(); ++j) {
      images.Put<double>(image.points2d[j].x());
      images.Put<double>(image.points2d[j].y());
      images.Put<uint64_t>(image.point3d_ids[j]);
    }
  }
  BinaryWriter points(Join(dir, "points3D.bin"));
  points.Put<uint64_t>(model.points3d.size());
  for (const auto& [id, point] : model.points3d) {
    points.Put<uint64_t>(id);
    for (int k = 0; k < 3; ++k) points.Put<double>(point.xyz[k]);
    for (int k = 0; k < 3; ++k) points.Put<uint8_t>(point.rgb[k]);
    points.Put<double>(point.error);
    points.Put<uint64_t>(point.track.size());
    for (const ColmapTrackElement& element : point.track) {
      points.Put<uint32_t>(element.image_id);
      points.Put<uint32_t>(element.point2d_idx);
    }
  }
  cameras.Commit();
  images.Commit();
  points.Commit();
}

void WriteColmapModelText(const ColmapModel& model, const std::string& dir) {
  CheckWritable(model);
  CreateDirectory(dir);
  WriteFileAtomic(Join(dir, "cameras.txt"), CamerasText(model));
  WriteFileAtomic(Join(dir, "images.txt"), ImagesText(model));
  WriteFileAtomic(Join(dir, "points3D.txt"), Points3dText(model));
}

// ---------------------------------------------------------------------------------------------
// Projection (src/base/camera_models.h, ImageToWorld's inverse: WorldToImage).

Eigen::Vector2d ProjectToImage(const ColmapCamera& camera, const ColmapImage& image,
                               const Eigen::Vector3d& world_point) {
  const Eigen::Vector3d x = image.cam_from_world_rotation.normalized() * world_point +
                            image.cam_from_world_translation;
  if (!(x.z() > 0)) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  const double u = x.x() / x.z(), v = x.y() / x.z();
  const std::vector<double>& p = camera.params;
  if (static_cast<int>(p.size()) != CameraModelNumParams(camera.model)) {
    throw std::invalid_argument("ProjectToImage: camera " + std::to_string(camera.camera_id) +
                                " (" + camera.model + ") has " + std::to_string(p.size()) +
                                " parameters");
  }
  Eigen::Vector2d pixel;
  if (PixelFromNormalized(ProjectionModelOf(camera.model), p.data(), u, v, &pixel.x(), &pixel.y())) return pixel;
  throw std::invalid_argument("ProjectToImage: camera model " + camera.model +
                              " is not supported (pinhole, radial and OpenCV models are)");
}

double MeanReprojectionError(const ColmapModel& model) {
  double sum = 0;
  size_t n = 0;
  for (const auto& [id, point] : model.points3d) {
    if (point.error == -1.0) continue;
    sum += point.error;
    ++n;
  }
  return n == 0 ? 0.0 : sum / static_cast<double>(n);
}

}  // namespace candi::photogrammetry
