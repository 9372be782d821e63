#include "io/ply/ply_header.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <sstream>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/text_format.h"

namespace candi::io::ply {

size_t TypeSize(Type type) {
  switch (type) {
    case Type::kInt8: case Type::kUint8: return 1;
    case Type::kInt16: case Type::kUint16: return 2;
    case Type::kInt32: case Type::kUint32: case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 0;
}

const char* TypeName(Type type) {
  switch (type) {
    case Type::kInt8: return "char";
    case Type::kUint8: return "uchar";
    case Type::kInt16: return "short";
    case Type::kUint16: return "ushort";
    case Type::kInt32: return "int";
    case Type::kUint32: return "uint";
    case Type::kFloat32: return "float";
    case Type::kFloat64: return "double";
  }
  return "?";
}

bool ParseType(const std::string& name, Type* type) {
  static const struct { const char* name; Type type; } kNames[] = {
      {"char", Type::kInt8},     {"int8", Type::kInt8},       {"uchar", Type::kUint8},
      {"uint8", Type::kUint8},   {"short", Type::kInt16},     {"int16", Type::kInt16},
      {"ushort", Type::kUint16}, {"uint16", Type::kUint16},   {"int", Type::kInt32},
      {"int32", Type::kInt32},   {"uint", Type::kUint32},     {"uint32", Type::kUint32},
      {"float", Type::kFloat32}, {"float32", Type::kFloat32}, {"double", Type::kFloat64},
      {"float64", Type::kFloat64}};
  for (const auto& entry : kNames) {
    if (name == entry.name) {
      *type = entry.type;
      return true;
    }
  }
  return false;
}

bool Element::HasLists() const {
  for (const Property& p : properties) {
    if (p.is_list) return true;
  }
  return false;
}

size_t Element::FixedSize() const {
  size_t size = 0;
  for (const Property& p : properties) size += p.is_list ? TypeSize(p.count_type) : TypeSize(p.type);
  return size;
}

int Header::FindElement(const std::string& name) const {
  for (size_t i = 0; i < elements.size(); ++i) {
    if (elements[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

namespace {

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> words;
  std::istringstream in(line);
  std::string word;
  while (in >> word) words.push_back(word);
  return words;
}

// Context for errors: the path and the current header line.
struct HeaderParser {
  BinaryFile& file;
  Header header;
  int line_number = 0;

  [[noreturn]] void Fail(const std::string& message) const {
    throw InputError(file.path(), "line " + std::to_string(line_number), message);
  }
  Type ParseTypeOrFail(const std::string& name) const {
    Type type;
    if (!ParseType(name, &type)) Fail("unknown property type '" + name + "'");
    return type;
  }
  void ParseFormat(const std::vector<std::string>& words);
  void ParseElement(const std::vector<std::string>& words);
  void ParseProperty(const std::vector<std::string>& words);
  void ParseComment(const std::string& line);
  void CheckBodyFits() const;
};

void HeaderParser::ParseFormat(const std::vector<std::string>& words) {
  if (words.size() != 3) Fail("expected 'format <encoding> 1.0'");
  if (words[1] == "ascii") header.encoding = PlyEncoding::kAscii;
  else if (words[1] == "binary_little_endian") header.encoding = PlyEncoding::kBinaryLittleEndian;
  else if (words[1] == "binary_big_endian") header.encoding = PlyEncoding::kBinaryBigEndian;
  else Fail("unknown PLY format '" + words[1] + "'");
  if (words[2] != "1.0") Fail("unsupported PLY version '" + words[2] + "' (expected 1.0)");
}

void HeaderParser::ParseElement(const std::vector<std::string>& words) {
  if (words.size() != 3) Fail("expected 'element <name> <count>'");
  Element element;
  element.name = words[1];
  const std::string& text = words[2];
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), element.count);
  if (ec != std::errc() || end != text.data() + text.size()) {
    Fail("element '" + element.name + "' count '" + text + "' is not a non-negative integer");
  }
  if (header.FindElement(element.name) >= 0) Fail("element '" + element.name + "' appears twice");
  header.elements.push_back(element);
}

void HeaderParser::ParseProperty(const std::vector<std::string>& words) {
  if (header.elements.empty()) Fail("property before any element");
  Property property;
  if (words.size() >= 2 && words[1] == "list") {
    if (words.size() != 5) Fail("expected 'property list <count type> <type> <name>'");
    property.is_list = true;
    property.count_type = ParseTypeOrFail(words[2]);
    if (property.count_type == Type::kFloat32 || property.count_type == Type::kFloat64) {
      Fail("list count type must be an integer type, not '" + words[2] + "'");
    }
    property.type = ParseTypeOrFail(words[3]);
    property.name = words[4];
  } else {
    if (words.size() != 3) Fail("expected 'property <type> <name>'");
    property.type = ParseTypeOrFail(words[1]);
    property.name = words[2];
  }
  Element& element = header.elements.back();
  for (const Property& p : element.properties) {
    if (p.name == property.name) Fail("property '" + property.name + "' appears twice");
  }
  element.properties.push_back(property);
}

void HeaderParser::ParseComment(const std::string& line) {
  const std::string text = line.size() > 8 ? line.substr(8) : "";
  const std::vector<std::string> words = Split(text);
  if (!words.empty() && words[0] == "candi_shift") {
    if (words.size() != 4) Fail("'comment candi_shift' needs three numbers");
    LocalFrame frame;
    for (int k = 0; k < 3; ++k) {
      const std::string& w = words[k + 1];
      auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), frame.origin[k]);
      if (ec != std::errc() || end != w.data() + w.size() || !std::isfinite(frame.origin[k])) {
        Fail("candi_shift component '" + w + "' is not a finite number");
      }
    }
    header.shift = frame;
    return;
  }
  if (!words.empty() && words[0] == "candi_crs") {
    // The rest of the line after the keyword (WKT holds spaces).
    const size_t at = text.find_first_not_of(" \t", text.find("candi_crs") + 9);
    header.crs = at == std::string::npos ? "" : text.substr(at);
    while (!header.crs.empty() && std::isspace(static_cast<unsigned char>(header.crs.back()))) header.crs.pop_back();
    return;
  }
  header.comments.push_back(text);
}

// A lower bound of the body size; a header whose counts need more than the file holds is refused
// here, before anything is allocated (a header may claim 10^12 vertices).
void HeaderParser::CheckBodyFits() const {
  const uint64_t available = file.size() - header.data_offset;
  unsigned __int128 needed = 0;
  for (const Element& element : header.elements) {
    // ASCII: at least one character and one separator per value.
    const uint64_t per_record = header.encoding == PlyEncoding::kAscii
                                    ? 2 * element.properties.size()
                                    : element.FixedSize();
    needed += static_cast<unsigned __int128>(element.count) * per_record;
    if (needed > available) {
      throw InputError(file.path(), "byte " + std::to_string(header.data_offset),
                       "header promises " + std::to_string(element.count) + " " + element.name +
                           " records, more than the " + std::to_string(available) +
                           " bytes after the header can hold (truncated file?)");
    }
  }
}

}  // namespace

Header ParseHeader(BinaryFile& file) {
  HeaderParser parser{file, {}, 0};
  std::string line;
  bool saw_format = false;
  constexpr int kMaxHeaderLines = 100000;
  while (true) {
    if (!file.ReadLine(&line)) {
      parser.line_number++;
      parser.Fail("end of file inside the header (no end_header)");
    }
    parser.line_number++;
    if (parser.line_number > kMaxHeaderLines) parser.Fail("header longer than 100000 lines");
    if (parser.line_number == 1) {
      if (line != "ply") parser.Fail("not a PLY file (first line is not 'ply')");
      continue;
    }
    const std::vector<std::string> words = Split(line);
    if (words.empty()) continue;
    if (words[0] == "end_header") break;
    if (words[0] == "comment" || words[0] == "obj_info") {
      if (words[0] == "comment") parser.ParseComment(line);
      continue;
    }
    if (words[0] == "format") {
      if (saw_format) parser.Fail("second format line");
      parser.ParseFormat(words);
      saw_format = true;
    } else if (!saw_format) {
      parser.Fail("'" + words[0] + "' before the format line");
    } else if (words[0] == "element") {
      parser.ParseElement(words);
    } else if (words[0] == "property") {
      parser.ParseProperty(words);
    } else {
      parser.Fail("unknown header keyword '" + words[0] + "'");
    }
  }
  parser.header.header_lines = parser.line_number;
  parser.header.data_offset = file.position();
  parser.CheckBodyFits();
  return parser.header;
}

std::string FormatHeader(const Header& header, int vertex_count_width) {
  std::string text = "ply\nformat ";
  switch (header.encoding) {
    case PlyEncoding::kAscii: text += "ascii 1.0\n"; break;
    case PlyEncoding::kBinaryLittleEndian: text += "binary_little_endian 1.0\n"; break;
    case PlyEncoding::kBinaryBigEndian: text += "binary_big_endian 1.0\n"; break;
  }
  for (const std::string& c : header.comments) text += "comment " + c + "\n";
  if (header.shift && !header.shift->IsIdentity()) {
    text += "comment candi_shift " + FormatDouble(header.shift->origin.x()) + " " +
            FormatDouble(header.shift->origin.y()) + " " + FormatDouble(header.shift->origin.z()) + "\n";
  }
  if (!header.crs.empty()) {
    std::string crs = header.crs;  // one line: WKT's line breaks are white space
    for (char& c : crs) c = (c == '\n' || c == '\r') ? ' ' : c;
    text += "comment candi_crs " + crs + "\n";
  }
  for (const Element& element : header.elements) {
    std::string count = std::to_string(element.count);
    if (element.name == "vertex" && vertex_count_width > static_cast<int>(count.size())) {
      count.append(vertex_count_width - count.size(), ' ');
    }
    text += "element " + element.name + " " + count + "\n";
    for (const Property& p : element.properties) {
      text += "property ";
      if (p.is_list) text += std::string("list ") + TypeName(p.count_type) + " ";
      text += std::string(TypeName(p.type)) + " " + p.name + "\n";
    }
  }
  return text + "end_header\n";
}

}  // namespace candi::io::ply
