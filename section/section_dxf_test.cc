#include "section/section_dxf.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "core/check.h"
#include "mesh/dxf_import.h"
#include "tests/util/input_error.h"
#include "tests/util/test_util.h"

namespace candi::section {
namespace {

using testing::InputErrorMessage;
using testing::ReadBytes;
using testing::TempDir;
using testing::WriteBytes;
using V = Eigen::Vector2d;

Polyline2 Line(std::vector<V> points, bool closed = false) { return {std::move(points), closed}; }

struct Group {
  int code;
  std::string value;
};

// The file's group code / value pairs.
std::vector<Group> Groups(const std::string& text) {
  std::istringstream in(text);
  std::vector<Group> groups;
  std::string code, value;
  while (std::getline(in, code) && std::getline(in, value))
    groups.push_back({std::stoi(code), value});
  return groups;
}

struct LayerRecord {
  std::string name;
  int aci = 0;
  long true_colour = -1;
};

// The LAYER table's records (ReadDxf lists only layers holding pieces).
std::vector<LayerRecord> LayerTable(const std::string& text) {
  std::vector<LayerRecord> records;
  bool in_record = false;
  for (const Group& g : Groups(text)) {
    if (g.code == 0) {
      in_record = g.value == "LAYER";
      if (in_record) records.emplace_back();
    } else if (in_record && g.code == 2) {
      records.back().name = g.value;
    } else if (in_record && g.code == 62) {
      records.back().aci = std::stoi(g.value);
    } else if (in_record && g.code == 420) {
      records.back().true_colour = std::stol(g.value);
    }
  }
  return records;
}

std::vector<std::string> Names(const std::vector<LayerRecord>& records) {
  std::vector<std::string> names;
  for (const LayerRecord& r : records) names.push_back(r.name);
  return names;
}

size_t Entries(const std::string& dir) {
  size_t n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) n += entry.exists();
  return n;
}

mesh::DxfDrawing WriteAndRead(const TempDir& dir, const std::vector<DxfLayerLines>& layers,
                        const DxfWriteOptions& options = {}) {
  WriteSectionDxf(options, layers, dir.File("s.dxf"));
  return mesh::ReadDxf(mesh::DxfReadOptions{}, dir.File("s.dxf"));
}

TEST(DxfWriteOptions, DefaultsPass) { EXPECT_NO_THROW(DxfWriteOptions().Check()); }

TEST(WriteSectionDxf, RoundTripKeepsLayersVerticesAndClosedFlags) {
  TempDir dir;
  const std::vector<DxfLayerLines> layers = {
      {"Section A",
       0xff0000,
       {Line({V(-2.5, 0), V(-1.25, 3.125), V(0.1, 3.3), V(2.5, 0.001)}),
        Line({V(0, 0), V(1, 0), V(0.5, 0.7)}, true)}},
      {"Section B",
       0x00ff00,
       {Line({V(1.0 / 3, -2.0 / 3), V(10.0 / 3, -2.0 / 3), V(10.0 / 3, 7.1), V(1.0 / 3, 7.1)},
             true),
        Line({V(5, 5)}), Line({}), Line({V(-1e-3, 1e-4), V(123.456789, -98.7654321)})}}};
  const mesh::DxfDrawing d = WriteAndRead(dir, layers);
  EXPECT_EQ(d.LayerNames(), (std::vector<std::string>{"Section A", "Section B"}));
  EXPECT_EQ(d.insunits, 6);
  EXPECT_EQ(d.unit_name, "metre");
  EXPECT_EQ(d.metres_per_unit, 1.0);
  EXPECT_EQ(d.model.lwpolylines, 4u) << "the polylines of fewer than 2 points are skipped";
  EXPECT_EQ(d.model.Sections(), 4u);
  EXPECT_EQ(d.closed_polylines, 2u);
  for (const DxfLayerLines& layer : layers) {
    std::vector<Polyline2> written;
    for (const Polyline2& line : layer.lines) {
      if (line.points.size() >= 2) written.push_back(line);
    }
    const std::vector<Polyline2>& read = d.layers.at(layer.name);
    ASSERT_EQ(read.size(), written.size()) << layer.name;
    for (size_t i = 0; i < read.size(); ++i) {
      EXPECT_EQ(read[i].closed, written[i].closed) << layer.name << " " << i;
      ASSERT_EQ(read[i].points.size(), written[i].points.size()) << layer.name << " " << i;
      for (size_t k = 0; k < read[i].points.size(); ++k) {
        EXPECT_LE((read[i].points[k] - written[i].points[k]).cwiseAbs().maxCoeff(), 1e-9)
            << layer.name << " " << i << " " << k;
      }
    }
  }
}

TEST(WriteSectionDxf, SurveyCoordinatesKeepSubMillimetreDetail) {
  TempDir dir;
  const V origin(712345.6789, 9162345.1234);
  const std::vector<V> points = {origin, origin + V(0.0001, 0), origin + V(0.0005, 0.0003),
                                 origin + V(1.2345, -0.0007), origin + V(-250.0004, 31.4159)};
  const mesh::DxfDrawing d = WriteAndRead(dir, {{"Survey", 0xffffff, {Line(points, true)}}});
  const Polyline2& read = d.layers.at("Survey").at(0);
  ASSERT_EQ(read.points.size(), points.size());
  EXPECT_TRUE(read.closed);
  for (size_t k = 0; k < points.size(); ++k) {
    EXPECT_LE((read.points[k] - points[k]).cwiseAbs().maxCoeff(), 1e-5) << k;
    // Measured: dxflib's "%.16f" holds more digits than a double has at 1e7 m (~1e-9 m steps).
    EXPECT_EQ(read.points[k], points[k]) << k << ": survey coordinates come back bit-identical";
  }
  // The text of the first vertex: 16 decimals (the double's exact value, rounded).
  const std::string text = ReadBytes(dir.File("s.dxf"));
  EXPECT_NE(text.find(" 10\n712345.6789000000571832\n 20\n9162345.1234000008553267\n"),
            std::string::npos);
}

// The precision the file holds, measured over many values: 16 decimals after the point, so at
// most 1e-16 m off, and the very same double from 0.5 m up.
TEST(WriteSectionDxf, ValuesComeBackWithin1e16AndExactFromHalfAMetre) {
  TempDir dir;
  std::mt19937_64 rng(20240611);
  std::uniform_real_distribution<double> survey(-1e7, 1e7), unit(-1, 1), exponent(-12, 3);
  std::vector<V> points;
  for (int k = 0; k < 1000; ++k) points.emplace_back(survey(rng), survey(rng));
  for (int k = 0; k < 500; ++k) points.emplace_back(unit(rng), unit(rng));
  for (int k = 0; k < 500; ++k) {
    points.emplace_back(std::pow(10.0, exponent(rng)), -std::pow(10.0, exponent(rng)));
  }
  const mesh::DxfDrawing d = WriteAndRead(dir, {{"P", 0xffffff, {Line(points)}}});
  const std::vector<V>& read = d.layers.at("P").at(0).points;
  ASSERT_EQ(read.size(), points.size());
  double worst_small = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    for (int c = 0; c < 2; ++c) {
      const double written = points[k][c], back = read[k][c];
      if (std::abs(written) >= 0.5) {
        EXPECT_EQ(back, written) << k;
      } else {
        worst_small = std::max(worst_small, std::abs(back - written));
      }
    }
  }
  EXPECT_LE(worst_small, 1e-16);
}

TEST(WriteSectionDxf, EmptyLayerIsStillInTheLayerTable) {
  TempDir dir;
  const std::vector<DxfLayerLines> layers = {{"Walls", 0xff0000, {Line({V(0, 0), V(1, 1)})}},
                                             {"Empty", 0x0000ff, {}},
                                             {"OnePoint", 0x00ff00, {Line({V(2, 2)})}}};
  const mesh::DxfDrawing d = WriteAndRead(dir, layers);
  EXPECT_EQ(d.LayerNames(), (std::vector<std::string>{"Walls"}));
  const std::vector<LayerRecord> table = LayerTable(ReadBytes(dir.File("s.dxf")));
  EXPECT_EQ(Names(table), (std::vector<std::string>{"0", "Walls", "Empty", "OnePoint"}));
  EXPECT_EQ(table[2].aci, 5);

  // A drawing of empty layers only is still a valid file.
  const mesh::DxfDrawing empty = WriteAndRead(dir, {{"Empty", 0xffffff, {}}});
  EXPECT_TRUE(empty.layers.empty());
  EXPECT_EQ(empty.unit_name, "metre");
  const std::string text = ReadBytes(dir.File("s.dxf"));
  EXPECT_EQ(Names(LayerTable(text)), (std::vector<std::string>{"0", "Empty"}));
  EXPECT_EQ(text.find("$EXTMIN"), std::string::npos) << "no extent without lines";
  // No layers at all: just layer "0".
  EXPECT_TRUE(WriteAndRead(dir, {}).layers.empty());
  EXPECT_EQ(Names(LayerTable(ReadBytes(dir.File("s.dxf")))), (std::vector<std::string>{"0"}));
}

TEST(DxfLayerNames, ForbiddenCharactersBecomeUnderscoresAndNamesStayDistinct) {
  const std::string long_name(300, 'x');
  const std::vector<std::string> given = {"a/b",
                                          "a:b",
                                          "Wall",
                                          "WALL",
                                          "",
                                          "0",
                                          "tab\there",
                                          "S\xc3\xa4ule",
                                          long_name,
                                          long_name,
                                          "bad\xff",
                                          "<>/\\\":;?*|,=`",
                                          "a_b",
                                          "emoji \xf0\x9f\x99\x82",
                                          "\xce\x9d\xce\xb1\xcf\x8c\xcf\x82"};
  std::vector<DxfLayerLines> layers;
  for (const std::string& name : given) layers.push_back({name, 0xffffff, {}});
  const std::vector<std::string> expected = {"a_b",
                                             "a_b_2",
                                             "Wall",
                                             "WALL_2",
                                             "0",
                                             "0_2",
                                             "tab_here",
                                             "S\xe4ule",
                                             "x" + std::string(254, 'x'),
                                             std::string(253, 'x') + "_2",
                                             "bad_",
                                             "_____________",
                                             "a_b_3",
                                             "emoji _",
                                             "\\U+039D\\U+03B1\\U+03CC\\U+03C2"};
  EXPECT_EQ(DxfLayerNames(layers), expected);
}

TEST(WriteSectionDxf, SanitisedLayerNamesAreWrittenAndReadBack) {
  TempDir dir;
  std::vector<DxfLayerLines> layers;
  for (const char* name : {"Nave: south/west", "Nave; south/west", "nave_ south_west", "Choir"}) {
    layers.push_back({name, 0xffffff, {Line({V(0, 0), V(1, 0)})}});
  }
  const mesh::DxfDrawing d = WriteAndRead(dir, layers);
  const std::vector<std::string> names = {"Nave_ south_west", "Nave_ south_west_2",
                                          "nave_ south_west_3", "Choir"};
  EXPECT_EQ(DxfLayerNames(layers), names);
  EXPECT_EQ(d.layers.size(), 4u) << "four distinct layers";
  for (const std::string& name : names) EXPECT_EQ(d.layers.count(name), 1u) << name;
  EXPECT_EQ(Names(LayerTable(ReadBytes(dir.File("s.dxf")))),
            (std::vector<std::string>{"0", names[0], names[1], names[2], names[3]}));
}

TEST(NearestAciColour, PicksThePaletteEntryAndBlackIsSeven) {
  EXPECT_EQ(NearestAciColour(0xff0000), 1);
  EXPECT_EQ(NearestAciColour(0xffff00), 2);
  EXPECT_EQ(NearestAciColour(0x00ff00), 3);
  EXPECT_EQ(NearestAciColour(0x0000ff), 5);
  EXPECT_EQ(NearestAciColour(0xffffff), 7);
  EXPECT_EQ(NearestAciColour(0x000000), 7);
  EXPECT_EQ(NearestAciColour(0x808080), 8);
  EXPECT_EQ(NearestAciColour(0xfe0101), 1);
  EXPECT_EQ(NearestAciColour(0xcc0000), 12);
  EXPECT_EQ(NearestAciColour(0x4c2626), 19);
  EXPECT_EQ(NearestAciColour(0xff7f9f), 241);
  EXPECT_EQ(NearestAciColour(0x3f00ff), 180);
  EXPECT_EQ(NearestAciColour(0x333333), 250);
  EXPECT_EQ(AciColourRgb(140), 0x00bfffu);
  EXPECT_EQ(AciColourRgb(63), 0xb2cc66u);
  for (int aci = 1; aci < 256; ++aci) {
    EXPECT_EQ(AciColourRgb(NearestAciColour(AciColourRgb(aci))), AciColourRgb(aci)) << aci;
  }
  EXPECT_THROW(NearestAciColour(0x1000000), InternalError);
  EXPECT_THROW(AciColourRgb(0), InternalError);
  EXPECT_THROW(AciColourRgb(256), InternalError);
}

TEST(WriteSectionDxf, LayerColoursAreAciAndOptionallyTrueColour) {
  TempDir dir;
  const std::vector<DxfLayerLines> layers = {{"Red", 0xff0000, {}}, {"Teal", 0x123456, {}}};
  WriteSectionDxf({}, layers, dir.File("s.dxf"));
  std::vector<LayerRecord> table = LayerTable(ReadBytes(dir.File("s.dxf")));
  ASSERT_EQ(table.size(), 3u);
  EXPECT_EQ(table[0].aci, 7) << "layer 0";
  EXPECT_EQ(table[1].aci, 1);
  EXPECT_EQ(table[2].aci, NearestAciColour(0x123456));
  for (const LayerRecord& r : table) EXPECT_EQ(r.true_colour, -1) << "no 420 in AC1015 by default";
  DxfWriteOptions options;
  options.true_colour = true;
  WriteSectionDxf(options, layers, dir.File("s.dxf"));
  table = LayerTable(ReadBytes(dir.File("s.dxf")));
  EXPECT_EQ(table[1].true_colour, 0xff0000);
  EXPECT_EQ(table[2].true_colour, 0x123456);
  EXPECT_EQ(table[2].aci, NearestAciColour(0x123456));
  EXPECT_NO_THROW(mesh::ReadDxf({}, dir.File("s.dxf")));
}

TEST(WriteSectionDxf, CommentIsTheFirstLineWithNewlinesReplaced) {
  TempDir dir;
  const std::vector<DxfLayerLines> layers = {{"A", 0xffffff, {Line({V(0, 0), V(1, 0)})}}};
  DxfWriteOptions options;
  options.comment = "candi section\nsource: scan.las\r\tS\xc3\xa4ule";
  WriteSectionDxf(options, layers, dir.File("s.dxf"));
  std::string text = ReadBytes(dir.File("s.dxf"));
  EXPECT_EQ(text.rfind("999\ncandi section source: scan.las  S\xe4ule\n999\ndxflib ", 0), 0u)
      << text.substr(0, 120);
  options.comment = std::string(5000, 'c');
  EXPECT_EQ(WriteAndRead(dir, layers, options).layers.size(), 1u) << "a long comment is cut";
  text = ReadBytes(dir.File("s.dxf"));
  EXPECT_EQ(text.rfind("999\n" + std::string(1000, 'c') + "\n999\ndxflib", 0), 0u);
  options.comment.clear();
  WriteSectionDxf(options, layers, dir.File("s.dxf"));
  EXPECT_EQ(ReadBytes(dir.File("s.dxf")).rfind("999\ndxflib ", 0), 0u);
}

// The file holds what AutoCAD needs: the sections in order, AC1015, metres, the tables, and
// handles that are unique and below $HANDSEED.
void CheckStructure(const std::string& text) {
  const std::vector<Group> groups = Groups(text);
  std::vector<std::string> sections, tables;
  std::map<std::string, std::vector<std::string>> header;
  std::set<long> handles;
  long seed = -1;
  std::string variable;
  for (size_t i = 0; i < groups.size(); ++i) {
    const Group& g = groups[i];
    if (g.code == 0 && (g.value == "SECTION" || g.value == "TABLE") && i + 1 < groups.size()) {
      (g.value == "SECTION" ? sections : tables).push_back(groups[i + 1].value);
    }
    if (g.code == 9) variable = g.value;
    if (g.code != 9 && !variable.empty() && sections.size() == 1)
      header[variable].push_back(g.value);
    if (g.code == 0) variable.clear();
    if (g.code == 5 && variable == "$HANDSEED") {
      seed = std::stol(g.value, nullptr, 16);
    } else if (g.code == 5 || g.code == 105) {  // 105: the DIMSTYLE record's handle
      EXPECT_TRUE(handles.insert(std::stol(g.value, nullptr, 16)).second) << "handle " << g.value;
    }
  }
  EXPECT_EQ(sections,
            (std::vector<std::string>{"HEADER", "TABLES", "BLOCKS", "ENTITIES", "OBJECTS"}));
  EXPECT_EQ(tables, (std::vector<std::string>{"VPORT", "LTYPE", "LAYER", "STYLE", "VIEW", "UCS",
                                              "APPID", "DIMSTYLE", "BLOCK_RECORD"}));
  EXPECT_EQ(header["$ACADVER"], (std::vector<std::string>{"AC1015"}));
  EXPECT_EQ(header["$DWGCODEPAGE"], (std::vector<std::string>{"ANSI_1252"}));
  EXPECT_EQ(header["$INSUNITS"], (std::vector<std::string>{"6"}));
  EXPECT_EQ(header["$MEASUREMENT"], (std::vector<std::string>{"1"}));
  ASSERT_FALSE(handles.empty());
  EXPECT_GT(seed, *handles.rbegin());
  EXPECT_EQ(text.substr(text.size() - 8), "  0\nEOF\n");
}

TEST(WriteSectionDxf, FileHasTheAc1015StructureAndUniqueHandlesBelowTheSeed) {
  TempDir dir;
  WriteSectionDxf({},
                  {{"A", 0xff0000, {Line({V(-3, 1), V(5, 2)}), Line({V(0, -4), V(1, 7)})}},
                   {"B", 0x00ff00, {}}},
                  dir.File("s.dxf"));
  const std::string text = ReadBytes(dir.File("s.dxf"));
  CheckStructure(text);
  EXPECT_NE(text.find("$EXTMIN\n 10\n-3.0\n 20\n-4.0\n 30\n0.0\n"), std::string::npos);
  EXPECT_NE(text.find("$EXTMAX\n 10\n5.0\n 20\n7.0\n 30\n0.0\n"), std::string::npos);
  EXPECT_NE(text.find("$HANDSEED\n  5\nFFFF\n"), std::string::npos) << "dxflib's usual seed";
}

TEST(WriteSectionDxf, ManyPolylinesRaiseTheHandleSeed) {
  // More entities than dxflib's fixed $HANDSEED FFFF covers.
  TempDir dir;
  DxfLayerLines layer{"Slices", 0xffffff, {}};
  for (int k = 0; k < 65600; ++k) layer.lines.push_back(Line({V(k, 0), V(k, 1)}));
  WriteSectionDxf({}, {layer}, dir.File("s.dxf"));
  const std::string text = ReadBytes(dir.File("s.dxf"));
  EXPECT_EQ(text.find("$HANDSEED\n  5\nFFFF\n"), std::string::npos);
  CheckStructure(text);
}

TEST(WriteSectionDxf, MissingFolderThrowsNamingThePathAndLeavesNothing) {
  TempDir dir;
  const std::string path = dir.File("missing/s.dxf");
  const std::string message = InputErrorMessage([&] {
    WriteSectionDxf({}, {{"A", 0xffffff, {Line({V(0, 0), V(1, 0)})}}}, path);
  });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_EQ(Entries(dir.path()), 0u);
  // A folder as the destination.
  EXPECT_NE(InputErrorMessage([&] { WriteSectionDxf({}, {}, dir.path()); }).find(dir.path()),
            std::string::npos);
}

// Writes fail part-way through: a file-size limit makes them fail (EFBIG) the way a full disk
// does (ENOSPC), as any user, root included.
TEST(WriteSectionDxf, AFailedWriteKeepsTheExistingFile) {
  TempDir dir;
  const std::string path = dir.File("s.dxf");
  WriteBytes(path, "precious");
  DxfLayerLines layer{"Big", 0xffffff, {}};
  for (int k = 0; k < 2000; ++k) layer.lines.push_back(Line({V(k, 0), V(k, 1)}));
  struct rlimit old_limit;
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
  struct rlimit limit = old_limit;
  limit.rlim_cur = 64 << 10;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  const std::string message = InputErrorMessage([&] { WriteSectionDxf({}, {layer}, path); });
  setrlimit(RLIMIT_FSIZE, &old_limit);
  signal(SIGXFSZ, old_handler);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("destination is unchanged"), std::string::npos) << message;
  EXPECT_EQ(ReadBytes(path), "precious");
  EXPECT_EQ(Entries(dir.path()), 1u) << "the temporary file is removed";
  // Without the limit the same drawing is written.
  WriteSectionDxf({}, {layer}, path);
  EXPECT_GT(ReadBytes(path).size(), size_t{64 << 10});
}

TEST(WriteSectionDxf, AReadOnlyFolderKeepsTheExistingFile) {
  if (geteuid() == 0) {
    GTEST_SKIP() << "running as root: a read-only folder does not stop root from writing (the "
                    "file-size-limit test covers a failed write for every user)";
  }
  TempDir dir;
  const std::string path = dir.File("s.dxf");
  WriteBytes(path, "precious");
  ASSERT_EQ(chmod(dir.path().c_str(), 0555), 0);
  const std::string message = InputErrorMessage([&] {
    WriteSectionDxf({}, {{"A", 0xffffff, {Line({V(0, 0), V(1, 0)})}}}, path);
  });
  chmod(dir.path().c_str(), 0755);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_EQ(ReadBytes(path), "precious");
  EXPECT_EQ(Entries(dir.path()), 1u);
}

TEST(WriteSectionDxf, BadCoordinatesAndColoursAreMisuseAndWriteNothing) {
  TempDir dir;
  const std::string path = dir.File("s.dxf");
  WriteBytes(path, "precious");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const V& bad : {V(nan, 0), V(0, inf), V(-inf, 0), V(2e12, 0)}) {
    const std::vector<DxfLayerLines> layers = {
        {"Good", 0xffffff, {Line({V(0, 0), V(1, 0)})}},
        {"Nave", 0xffffff, {Line({V(0, 0), V(1, 0)}), Line({V(0, 0), V(1, 1), bad})}}};
    try {
      WriteSectionDxf({}, layers, path);
      ADD_FAILURE() << "no exception for " << bad.transpose();
    } catch (const InternalError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("layer 'Nave', polyline 1, vertex 2"), std::string::npos) << message;
    }
  }
  // Also in a polyline that would be skipped (one point).
  EXPECT_THROW(WriteSectionDxf({}, {{"A", 0xffffff, {Line({V(nan, nan)})}}}, path), InternalError);
  EXPECT_THROW(WriteSectionDxf({}, {{"A", 0x1000000, {}}}, path), InternalError);
  EXPECT_EQ(ReadBytes(path), "precious");
  EXPECT_EQ(Entries(dir.path()), 1u);
}

}  // namespace
}  // namespace candi::section
