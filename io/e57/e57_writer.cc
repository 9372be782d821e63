// E57 writing: WriteE57 (several scans, any coding) and the streaming point writer.
#include "io/e57/e57_writer.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/check.h"
#include "core/log.h"
#include "core/text_format.h"
#include "io/e57/e57_format.h"
#include "io/e57/e57_io.h"

namespace candi::io {

namespace {

using e57::FieldDesc;
using e57::FieldKind;
using e57::ScanDesc;

constexpr size_t kBlock = 1 << 16;  // points converted at a time by the point writer
constexpr const char* kLibrary = "candi 0.1.0";

std::string NewGuid() {
  std::random_device device;
  std::mt19937_64 rng((uint64_t{device()} << 32) ^ device());
  char buf[48];
  const uint64_t a = rng(), b = rng();
  std::snprintf(buf, sizeof(buf), "{%08X-%04X-4%03X-%04X-%012llX}", static_cast<unsigned>(a >> 32),
                static_cast<unsigned>((a >> 16) & 0xFFFF), static_cast<unsigned>(a & 0xFFF),
                static_cast<unsigned>(0x8000 | ((b >> 48) & 0x3FFF)),
                static_cast<unsigned long long>(b & 0xFFFFFFFFFFFFull));
  return buf;
}

std::string Cdata(const std::string& text) {
  std::string out = "<![CDATA[";
  for (size_t i = 0; i < text.size(); ++i) {
    if (text.compare(i, 3, "]]>") == 0) {
      out += "]]]]><![CDATA[>";
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out + "]]>";
}

std::string StringElement(const std::string& name, const std::string& text) {
  return "<" + name + " type=\"String\">" + Cdata(text) + "</" + name + ">";
}

std::string FloatElement(const std::string& name, double v) {
  return "<" + name + " type=\"Float\">" + FormatDouble(v) + "</" + name + ">";
}

std::string PrototypeElement(const FieldDesc& f) {
  const std::string open = "<" + f.name + " type=\"";
  switch (f.kind) {
    case FieldKind::kFloat: return open + "Float\" precision=\"single\"/>";
    case FieldKind::kDouble: return open + "Float\" precision=\"double\"/>";
    case FieldKind::kInteger:
      return open + "Integer\" minimum=\"" + std::to_string(f.minimum) + "\" maximum=\"" +
             std::to_string(f.maximum) + "\"/>";
    case FieldKind::kScaledInteger:
      return open + "ScaledInteger\" minimum=\"" + std::to_string(f.minimum) + "\" maximum=\"" +
             std::to_string(f.maximum) + "\" scale=\"" + FormatDouble(f.scale) + "\" offset=\"" +
             FormatDouble(f.offset) + "\"/>";
  }
  return "";
}

std::string PoseXml(const ScanDesc& s) {
  const Eigen::Quaterniond& q = s.rotation;
  return "<pose type=\"Structure\"><rotation type=\"Structure\">" + FloatElement("w", q.w()) +
         FloatElement("x", q.x()) + FloatElement("y", q.y()) + FloatElement("z", q.z()) +
         "</rotation><translation type=\"Structure\">" + FloatElement("x", s.translation.x()) +
         FloatElement("y", s.translation.y()) + FloatElement("z", s.translation.z()) +
         "</translation></pose>\n";
}

std::string LimitsXml(const ScanDesc& s) {
  std::string xml;
  if (s.intensity_limits) {
    xml += "<intensityLimits type=\"Structure\">" +
           FloatElement("intensityMinimum", s.intensity_limits->x()) +
           FloatElement("intensityMaximum", s.intensity_limits->y()) + "</intensityLimits>\n";
  }
  if (s.color_limits[0]) {
    xml += "<colorLimits type=\"Structure\">";
    const char* names[3] = {"Red", "Green", "Blue"};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d l = s.color_limits[k].value_or(s.color_limits[0].value());
      xml += FloatElement(std::string("color") + names[k] + "Minimum", l.x()) +
             FloatElement(std::string("color") + names[k] + "Maximum", l.y());
    }
    xml += "</colorLimits>\n";
  }
  return xml;
}

std::string ScanXml(const ScanDesc& s) {
  std::string xml = "<vectorChild type=\"Structure\">\n" + StringElement("guid", s.guid) + "\n";
  if (!s.name.empty()) xml += StringElement("name", s.name) + "\n";
  xml += PoseXml(s) + LimitsXml(s);
  xml += "<points type=\"CompressedVector\" fileOffset=\"" + std::to_string(s.section_offset) +
         "\" recordCount=\"" + std::to_string(s.record_count) + "\">\n<prototype type=\"Structure\">\n";
  for (const FieldDesc& f : s.fields) xml += "  " + PrototypeElement(f) + "\n";
  xml += "</prototype>\n<codecs type=\"Vector\" allowHeterogeneousChildren=\"1\"></codecs>\n"
         "</points>\n</vectorChild>\n";
  return xml;
}

std::string FileXml(const std::vector<ScanDesc>& scans, const std::string& guid,
                    const std::string& coordinate_metadata) {
  std::string xml =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<e57Root type=\"Structure\" xmlns=\"http://www.astm.org/COMMIT/E57/2010-e57-v1.0\">\n" +
      StringElement("formatName", "ASTM E57 3D Imaging Data File") + "\n" +
      StringElement("guid", guid.empty() ? NewGuid() : guid) + "\n" +
      "<versionMajor type=\"Integer\">1</versionMajor>\n"
      "<versionMinor type=\"Integer\">0</versionMinor>\n" +
      StringElement("e57LibraryVersion", kLibrary) + "\n";
  if (!coordinate_metadata.empty()) {
    xml += StringElement("coordinateMetadata", coordinate_metadata) + "\n";
  }
  xml += "<data3D type=\"Vector\" allowHeterogeneousChildren=\"1\">\n";
  for (const ScanDesc& s : scans) xml += ScanXml(s);
  xml += "</data3D>\n<images2D type=\"Vector\" allowHeterogeneousChildren=\"1\"></images2D>\n"
         "</e57Root>\n";
  return xml;
}

FieldDesc DescOf(const E57Field& field) {
  if (field.name.empty()) throw std::invalid_argument("E57Field::name is empty");
  FieldDesc d;
  d.name = field.name;
  switch (field.type) {
    case E57FieldType::kFloat: d.kind = FieldKind::kFloat, d.bits = 32; return d;
    case E57FieldType::kDouble: d.kind = FieldKind::kDouble, d.bits = 64; return d;
    case E57FieldType::kInteger: d.kind = FieldKind::kInteger; break;
    case E57FieldType::kScaledInteger: d.kind = FieldKind::kScaledInteger; break;
  }
  if (field.minimum > field.maximum) {
    throw std::invalid_argument("E57Field " + field.name + ": minimum " +
                                std::to_string(field.minimum) + " > maximum " +
                                std::to_string(field.maximum));
  }
  if (!(std::isfinite(field.scale) && field.scale != 0.0 && std::isfinite(field.offset))) {
    throw std::invalid_argument("E57Field " + field.name + ": scale must be finite and non-zero");
  }
  d.minimum = field.minimum, d.maximum = field.maximum;
  d.scale = field.scale, d.offset = field.offset;
  d.bits = e57::BitsForRange(d.minimum, d.maximum);
  return d;
}

ScanDesc WriteScan(e57::PagedWriter* out, const E57Scan& scan, size_t index,
                   const E57WriteOptions& options) {
  if (scan.fields.empty()) {
    throw std::invalid_argument("E57Scan " + std::to_string(index) + " has no fields");
  }
  ScanDesc d;
  d.name = scan.name;
  d.guid = scan.guid.empty() ? NewGuid() : scan.guid;
  d.rotation = scan.rotation.normalized();
  d.translation = scan.translation;
  d.intensity_limits = scan.intensity_limits;
  d.color_limits[0] = scan.color_limits;
  d.record_count = scan.fields[0].values.size();
  std::vector<const double*> columns;
  for (const E57Field& f : scan.fields) {
    if (f.values.size() != d.record_count) {
      throw std::invalid_argument("E57Scan " + std::to_string(index) + ": field " + f.name +
                                  " has " + std::to_string(f.values.size()) + " values, " +
                                  scan.fields[0].name + " " + std::to_string(d.record_count));
    }
    d.fields.push_back(DescOf(f));
    columns.push_back(f.values.data());
  }
  e57::SectionWriter section(out, d.fields, options.packet_records);
  section.Append(columns, d.record_count);
  section.Finish();
  d.section_offset = section.section_physical_offset();
  return d;
}

// ---- The streaming point writer ----

class E57PointWriter : public PointWriter {
 public:
  E57PointWriter(const std::string& path, const PointWriteSpec& spec,
                 const PointWriteOptions& options);
  void Write(const PointCloud& chunk) override;
  void Close() override;

 private:
  void WriteBlock(const PointCloud& chunk, size_t first, size_t n, const Eigen::Vector3d& delta);

  std::string path_;
  PointWriteSpec spec_;
  std::vector<FieldDesc> fields_;
  int intensity_ = -1, time_ = -1;  // scalar indices in the schema
  Eigen::Vector2d intensity_range_{INFINITY, -INFINITY};
  std::vector<std::vector<double>> columns_;
  std::unique_ptr<e57::PagedWriter> out_;
  std::unique_ptr<e57::SectionWriter> section_;
  bool closed_ = false, failed_ = false;
};

FieldDesc Field(const std::string& name, FieldKind kind, int64_t lo = 0, int64_t hi = 0) {
  FieldDesc f;
  f.name = name;
  f.kind = kind;
  f.minimum = lo, f.maximum = hi;
  f.bits = kind == FieldKind::kFloat    ? 32
           : kind == FieldKind::kDouble ? 64
                                        : e57::BitsForRange(lo, hi);
  return f;
}

E57PointWriter::E57PointWriter(const std::string& path, const PointWriteSpec& spec,
                               const PointWriteOptions& options)
    : path_(path), spec_(spec) {
  const PointSchema& schema = spec.schema;
  const bool wide = options.precision == PositionPrecision::kFloat64 ||
                    (options.precision == PositionPrecision::kAuto &&
                     (!spec.frame.IsIdentity() || schema.position_type == ScalarType::kFloat64));
  const FieldKind xyz = wide ? FieldKind::kDouble : FieldKind::kFloat;
  for (const char* name : {"cartesianX", "cartesianY", "cartesianZ"}) fields_.push_back(Field(name, xyz));
  if (schema.colors) {
    for (const char* name : {"colorRed", "colorGreen", "colorBlue"}) {
      fields_.push_back(Field(name, FieldKind::kInteger, 0, 255));
    }
  }
  intensity_ = schema.ScalarIndex("intensity");
  time_ = schema.ScalarIndex("time_stamp");
  if (intensity_ >= 0) fields_.push_back(Field("intensity", FieldKind::kFloat));
  if (time_ >= 0) fields_.push_back(Field("timeStamp", FieldKind::kDouble));
  std::string dropped = schema.normals ? " normals" : "";
  for (const ScalarFieldSpec& s : schema.scalars) {
    if (s.name != "intensity" && s.name != "time_stamp") dropped += " " + s.name;
  }
  if (!dropped.empty()) LogInfo(path + ": E57 has no place for:" + dropped + "; not written");
  columns_.resize(fields_.size());
  out_ = std::make_unique<e57::PagedWriter>(path);
  section_ = std::make_unique<e57::SectionWriter>(out_.get(), fields_);
}

void E57PointWriter::WriteBlock(const PointCloud& chunk, size_t first, size_t n,
                                const Eigen::Vector3d& delta) {
  for (auto& c : columns_) c.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = chunk.positions[first + i];
    for (int k = 0; k < 3; ++k) columns_[k][i] = p[k] + delta[k];
  }
  size_t f = 3;
  if (spec_.schema.colors) {
    for (size_t i = 0; i < n; ++i) {
      const Rgb8& c = chunk.colors[first + i];
      columns_[3][i] = c.r, columns_[4][i] = c.g, columns_[5][i] = c.b;
    }
    f = 6;
  }
  if (intensity_ >= 0) {
    const ScalarField& s = chunk.scalars[intensity_];
    for (size_t i = 0; i < n; ++i) {
      const double v = static_cast<float>(s.Get(first + i));
      columns_[f][i] = v;
      intensity_range_[0] = std::min(intensity_range_[0], v);
      intensity_range_[1] = std::max(intensity_range_[1], v);
    }
    ++f;
  }
  if (time_ >= 0) {
    const ScalarField& s = chunk.scalars[time_];
    for (size_t i = 0; i < n; ++i) columns_[f][i] = s.Get(first + i);
  }
  std::vector<const double*> pointers;
  for (const auto& c : columns_) pointers.push_back(c.data());
  section_->Append(pointers, n);
}

void E57PointWriter::Write(const PointCloud& chunk) {
  CANDI_CHECK(!closed_) << "E57 writer: Write after Close";
  CANDI_CHECK(!failed_) << "E57 writer: Write after a failed Write";
  CANDI_CHECK(chunk.schema == spec_.schema) << "chunk schema differs from the writer's spec";
  chunk.CheckConsistent();
  const Eigen::Vector3d delta = chunk.frame.origin - spec_.frame.origin;
  failed_ = true;
  for (size_t first = 0; first < chunk.size(); first += kBlock) {
    WriteBlock(chunk, first, std::min(kBlock, chunk.size() - first), delta);
  }
  failed_ = false;
  points_written_ += chunk.size();
}

void E57PointWriter::Close() {
  CANDI_CHECK(!closed_) << "E57 writer: Close twice";
  CANDI_CHECK(!failed_) << "E57 writer: Close after a failed Write";
  closed_ = true;
  section_->Finish();
  ScanDesc scan;
  scan.guid = NewGuid();
  scan.translation = spec_.frame.origin;  // positions are written in the spec's frame
  scan.section_offset = section_->section_physical_offset();
  scan.record_count = section_->records();
  scan.fields = fields_;
  if (spec_.schema.colors) scan.color_limits[0] = Eigen::Vector2d(0, 255);
  if (intensity_ >= 0) {
    scan.intensity_limits = points_written_ > 0 ? intensity_range_ : Eigen::Vector2d(0, 0);
  }
  out_->Finish(FileXml({scan}, "", spec_.meta.crs));
}

}  // namespace

void WriteE57(const std::string& path, const std::vector<E57Scan>& scans,
              const E57WriteOptions& options) {
  options.Check();
  for (size_t i = 0; i < scans.size(); ++i) {
    if (scans[i].fields.empty()) {
      throw std::invalid_argument("E57Scan " + std::to_string(i) + " has no fields");
    }
    for (const E57Field& f : scans[i].fields) DescOf(f);  // validate before creating the file
  }
  e57::PagedWriter out(path);
  std::vector<ScanDesc> written;
  for (size_t i = 0; i < scans.size(); ++i) written.push_back(WriteScan(&out, scans[i], i, options));
  out.Finish(FileXml(written, options.guid, options.coordinate_metadata));
}

std::unique_ptr<PointWriter> OpenE57Writer(const std::string& path, const PointWriteSpec& spec,
                                           const PointWriteOptions& options) {
  options.Check();
  return std::make_unique<E57PointWriter>(path, spec, options);
}

}  // namespace candi::io
