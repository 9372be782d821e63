// E57 XML section: the scans (data3D), their poses, prototypes and codecs, parsed with pugixml.
#include <pugixml.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "core/check.h"
#include "io/e57/e57_format.h"

namespace candi::io::e57 {

namespace {

// Element positions for messages: "XML line N, <path>".
class XmlContext {
 public:
  XmlContext(const std::string& path, const std::string& xml) : path_(path), xml_(xml) {}

  int LineOf(ptrdiff_t offset) const {
    if (offset < 0) return 0;
    const size_t end = std::min<size_t>(static_cast<size_t>(offset), xml_.size());
    return 1 + static_cast<int>(std::count(xml_.begin(), xml_.begin() + end, '\n'));
  }
  std::string Where(const pugi::xml_node& node, const std::string& element) const {
    return "XML line " + std::to_string(LineOf(node.offset_debug())) + ", " + element;
  }
  [[noreturn]] void Fail(const pugi::xml_node& node, const std::string& element,
                         const std::string& what) const {
    throw InputError(path_, Where(node, element), what);
  }

  pugi::xml_node Child(const pugi::xml_node& node, const std::string& element,
                       const char* name) const {
    pugi::xml_node child = node.child(name);
    if (!child) Fail(node, element, std::string("missing required element <") + name + ">");
    return child;
  }

  int64_t Integer(const pugi::xml_node& node, const std::string& element) const {
    return ParseInteger(node, element, node.child_value(), 0);
  }
  int64_t ParseInteger(const pugi::xml_node& node, const std::string& element, const char* text,
                       int64_t fallback) const {
    while (*text == ' ' || *text == '\n' || *text == '\t' || *text == '\r') ++text;
    if (*text == '\0') return fallback;  // an empty element holds the default value
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(text, &end, 10);
    while (end && (*end == ' ' || *end == '\n' || *end == '\t' || *end == '\r')) ++end;
    if (errno != 0 || end == text || *end != '\0') {
      Fail(node, element, std::string("'") + text + "' is not a 64-bit integer");
    }
    return v;
  }
  double Float(const pugi::xml_node& node, const std::string& element) const {
    const char* text = node.child_value();
    while (*text == ' ' || *text == '\n' || *text == '\t' || *text == '\r') ++text;
    if (*text == '\0') return 0.0;
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    while (end && (*end == ' ' || *end == '\n' || *end == '\t' || *end == '\r')) ++end;
    if (end == text || *end != '\0' || !std::isfinite(v)) {
      Fail(node, element, std::string("'") + text + "' is not a finite number");
    }
    return v;
  }
  // A number element of type Integer, ScaledInteger or Float.
  double Number(const pugi::xml_node& node, const std::string& element) const {
    const std::string type = node.attribute("type").value();
    if (type == "Float") return Float(node, element);
    if (type == "Integer") return static_cast<double>(Integer(node, element));
    if (type == "ScaledInteger") {
      return static_cast<double>(Integer(node, element)) * node.attribute("scale").as_double(1.0) +
             node.attribute("offset").as_double(0.0);
    }
    Fail(node, element, "expected a number (Integer, ScaledInteger or Float), found type '" +
                            type + "'");
  }
  // The text of a String element: CDATA sections and text joined (a "]]>" in a string is written
  // as two CDATA sections).
  std::string Text(const pugi::xml_node& node) const {
    std::string text;
    for (pugi::xml_node part : node.children()) {
      if (part.type() == pugi::node_pcdata || part.type() == pugi::node_cdata) text += part.value();
    }
    return text;
  }

 private:
  const std::string& path_;
  const std::string& xml_;
};

int64_t IntAttribute(const XmlContext& c, const pugi::xml_node& node, const std::string& element,
                     const char* name, int64_t fallback) {
  const pugi::xml_attribute a = node.attribute(name);
  return a ? c.ParseInteger(node, element + " @" + name, a.value(), fallback) : fallback;
}

void ParseLeaf(const XmlContext& c, const pugi::xml_node& node, const std::string& name,
               const std::string& element, std::vector<FieldDesc>* fields) {
  FieldDesc f;
  f.name = name;
  const std::string type = node.attribute("type").value();
  if (type == "Float") {
    const std::string precision = node.attribute("precision").value();
    if (!precision.empty() && precision != "single" && precision != "double") {
      c.Fail(node, element, "Float precision '" + precision + "' (must be single or double)");
    }
    f.kind = precision == "single" ? FieldKind::kFloat : FieldKind::kDouble;
    f.bits = f.kind == FieldKind::kFloat ? 32 : 64;
  } else if (type == "Integer" || type == "ScaledInteger") {
    f.kind = type == "Integer" ? FieldKind::kInteger : FieldKind::kScaledInteger;
    f.minimum = IntAttribute(c, node, element, "minimum", INT64_MIN);
    f.maximum = IntAttribute(c, node, element, "maximum", INT64_MAX);
    if (f.maximum < f.minimum) {
      c.Fail(node, element, "maximum " + std::to_string(f.maximum) + " < minimum " +
                                std::to_string(f.minimum));
    }
    f.bits = BitsForRange(f.minimum, f.maximum);  // at most 64 for int64 bounds
    if (f.kind == FieldKind::kScaledInteger) {
      f.scale = node.attribute("scale").as_double(1.0);
      f.offset = node.attribute("offset").as_double(0.0);
      if (!std::isfinite(f.scale) || f.scale == 0.0 || !std::isfinite(f.offset)) {
        c.Fail(node, element, "ScaledInteger scale must be finite and non-zero, offset finite");
      }
    }
  } else {
    c.Fail(node, element, "prototype field of type '" + type +
                              "' is not supported (Integer, ScaledInteger or Float)");
  }
  fields->push_back(f);
}

// Prototype leaves in depth-first order: the order of the bytestreams.
void ParsePrototype(const XmlContext& c, const pugi::xml_node& node, const std::string& prefix,
                    const std::string& element, int depth, std::vector<FieldDesc>* fields) {
  if (depth > 16) c.Fail(node, element, "prototype nested too deeply");
  for (pugi::xml_node child : node.children()) {
    if (child.type() != pugi::node_element) continue;
    const std::string name = prefix + child.name();
    const std::string where = element + "/" + child.name();
    const std::string type = child.attribute("type").value();
    if (type == "Structure") {
      ParsePrototype(c, child, name + "/", where, depth + 1, fields);
    } else if (type == "Vector") {
      c.Fail(child, where, "Vector fields in a prototype are not supported");
    } else {
      ParseLeaf(c, child, name, where, fields);
    }
    if (fields->size() > 4096) c.Fail(node, element, "more than 4096 prototype fields");
  }
}

void CheckCodecs(const XmlContext& c, const pugi::xml_node& codecs, const std::string& element) {
  int i = 0;
  for (pugi::xml_node codec : codecs.children()) {
    if (codec.type() != pugi::node_element) continue;
    const std::string where = element + "/" + std::to_string(i++);
    for (pugi::xml_node part : codec.children()) {
      if (part.type() != pugi::node_element) continue;
      const std::string name = part.name();
      if (name != "inputs" && name != "bitPackCodec") {
        c.Fail(part, where, "unsupported E57 codec '" + name + "' (only bitPackCodec)");
      }
    }
  }
}

void ParsePose(const XmlContext& c, const pugi::xml_node& pose, const std::string& element,
               ScanDesc* scan) {
  if (pugi::xml_node r = pose.child("rotation")) {
    const std::string where = element + "/rotation";
    Eigen::Quaterniond q(c.Number(c.Child(r, where, "w"), where + "/w"),
                         c.Number(c.Child(r, where, "x"), where + "/x"),
                         c.Number(c.Child(r, where, "y"), where + "/y"),
                         c.Number(c.Child(r, where, "z"), where + "/z"));
    if (!(q.norm() > 1e-9)) c.Fail(r, where, "rotation quaternion has zero length");
    scan->rotation = q.normalized();
  }
  if (pugi::xml_node t = pose.child("translation")) {
    const std::string where = element + "/translation";
    scan->translation = Eigen::Vector3d(c.Number(c.Child(t, where, "x"), where + "/x"),
                                        c.Number(c.Child(t, where, "y"), where + "/y"),
                                        c.Number(c.Child(t, where, "z"), where + "/z"));
  }
}

std::optional<Eigen::Vector2d> Limits(const XmlContext& c, const pugi::xml_node& parent,
                                      const std::string& element, const std::string& min_name,
                                      const std::string& max_name) {
  pugi::xml_node lo = parent.child(min_name.c_str()), hi = parent.child(max_name.c_str());
  if (!lo || !hi) return std::nullopt;
  return Eigen::Vector2d(c.Number(lo, element + "/" + min_name),
                         c.Number(hi, element + "/" + max_name));
}

void ParseLimits(const XmlContext& c, const pugi::xml_node& node, const std::string& element,
                 ScanDesc* scan) {
  if (pugi::xml_node l = node.child("intensityLimits")) {
    scan->intensity_limits =
        Limits(c, l, element + "/intensityLimits", "intensityMinimum", "intensityMaximum");
  }
  if (pugi::xml_node l = node.child("colorLimits")) {
    const char* names[3] = {"Red", "Green", "Blue"};
    for (int k = 0; k < 3; ++k) {
      const std::string n = names[k];
      scan->color_limits[k] =
          Limits(c, l, element + "/colorLimits", "color" + n + "Minimum", "color" + n + "Maximum");
    }
  }
}

void CheckRecordCount(const XmlContext& c, const pugi::xml_node& points, const std::string& element,
                      const ScanDesc& scan, uint64_t physical_length) {
  uint64_t bits = 0;
  for (const FieldDesc& f : scan.fields) bits += static_cast<uint64_t>(f.bits);
  // Each record takes at least `bits` bits of packet payload, all inside the file.
  const long double needed = static_cast<long double>(scan.record_count) * bits / 8.0L;
  const bool absurd = bits > 0 ? needed > static_cast<long double>(physical_length)
                               : scan.record_count > (uint64_t{1} << 32);
  if (absurd) {
    c.Fail(points, element,
           "recordCount " + std::to_string(scan.record_count) + " needs at least " +
               std::to_string(static_cast<unsigned long long>(needed)) +
               " bytes of point data but the file has " + std::to_string(physical_length) +
               " bytes (records of 0 bits: at most 2^32)");
  }
}

ScanDesc ParseScan(const XmlContext& c, const pugi::xml_node& node, size_t index,
                   uint64_t physical_length) {
  ScanDesc scan;
  scan.element = "/data3D/" + std::to_string(index);
  scan.line = c.LineOf(node.offset_debug());
  scan.guid = c.Text(node.child("guid"));
  scan.name = c.Text(node.child("name"));
  scan.description = c.Text(node.child("description"));
  if (pugi::xml_node pose = node.child("pose")) ParsePose(c, pose, scan.element + "/pose", &scan);
  ParseLimits(c, node, scan.element, &scan);
  const std::string pe = scan.element + "/points";
  pugi::xml_node points = c.Child(node, scan.element, "points");
  if (std::string(points.attribute("type").value()) != "CompressedVector") {
    c.Fail(points, pe, "points must be a CompressedVector");
  }
  const int64_t offset = IntAttribute(c, points, pe, "fileOffset", -1);
  const int64_t count = IntAttribute(c, points, pe, "recordCount", -1);
  if (offset < 0 || count < 0) c.Fail(points, pe, "missing or negative fileOffset or recordCount");
  scan.section_offset = static_cast<uint64_t>(offset);
  scan.record_count = static_cast<uint64_t>(count);
  ParsePrototype(c, c.Child(points, pe, "prototype"), "", pe + "/prototype", 0, &scan.fields);
  if (pugi::xml_node codecs = points.child("codecs")) CheckCodecs(c, codecs, pe + "/codecs");
  CheckRecordCount(c, points, pe, scan, physical_length);
  return scan;
}

}  // namespace

int ScanDesc::FieldIndex(const std::string& field) const {
  for (size_t i = 0; i < fields.size(); ++i) {
    if (fields[i].name == field) return static_cast<int>(i);
  }
  return -1;
}

FileDesc ParseE57Xml(const std::string& path, const std::string& xml, uint64_t physical_length) {
  pugi::xml_document doc;
  const pugi::xml_parse_result result = doc.load_buffer(xml.data(), xml.size());
  XmlContext c(path, xml);
  if (!result) {
    throw InputError(path, "XML line " + std::to_string(c.LineOf(result.offset)),
                     std::string("E57 XML parse error: ") + result.description());
  }
  pugi::xml_node root = doc.child("e57Root");
  if (!root) throw InputError(path, "XML line 1", "missing the <e57Root> element");
  FileDesc file;
  file.major = static_cast<int>(c.Integer(c.Child(root, "/", "versionMajor"), "/versionMajor"));
  if (pugi::xml_node minor = root.child("versionMinor")) {
    file.minor = static_cast<int>(c.Integer(minor, "/versionMinor"));
  }
  file.guid = c.Text(root.child("guid"));
  file.library = c.Text(root.child("e57LibraryVersion"));
  file.coordinate_metadata = c.Text(root.child("coordinateMetadata"));
  if (pugi::xml_node data3d = root.child("data3D")) {
    for (pugi::xml_node scan : data3d.children()) {
      if (scan.type() != pugi::node_element) continue;
      file.scans.push_back(ParseScan(c, scan, file.scans.size(), physical_length));
    }
  }
  if (pugi::xml_node images = root.child("images2D")) {
    for (pugi::xml_node image : images.children()) {
      if (image.type() == pugi::node_element) ++file.images;
    }
  }
  return file;
}

}  // namespace candi::io::e57
