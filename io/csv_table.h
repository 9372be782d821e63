// CsvTable: a small comma-separated table with a required header row, for the survey-target,
// image-pick and colour-patch files of photogrammetry, relief placement's correspondences and the
// scan targets of `candi register-scans`.
//
// Format: UTF-8/ASCII text; the first non-blank line that is not a comment is the header (column
// names, matched case-insensitively, surrounding blanks ignored); every further non-blank line is a
// row with exactly as many comma-separated fields as the header. Lines starting with '#' are
// comments. CRLF line ends are accepted. Fields are not quoted (names must not contain commas).
//
// Failure: every error throws candi::InputError "<path>: line N: <what>" naming the field.
#pragma once

#include <string>
#include <vector>

namespace candi::io {

class CsvTable {
 public:
  struct Row {
    int line = 0;                     // 1-based line number in the file
    std::vector<std::string> fields;  // trimmed, one per header column
  };

  // Reads `path`; throws InputError when it cannot be read, has no header, lacks one of
  // `required` columns (names compared case-insensitively) or has a row of the wrong width.
  static CsvTable Read(const std::string& path, const std::vector<std::string>& required);
  // Parses `text` as if read from `path` (for tests and generated tables).
  static CsvTable Parse(const std::string& path, const std::string& text,
                        const std::vector<std::string>& required);

  const std::string& path() const { return path_; }
  const std::vector<Row>& rows() const { return rows_; }
  bool Has(const std::string& column) const { return Column(column) >= 0; }
  int Column(const std::string& column) const;  // -1 when absent

  // The field's text (the column must exist: CANDI_CHECK).
  const std::string& Text(const Row& row, const std::string& column) const;
  // The field as a finite number; throws InputError "<path>: line N: field 'E': 'x' is not a
  // finite number" (also for an empty field).
  double Number(const Row& row, const std::string& column) const;
  // Throws InputError "<path>: line N: field '<column>': <message>".
  [[noreturn]] void Fail(const Row& row, const std::string& column,
                         const std::string& message) const;

 private:
  std::string path_;
  std::vector<std::string> header_;  // lower case
  std::vector<Row> rows_;
};

}  // namespace candi::io
