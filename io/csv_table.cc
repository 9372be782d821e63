#include "io/csv_table.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

#include "core/atomic_file.h"
#include "core/check.h"

namespace candi::io {

namespace {

std::string Trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (;;) {
    const size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma == std::string::npos ? comma : comma - start)));
    if (comma == std::string::npos) return fields;
    start = comma + 1;
  }
}

std::string Line(int line) { return "line " + std::to_string(line); }

}  // namespace

CsvTable CsvTable::Read(const std::string& path, const std::vector<std::string>& required) {
  return Parse(path, ReadFileToString(path), required);
}

CsvTable CsvTable::Parse(const std::string& path, const std::string& text,
                         const std::vector<std::string>& required) {
  CsvTable table;
  table.path_ = path;
  int line_number = 0;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = Trim(text.substr(start, end - start));
    start = end + 1;
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> fields = Split(line);
    if (table.header_.empty()) {
      for (std::string& f : fields) table.header_.push_back(Lower(f));
      for (const std::string& name : required) {
        if (table.Column(name) < 0) {
          throw InputError(path, Line(line_number), "header lacks the column '" + name + "'");
        }
      }
      continue;
    }
    if (fields.size() != table.header_.size()) {
      throw InputError(path, Line(line_number),
                       std::to_string(fields.size()) + " fields; the header has " +
                           std::to_string(table.header_.size()));
    }
    table.rows_.push_back({line_number, std::move(fields)});
  }
  if (table.header_.empty()) throw InputError(path, "", "empty: no header row");
  return table;
}

int CsvTable::Column(const std::string& column) const {
  const auto it = std::find(header_.begin(), header_.end(), Lower(column));
  return it == header_.end() ? -1 : static_cast<int>(it - header_.begin());
}

const std::string& CsvTable::Text(const Row& row, const std::string& column) const {
  const int c = Column(column);
  CANDI_CHECK(c >= 0) << "no column " << column;
  return row.fields[static_cast<size_t>(c)];
}

double CsvTable::Number(const Row& row, const std::string& column) const {
  const std::string& text = Text(row, column);
  double v = 0;
  const char* end = text.data() + text.size();
  const auto [next, ec] = std::from_chars(text.data(), end, v);
  if (text.empty() || ec != std::errc() || next != end || !std::isfinite(v)) {
    Fail(row, column, "'" + text + "' is not a finite number");
  }
  return v;
}

void CsvTable::Fail(const Row& row, const std::string& column, const std::string& message) const {
  throw InputError(path_, Line(row.line), "field '" + column + "': " + message);
}

}  // namespace candi::io
