#include "io/xyz/xyz_io.h"

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/check.h"
#include "core/log.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "io/shift_sidecar.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::FileExists;
using testing::ReadBytes;
using testing::TempDir;
using testing::WriteBytes;

PointCloud ReadText(const std::string& path, bool pts, const std::string& columns = "",
                    size_t chunk_size = 1 << 20) {
  PointReadOptions options;
  options.columns = columns;
  auto reader = OpenXyzReader(path, pts, options);
  PointCloud cloud;
  cloud.SetSchema(reader->info().schema);
  cloud.frame = reader->info().frame;
  PointCloud chunk;
  while (reader->Read(chunk_size, &chunk) > 0) cloud.Append(chunk);
  EXPECT_EQ(reader->info().count, cloud.size());
  return cloud;
}

PointCloud ReadXyz(const TempDir& dir, const std::string& text, const std::string& columns = "") {
  const std::string path = dir.File("in.xyz");
  WriteBytes(path, text);
  return ReadText(path, /*pts=*/false, columns);
}

// The message of the InputError that reading `text` throws ("" when none is thrown).
std::string ReadError(const std::string& text, const std::string& columns = "", bool pts = false) {
  TempDir dir;
  const std::string path = dir.File(pts ? "in.pts" : "in.xyz");
  WriteBytes(path, text);
  try {
    ReadText(path, pts, columns);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::vector<std::string> ScalarNames(const PointCloud& cloud) {
  std::vector<std::string> names;
  for (const ScalarFieldSpec& s : cloud.schema.scalars) names.push_back(s.name);
  return names;
}

// Survey-scale points with colours, normals and a float scalar, in `frame`.
PointCloud SurveyCloud(size_t n, const LocalFrame& frame) {
  PointCloud cloud;
  cloud.frame = frame;
  PointSchema schema;
  schema.colors = schema.normals = true;
  schema.scalars = {{"quality", ScalarType::kFloat32}};
  cloud.SetSchema(schema);
  cloud.Resize(n);
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d world(500000.123 + k * 0.001, 4500000.456, 100.789);
    cloud.positions[k] = world - frame.origin;
    cloud.colors[k] = {static_cast<uint8_t>(k % 256), static_cast<uint8_t>(k * 7 % 256), 255};
    cloud.normals[k] =
        Eigen::Vector3f(std::sin(0.1f * k), std::cos(0.1f * k), 1.0f / 3).normalized();
    cloud.scalars[0].f32[k] = 0.1f * static_cast<float>(k) - 7.3f;
  }
  return cloud;
}

void ExpectSamePoints(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a.WorldPosition(k), b.WorldPosition(k)) << "point " << k;  // bit-exact
    ASSERT_EQ(a.colors[k], b.colors[k]) << "point " << k;
    ASSERT_EQ(a.normals[k], b.normals[k]) << "point " << k;
    ASSERT_EQ(a.scalars[0].f32[k], b.scalars[0].f32[k]) << "point " << k;
  }
}

constexpr char kSurveyColumns[] = "x,y,z,r,g,b,nx,ny,nz,quality";

// The file's text after candi's "//names" header line.
std::string Body(const std::string& path) {
  const std::string text = ReadBytes(path);
  EXPECT_EQ(text.rfind("//", 0), 0u) << "candi's XYZ starts with a header line";
  return text.substr(text.find('\n') + 1);
}

TEST(XyzRoundTrip, SurveyScalePositionsAreBitExact) {
  TempDir dir;
  const PointCloud cloud = SurveyCloud(2000, LocalFrame());
  const std::string path = dir.File("cloud.xyz");
  WritePointCloud(path, cloud);
  EXPECT_FALSE(FileExists(ShiftSidecarPath(path)));
  EXPECT_EQ(Body(path).substr(0, 26), "500000.123 4500000.456 100");
  const PointCloud back = ReadText(path, false, kSurveyColumns);
  EXPECT_TRUE(back.frame.IsIdentity());
  EXPECT_EQ(back.schema.position_type, ScalarType::kFloat64);
  ExpectSamePoints(cloud, back);
}

TEST(XyzRoundTrip, ShiftedCloudWritesSidecarAndReadsBackExactWorld) {
  TempDir dir;
  LocalFrame shift;
  shift.origin = Eigen::Vector3d(500000, 4500000, 100);
  const PointCloud cloud = SurveyCloud(2000, shift);
  const std::string path = dir.File("cloud.xyz");
  WritePointCloud(path, cloud);
  ASSERT_TRUE(FileExists(ShiftSidecarPath(path)));
  EXPECT_EQ(Body(path).substr(0, 4), "0.12");  // local coordinates
  const PointCloud back = ReadText(path, false, kSurveyColumns);
  EXPECT_EQ(back.frame, shift);
  ExpectSamePoints(cloud, back);
  for (size_t k = 0; k < back.size(); ++k) {
    ASSERT_EQ(back.WorldPosition(k).x(), 500000.123 + k * 0.001);
  }
}

TEST(XyzRoundTrip, ChunksInAnotherFrameAreReexpressed) {
  TempDir dir;
  LocalFrame shift;
  shift.origin = Eigen::Vector3d(500000, 4500000, 100);
  const PointCloud world = SurveyCloud(100, LocalFrame());
  const std::string path = dir.File("cloud.pts");
  PointWriteSpec spec{world.schema, shift, {}, kUnknownCount};
  auto writer = OpenXyzWriter(path, /*pts=*/true, spec, {});
  writer->Write(world);
  writer->Close();
  EXPECT_EQ(ReadBytes(path).substr(0, 21), "100                 \n");  // patched count line
  const PointCloud back = ReadText(path, true, kSurveyColumns);
  EXPECT_EQ(back.frame, shift);
  ExpectSamePoints(world, back);
}

TEST(XyzRoundTrip, UnshiftedRewriteRemovesStaleSidecar) {
  TempDir dir;
  LocalFrame shift;
  shift.origin = Eigen::Vector3d(500000, 4500000, 100);
  const std::string path = dir.File("cloud.xyz");
  WritePointCloud(path, SurveyCloud(10, shift));
  ASSERT_TRUE(FileExists(ShiftSidecarPath(path)));
  WritePointCloud(path, SurveyCloud(10, LocalFrame()));
  EXPECT_FALSE(FileExists(ShiftSidecarPath(path)));
}

TEST(XyzRoundTrip, DefaultColumnsReadBackWithTheGuess) {
  TempDir dir;
  PointCloud cloud;
  PointSchema schema;
  schema.colors = true;
  schema.scalars = {{"intensity", ScalarType::kFloat32}};
  cloud.SetSchema(schema);
  cloud.Resize(2);
  cloud.positions = {{1.5, 2.5, 3.5}, {-4.0, 5.0, 6.0}};
  cloud.colors = {{10, 20, 30}, {40, 50, 60}};
  cloud.scalars[0].f32 = {0.25f, 7.0f};
  const std::string path = dir.File("c.pts");
  WritePointCloud(path, cloud);
  EXPECT_EQ(ReadBytes(path), "2\n1.5 2.5 3.5 0.25 10 20 30\n-4 5 6 7 40 50 60\n");
  const PointCloud back = ReadText(path, true);
  EXPECT_EQ(back.positions, cloud.positions);
  EXPECT_EQ(back.colors, cloud.colors);
  EXPECT_EQ(back.scalars[0].f32, cloud.scalars[0].f32);
}

TEST(XyzRoundTrip, HeaderLineNamesTheColumnsSoNoSpecIsNeeded) {
  TempDir dir;
  const PointCloud cloud = SurveyCloud(50, LocalFrame());
  const std::string path = dir.File("named.xyz");
  WritePointCloud(path, cloud);
  EXPECT_EQ(ReadBytes(path).substr(0, ReadBytes(path).find('\n')), "//x y z r g b nx ny nz quality");
  const PointCloud back = ReadPointCloud(path);  // no column spec
  EXPECT_TRUE(back.schema.colors);
  EXPECT_TRUE(back.schema.normals);
  ASSERT_NE(back.FindScalar("quality"), nullptr);
  ExpectSamePoints(cloud, back);
  // CloudCompare's header style, and a plain title comment that names no columns.
  WriteBytes(dir.File("cc.txt"), "//X,Y,Z,R,G,B,Deviation\n1 2 3 10 20 30 0.5\n");
  const PointCloud cc = ReadPointCloud(dir.File("cc.txt"));
  EXPECT_EQ(cc.colors[0], (Rgb8{10, 20, 30}));
  EXPECT_EQ(cc.FindScalar("Deviation")->Get(0), 0.5);
  WriteBytes(dir.File("title.xyz"), "# survey of 2024-05-01\n1 2 3\n");
  EXPECT_EQ(ReadPointCloud(dir.File("title.xyz")).size(), 1u);
}

TEST(XyzWriter, Float32PrecisionAndColumnSpec) {
  TempDir dir;
  PointCloud cloud = SurveyCloud(1, LocalFrame());
  cloud.positions[0] = Eigen::Vector3d(0.1, 2, 3);
  PointWriteOptions options;
  options.precision = PositionPrecision::kFloat32;
  options.columns = "quality,z,y,x";
  const std::string path = dir.File("c.xyz");
  WritePointCloud(path, cloud, options);
  EXPECT_EQ(ReadBytes(path), "//quality z y x\n-7.3 3 2 0.1\n");
  options.columns = "x,y,z,missing";
  EXPECT_THROW(WritePointCloud(path, cloud, options), std::invalid_argument);
  options.columns = "x,y,z,_";
  EXPECT_THROW(WritePointCloud(path, cloud, options), std::invalid_argument);
}

// ---- Column guessing and specs.

TEST(XyzColumns, GuessesFromTheColumnCount) {
  TempDir dir;
  struct Case {
    std::string line;
    bool colors, normals;
    std::vector<std::string> scalars;
  };
  const std::vector<Case> cases = {
      {"1 2 3", false, false, {}},
      {"1 2 3 0.5", false, false, {"intensity"}},
      {"1 2 3 10 20 255", true, false, {}},
      {"1 2 3 0.6 0 0.8", false, true, {}},
      {"1 2 3 0 0 1", false, true, {}},  // an integer unit vector is a normal
      {"1 2 3 0.5 10 20 30", true, false, {"intensity"}},
      {"1 2 3 10 20 30 0 0.6 0.8", true, true, {}},
      {"1 2 3 0 0.6 0.8 10 20 30", true, true, {}},
      {"1 2 3 4 5", false, false, {"c3", "c4"}},
  };
  for (const Case& c : cases) {
    const PointCloud cloud = ReadXyz(dir, c.line + "\n");
    ASSERT_EQ(cloud.size(), 1u) << c.line;
    EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(1, 2, 3)) << c.line;
    EXPECT_EQ(cloud.schema.colors, c.colors) << c.line;
    EXPECT_EQ(cloud.schema.normals, c.normals) << c.line;
    EXPECT_EQ(ScalarNames(cloud), c.scalars) << c.line;
  }
  const PointCloud nine = ReadXyz(dir, "1 2 3 0 0.6 0.8 10 20 30\n");
  EXPECT_EQ(nine.colors[0], (Rgb8{10, 20, 30}));
  EXPECT_EQ(nine.normals[0], Eigen::Vector3f(0, 0.6f, 0.8f));
}

TEST(XyzColumns, GuessIsLogged) {
  TempDir dir;
  std::string logged;
  LogSink old = SetLogSink([&](LogLevel, const std::string& m) { logged += m + "\n"; });
  ReadXyz(dir, "1 2 3 10 20 30\n");
  SetLogSink(old);
  EXPECT_NE(logged.find("6 columns, guessed x,y,z,r,g,b; pass --columns"), std::string::npos)
      << logged;
}

// A command that opens one file several times (render: to choose a mode, to peek at the schema,
// to read) says its columns once.
TEST(XyzColumns, GuessIsLoggedOncePerFile) {
  TempDir dir;
  const std::string path = dir.File("twice.xyz");
  testing::WriteBytes(path, "1 2 3 10 20 30 7\n4 5 6 1 2 3 8\n");
  std::string logged;
  LogSink old = SetLogSink([&](LogLevel, const std::string& m) { logged += m + "\n"; });
  for (int i = 0; i < 3; ++i) EXPECT_EQ(ReadPointCloud(path).size(), 2u);
  SetLogSink(old);
  const std::string line = "7 columns, guessed";
  const size_t first = logged.find(line);
  ASSERT_NE(first, std::string::npos) << logged;
  EXPECT_EQ(logged.find(line, first + 1), std::string::npos) << "said once\n" << logged;
}

TEST(XyzColumns, ExplicitSpecWithSkipAliasesAndNames) {
  TempDir dir;
  const PointCloud cloud =
      ReadXyz(dir, "7 1 2 3 200 100 50 0.5 9.25 extra\n", "_,x,y,z,red,green,blue,I,quality");
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(cloud.colors[0], (Rgb8{200, 100, 50}));
  EXPECT_EQ(ScalarNames(cloud), (std::vector<std::string>{"intensity", "quality"}));
  EXPECT_EQ(cloud.scalars[0].f32[0], 0.5f);
  EXPECT_EQ(cloud.scalars[1].f32[0], 9.25f);
}

TEST(XyzColumns, InvalidSpecsNameTheEntry) {
  TempDir dir;
  WriteBytes(dir.File("a.xyz"), "1 2 3\n");
  auto message = [&](const std::string& spec) -> std::string {
    PointReadOptions options;
    options.columns = spec;
    try {
      OpenXyzReader(dir.File("a.xyz"), false, options);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_NE(message("x,y,z,3d").find("'3d'"), std::string::npos);
  EXPECT_NE(message("x,y,z,x").find("'x' appears twice"), std::string::npos);
  EXPECT_NE(message("x,y,z,r,red,g,b").find("'red' appears twice"), std::string::npos);
  EXPECT_NE(message("x,y,z,i,intensity").find("'intensity' appears twice"), std::string::npos);
  EXPECT_NE(message("x,y,z,r,g").find("incomplete r,g,b"), std::string::npos);
  EXPECT_NE(message("x,y,z,nx,ny").find("incomplete nx,ny,nz"), std::string::npos);
  EXPECT_NE(message("x,y").find("no 'z' column"), std::string::npos);
  EXPECT_NE(message("x,,y,z").find("empty entry"), std::string::npos);
  EXPECT_NE(message("x y z").find("'x y z'"), std::string::npos);
}

TEST(XyzColumns, SeparatorsCommentsAndCrlf) {
  TempDir dir;
  const PointCloud cloud = ReadXyz(dir,
                                   "# a comment\r\n"
                                   "// another\r\n"
                                   "\r\n"
                                   "1,2,3\r\n"
                                   "4\t5\t6\r\n"
                                   "   # indented comment\n"
                                   "7;8;9\r\n"
                                   "  10 , 11 ,\t12\n"
                                   "13;\t14 ;15\n"
                                   "16  \t 17   18");  // no final newline
  std::vector<Eigen::Vector3d> expected;
  for (int k = 0; k < 6; ++k) expected.emplace_back(3 * k + 1, 3 * k + 2, 3 * k + 3);
  EXPECT_EQ(cloud.positions, expected);
}

TEST(XyzColumns, HeaderLineIsSkipped) {
  TempDir dir;
  const PointCloud cloud = ReadXyz(dir, "X,Y,Z,Red,Green,Blue\n1,2,3,10,20,30\n4,5,6,40,50,60\n");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_TRUE(cloud.schema.colors);
  EXPECT_EQ(cloud.colors[1], (Rgb8{40, 50, 60}));
}

TEST(XyzColumns, ExtraColumnsAreIgnored) {
  TempDir dir;
  const PointCloud cloud = ReadXyz(dir, "1 2 3 4 5\n6 7 8 9\n", "x,y,z");
  EXPECT_EQ(cloud.positions, (std::vector<Eigen::Vector3d>{{1.0, 2.0, 3.0}, {6.0, 7.0, 8.0}}));
}

TEST(XyzColumns, PositionsParseExactly) {
  TempDir dir;
  const PointCloud cloud = ReadXyz(dir, "0.1 +4500000.4560000001 -1e-3\n");
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(0.1, 4500000.4560000001, -1e-3));
}

template <typename T>
uint64_t Bits(T value) {
  uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof(T));
  return bits;
}
template <typename T>
T FromBits(uint32_t bits) {
  T value;
  std::memcpy(&value, &bits, sizeof(T));
  return value;
}

// Every value must parse to exactly what std::from_chars gives (the fast path is exact).
TEST(XyzColumns, NumbersParseLikeFromChars) {
  std::mt19937_64 rng(7);
  std::vector<std::string> values = {
      "9007199254740993",      "1e22",         "1e23", "-0", "0.0000001e-15",
      "123456789012345678901", "3.4028235e38", ".5",   "5."};
  char buf[64];
  for (int k = 0; k < 20000; ++k) {
    std::string digits =
        std::to_string(rng() % 1000000000000ull) + std::to_string(rng() % 10000000);
    digits.resize(1 + rng() % std::min<size_t>(digits.size(), 19));
    if (rng() % 2) digits.insert(rng() % digits.size(), ".");
    if (rng() % 4 == 0) digits += "e" + std::to_string(static_cast<int>(rng() % 26) - 10);
    values.push_back((rng() % 2 ? "-" : "") + digits);
    const float f = FromBits<float>(0x00800000u + static_cast<uint32_t>(rng() % 0x7e000000u));
    const double mid = (double(f) + double(std::nextafter(f, 1e30f))) / 2;  // a float midpoint
    std::snprintf(buf, sizeof(buf), "%.17g", mid);
    values.push_back(buf);
    values.push_back(FormatDouble(mid));
  }
  std::string text;
  for (const std::string& v : values) text += "1 2 " + v + " " + v + "\n";
  TempDir dir;
  const PointCloud cloud = ReadXyz(dir, text, "x,y,z,f");
  ASSERT_EQ(cloud.size(), values.size());
  for (size_t k = 0; k < values.size(); ++k) {
    double d = 0;
    float f = 0;
    const std::string& v = values[k];
    std::from_chars(v.data(), v.data() + v.size(), d);
    std::from_chars(v.data(), v.data() + v.size(), f);
    ASSERT_EQ(Bits(cloud.positions[k].z()), Bits(d)) << v;
    ASSERT_EQ(Bits(cloud.scalars[0].f32[k]), Bits(f)) << v;
  }
}

TEST(PtsReader, CountLineAndIntensityColours) {
  TempDir dir;
  const std::string path = dir.File("a.pts");
  WriteBytes(path, "2\n1 2 3 -5 10 20 30\n4 5 6 7 40 50 60\n");
  auto reader = OpenXyzReader(path, /*pts=*/true, {});
  EXPECT_EQ(reader->info().count, 2u);
  EXPECT_EQ(reader->info().format, PointFormat::kPts);
  const PointCloud cloud = ReadText(path, true);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(ScalarNames(cloud), std::vector<std::string>{"intensity"});
  EXPECT_EQ(cloud.scalars[0].f32, (std::vector<float>{-5, 7}));
  EXPECT_EQ(cloud.colors[1], (Rgb8{40, 50, 60}));
}

TEST(PtsReader, SectionsAndMissingCountLine) {
  TempDir dir;
  const std::string path = dir.File("a.pts");
  WriteBytes(path, "1\n1 2 3 4\n2\n5 6 7 8\n9 10 11 12\n");
  EXPECT_EQ(ReadText(path, true).size(), 3u);
  WriteBytes(path, "1 2 3 4\n5 6 7 8\n");
  EXPECT_EQ(ReadText(path, true).size(), 2u);
  EXPECT_NE(ReadError("12.5\n1 2 3\n", "", true).find("line 1: expected the PTS point count"),
            std::string::npos);
}

// ---- Streaming.

std::string NumberedLines(size_t n) {
  std::string text;
  char buf[64];
  for (size_t k = 0; k < n; ++k) {
    char* p = AppendDouble(buf, 500000.0 + k * 0.001);
    *p++ = k % 2 ? '\t' : ' ';
    p = AppendDouble(p, -static_cast<double>(k));
    *p++ = ' ';
    p = AppendDouble(p, k * 1e-7);
    text.append(buf, p);
    text += " " + std::to_string(k % 256) + " 0 255" + (k % 3 ? "\n" : "\r\n");
  }
  return text;
}

TEST(XyzStreaming, SmallChunksEqualWholeFile) {
  TempDir dir;
  const std::string path = dir.File("a.xyz");
  WriteBytes(path, "# header comment\n" + NumberedLines(1000));
  const PointCloud whole = ReadText(path, false);
  const PointCloud small = ReadText(path, false, "", 3);
  ASSERT_EQ(whole.size(), 1000u);
  EXPECT_EQ(small.positions, whole.positions);
  EXPECT_EQ(small.colors, whole.colors);
}

TEST(XyzStreaming, LinesCarryOverBlockBoundaries) {
  TempDir dir;
  const std::string path = dir.File("big.xyz");
  const size_t n = 250001;  // ~10 MiB: two block boundaries, at arbitrary places in lines
  std::string text = NumberedLines(n);
  ASSERT_GT(text.size(), size_t{8} << 20);
  text.pop_back();  // no final newline: the last line is followed by stale buffer bytes
  WriteBytes(path, text);
  const PointCloud cloud = ReadText(path, false, "", 77777);
  ASSERT_EQ(cloud.size(), n);
  for (size_t k = 0; k < n; ++k) {
    ASSERT_EQ(cloud.positions[k], Eigen::Vector3d(500000.0 + k * 0.001, -double(k), k * 1e-7)) << k;
    ASSERT_EQ(cloud.colors[k], (Rgb8{static_cast<uint8_t>(k % 256), 0, 255})) << k;
  }
}

// ---- Bad input.

void ExpectError(const std::string& message, const std::string& part) {
  EXPECT_NE(message.find(part), std::string::npos)
      << "message: '" << message << "', want '" << part << "'";
}

TEST(XyzBadInput, NonFiniteCoordinatesNameTheLine) {
  ExpectError(ReadError("1 2 3\n4 nan 6\n"),
              "in.xyz: line 2, column 2: coordinate is not finite: 'nan'");
  ExpectError(ReadError("1 2 3\n\n4 5 -inf\n"), "line 3, column 3: coordinate is not finite");
  ExpectError(ReadError("1 2 3\n4 5 1e999\n"), "line 2, column 3: not a number");
}

TEST(XyzBadInput, ShortLineGarbageAndBadColour) {
  ExpectError(ReadError("1 2 3 4\n5 6 7\n"),
              "line 2: expected 4 columns (x,y,z,intensity), found 3");
  ExpectError(ReadError("1 2 3 4 5 6\n1 2 3 300 5 6\n"),
              "line 2, column 4: colour is not an integer in 0..255: '300'");
  ExpectError(ReadError("1 2 3 4 5 6\n1 2 3 4.5 5 6\n"), "line 2, column 4: colour");
  ExpectError(ReadError("1 2 3\n1 2x 3\n"), "line 2, column 2: not a number: '2x'");
  ExpectError(ReadError("1 2 3 0.5\n1 2 3 abc\n"), "line 2, column 4: not a number: 'abc'");
  ExpectError(ReadError("1,2,3\n1,,3\n"), "line 2, column 2: empty value");
  ExpectError(ReadError("1 2\n"), "line 1: 2 column(s); at least x,y,z are needed");
  ExpectError(ReadError("1,5;2,5;3,5\n"), "line 1: mixes ',' and ';'");
}

TEST(XyzBadInput, EmptyFileIsAnErrorCommentsOnlyIsNoPoints) {
  ExpectError(ReadError(""), "in.xyz: byte 0: empty file");
  TempDir dir;
  const PointCloud cloud = ReadXyz(dir, "# nothing here\n\n// really\n");
  EXPECT_EQ(cloud.size(), 0u);
  EXPECT_EQ(ReadXyz(dir, "x y z\n").size(), 0u);  // a header only
}

TEST(XyzBadInput, OverlongLine) {
  ExpectError(ReadError("1 2 3\n1 2 3" + std::string(1100000, ' ') + "\n"),
              "line 2: line longer than 1048576 bytes");
  ExpectError(ReadError("1 2 3\n" + std::string(3 << 20, '1')), "line 2: line longer");
}

// ---- Writer failures.

TEST(XyzWriter, UnwritableFolderThrowsAndCreatesNothing) {
  TempDir dir;
  WriteBytes(dir.File("file"), "x");
  const std::string path = dir.File("file/out.xyz");  // a file where a folder should be
  EXPECT_THROW(WritePointCloud(path, SurveyCloud(3, LocalFrame())), InputError);
  EXPECT_FALSE(FileExists(path));
}

TEST(XyzWriter, NoCloseLeavesDestinationUnchanged) {
  TempDir dir;
  const std::string path = dir.File("out.xyz");
  WriteBytes(path, "old contents\n");
  const PointCloud cloud = SurveyCloud(3, LocalFrame());
  {
    auto writer = OpenXyzWriter(path, false, {cloud.schema, cloud.frame, {}, 3}, {});
    writer->Write(cloud);
  }
  EXPECT_EQ(ReadBytes(path), "old contents\n");
}

TEST(XyzWriter, MisuseIsCaught) {
  TempDir dir;
  const PointCloud cloud = SurveyCloud(3, LocalFrame());
  PointSchema other = cloud.schema;
  other.normals = false;
  auto writer = OpenXyzWriter(dir.File("a.pts"), true, {other, {}, {}, 5}, {});
  EXPECT_THROW(writer->Write(cloud), InternalError);  // schema differs
  PointCloud chunk = cloud;
  chunk.SetSchema(other);
  writer->Write(chunk);
  EXPECT_THROW(writer->Close(), InternalError);  // 3 points written, 5 promised
}

}  // namespace
}  // namespace candi::io
