// Parallel reading (issue 38): binary PLY, LAS, XYZ and PTS files written by candi's writers read
// on 1 and on 2 threads give the same bytes, equal to the cloud written; truncated and malformed
// files give the same error, naming the file, the record and where useful the byte offset.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/check.h"
#include "core/rng.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::ReadBytes;
using testing::TempDir;
using testing::WriteBytes;

constexpr size_t kPoints = 300000;  // many blocks of every reader

// A seeded cloud of double positions (millimetres on a 300 m square) and colours; with
// `intensity`, a float field too.
PointCloud Generated(size_t n, bool intensity) {
  PointCloud c;
  PointSchema schema;
  schema.colors = true;
  schema.position_type = ScalarType::kFloat64;
  if (intensity) schema.scalars.push_back({"intensity", ScalarType::kFloat32});
  c.SetSchema(schema);
  c.Resize(n);
  Rng rng(38);
  for (size_t i = 0; i < n; ++i) {
    c.positions[i] =
        Eigen::Vector3d(std::round(rng.Uniform(0, 3e5)), std::round(rng.Uniform(0, 3e5)),
                        std::round(rng.Uniform(-1e4, 1e4))) *
        1e-3;
    c.colors[i] = {static_cast<uint8_t>(i), static_cast<uint8_t>(i >> 8),
                   static_cast<uint8_t>(i >> 16)};
    if (intensity) c.scalars[0].f32[i] = static_cast<float>(i % 1000) * 0.5f;
  }
  return c;
}

// The raw bytes of every array of a cloud, for comparing reads.
std::string Bytes(const PointCloud& c) {
  std::string out;
  auto add = [&out](const auto& v) {
    out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(v[0]));
  };
  add(c.positions);
  add(c.colors);
  add(c.normals);
  for (const ScalarField& f : c.scalars) {
    add(f.f32);
    add(f.f64);
  }
  return out;
}

// Reads `path` with at most `threads` threads, in chunks of `chunk` points.
PointCloud ReadOn(int threads, const std::string& path, size_t chunk = 1 << 20) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  if (chunk == (1 << 20)) return ReadPointCloud(path);
  auto reader = OpenPointReader(path);
  PointCloud cloud, part;
  cloud.SetSchema(reader->info().schema);
  cloud.frame = reader->info().frame;
  while (reader->Read(chunk, &part) > 0) cloud.Append(part);
  return cloud;
}

// The InputError message of reading `path` on `threads` threads ("" when none), and in *points
// the points the reader returned, in chunks of `chunk`, before it threw.
std::string ErrorOn(int threads, const std::string& path, size_t chunk = 1 << 20,
                    size_t* points = nullptr) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  size_t read = 0;
  std::string message;
  try {
    auto reader = OpenPointReader(path);
    PointCloud part;
    while (size_t n = reader->Read(chunk, &part)) read += n;
  } catch (const InputError& e) {
    message = e.what();
  }
  if (points) *points = read;
  return message;
}

// Reads on 1 and 2 threads (whole and in odd chunks) and checks the bytes agree; returns the read.
PointCloud ReadAgreeing(const std::string& path) {
  const PointCloud one = ReadOn(1, path), two = ReadOn(2, path);
  EXPECT_EQ(one.size(), two.size());
  EXPECT_TRUE(Bytes(one) == Bytes(two)) << path << ": 1 and 2 threads differ";
  const PointCloud chunks = ReadOn(2, path, 77777);
  EXPECT_TRUE(Bytes(one) == Bytes(chunks)) << path << ": chunks of 77777 differ";
  return one;
}

void ExpectSameCloud(const PointCloud& written, const PointCloud& read) {
  ASSERT_EQ(written.size(), read.size());
  ASSERT_EQ(written.schema.colors, read.schema.colors);
  EXPECT_TRUE(Bytes(written) == Bytes(read)) << "the points read are not the points written";
}

TEST(ParallelRead, LasIsTheCloudWrittenOnOneAndTwoThreads) {
  TempDir dir;
  const PointCloud cloud = Generated(kPoints, false);
  const std::string path = dir.File("c.las");
  WritePointCloud(path, cloud);
  const PointCloud read = ReadAgreeing(path);
  ASSERT_EQ(read.size(), cloud.size());
  for (size_t i = 0; i < cloud.size(); i += 997) {
    ASSERT_LT((read.WorldPosition(i) - cloud.WorldPosition(i)).norm(), 1e-6) << "point " << i;
    ASSERT_EQ(read.colors[i].r, cloud.colors[i].r) << "point " << i;
  }
}

TEST(ParallelRead, PlyXyzAndPtsAreTheCloudWrittenOnOneAndTwoThreads) {
  TempDir dir;
  const PointCloud cloud = Generated(kPoints, true);
  for (const char* name : {"c.ply", "c.xyz", "c.pts"}) {
    const std::string path = dir.File(name);
    WritePointCloud(path, cloud);
    ASSERT_GT(std::filesystem::file_size(path), uint64_t{8} << 20) << "fewer blocks than meant";
    ExpectSameCloud(cloud, ReadAgreeing(path));
  }
}

// Two PTS files one after the other: a section count line in the middle of a block, and
// comments, CRLF endings and a last line without '\n' around block boundaries.
TEST(ParallelRead, PtsSectionsCommentsAndCrlfAgree) {
  TempDir dir;
  const PointCloud cloud = Generated(kPoints, true);
  const std::string a = dir.File("a.pts");
  WritePointCloud(a, cloud);
  const std::string text = ReadBytes(a);
  std::string mixed;
  size_t line = 0;
  for (size_t at = 0; at < text.size(); ++line) {
    const size_t nl = text.find('\n', at);
    mixed += text.substr(at, nl - at);
    mixed += line % 3 == 0 ? "\r\n" : "\n";
    if (line % 1000 == 7) mixed += "# a comment\n\n";
    at = nl + 1;
  }
  const std::string both = dir.File("both.pts");
  WriteBytes(both, mixed + mixed.substr(0, mixed.size() - 2));  // no '\n' at the end
  const PointCloud read = ReadAgreeing(both);
  ASSERT_EQ(read.size(), 2 * kPoints);
  PointCloud twice = cloud;
  twice.Append(cloud);
  ExpectSameCloud(twice, read);
}

// Writes the cloud as `name`, cuts 1000 bytes off and checks that 1 and 2 threads give one error
// naming the file, a byte offset and `what`.
void ExpectOneTruncationError(const std::string& name, const std::string& what) {
  TempDir dir;
  const std::string path = dir.File(name);
  WritePointCloud(path, Generated(kPoints, false));
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 1000);
  const std::string one = ErrorOn(1, path), two = ErrorOn(2, path);
  EXPECT_EQ(one, two);
  EXPECT_NE(one.find(path + ": byte "), std::string::npos) << one;
  EXPECT_NE(one.find(what), std::string::npos) << one;
}

TEST(ParallelRead, TruncatedPlyAndLasGiveOneError) {
  ExpectOneTruncationError("c.ply", "header promises 300000 vertex records");
  ExpectOneTruncationError("c.las", "header promises 300000 points");
}

// A file cut after opening: the records the map no longer holds are an error, not SIGBUS.
TEST(ParallelRead, FileCutAfterOpeningGivesAnError) {
  TempDir dir;
  for (const char* name : {"c.ply", "c.las", "c.xyz"}) {
    const std::string path = dir.File(name);
    WritePointCloud(path, Generated(kPoints, false));
    auto reader = OpenPointReader(path);
    std::filesystem::resize_file(path, 5000);
    PointCloud chunk;
    try {
      reader->Read(kPoints, &chunk);
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ": byte 5000: the file shrank"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(ParallelRead, NanInPlyGivesOneErrorNamingTheFirstBadVertex) {
  TempDir dir;
  const std::string path = dir.File("c.ply");
  WritePointCloud(path, Generated(kPoints, false));
  std::string bytes = ReadBytes(path);
  const size_t data = bytes.find("end_header\n") + 11;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t vertex : {250001, 123457}) {
    std::memcpy(&bytes[data + vertex * 27 + 8], &nan, sizeof(nan));  // its y
  }
  WriteBytes(path, bytes);
  const std::string one = ErrorOn(1, path), two = ErrorOn(2, path);
  EXPECT_EQ(one, two);
  EXPECT_NE(one.find(path), std::string::npos) << one;
  EXPECT_NE(one.find("vertex 123457: coordinate is NaN or infinite"), std::string::npos) << one;
}

// Replaces the first value of (1-based) line `line` of `text` with `value`.
void ReplaceFirstValue(std::string* text, size_t line, const std::string& value) {
  size_t at = 0;
  for (size_t k = 1; k < line; ++k) at = text->find('\n', at) + 1;
  text->replace(at, text->find(' ', at) - at, value);
}

TEST(ParallelRead, BadXyzTokenGivesTheFirstBadLineAfterTheSamePoints) {
  TempDir dir;
  const std::string path = dir.File("c.xyz");
  WritePointCloud(path, Generated(kPoints, false));
  std::string text = ReadBytes(path);
  ReplaceFirstValue(&text, 280000, "1.2.3");
  ReplaceFirstValue(&text, 234567, "abc");  // the first bad line; a header comes first
  WriteBytes(path, text);
  for (size_t chunk : {size_t{1} << 20, size_t{100000}, size_t{4096}}) {
    size_t points_one = 0, points_two = 0;
    const std::string one = ErrorOn(1, path, chunk, &points_one);
    const std::string two = ErrorOn(2, path, chunk, &points_two);
    EXPECT_EQ(one, two) << "chunks of " << chunk;
    EXPECT_EQ(one, path + ": line 234567, column 1: not a number: 'abc'");
    // Line 234567 holds point 234565 (0-based): the chunks before it come back first.
    EXPECT_EQ(points_one, 234565 / chunk * chunk) << "chunks of " << chunk;
    EXPECT_EQ(points_two, points_one) << "chunks of " << chunk;
  }
}

TEST(ParallelRead, TruncatedXyzGivesOneErrorAtTheLastLine) {
  TempDir dir;
  const std::string path = dir.File("c.xyz");
  WritePointCloud(path, Generated(kPoints, false));
  std::string text = ReadBytes(path);
  text.resize(text.rfind(' ', text.size() - 2));  // the last line loses its last value
  WriteBytes(path, text);
  const std::string one = ErrorOn(1, path), two = ErrorOn(2, path);
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, path + ": line " + std::to_string(kPoints + 1) + ": expected 6 columns " +
                     "(x,y,z,r,g,b), found 5");
}

// Text with everything the serial reader handles between points: comments, blank and blank-only
// lines, CRLF, extra values, PTS section lines, and a last line without '\n'; `bad_line` (0:
// none) holds a bad value.
std::string MessyPts(size_t points, size_t bad_line) {
  Rng rng(3838);
  std::string text = "1000\n", line;
  size_t lines = 1;
  for (size_t i = 0; i < points;) {
    const uint64_t kind = i == 0 ? 99 : rng.Below(100);  // a point first: it sets the columns
    if (kind < 3) {
      line = "# comment " + std::to_string(i);
    } else if (kind < 5) {
      line = kind == 3 ? "" : " \t ";
    } else if (kind < 6) {
      line = std::to_string(rng.Below(5000));  // a new section
    } else {
      line = std::to_string(rng.Uniform(-1e3, 1e3)) + " " + std::to_string(rng.Below(100000)) +
             ".25 -" + std::to_string(rng.Below(999)) + " " + std::to_string(rng.Below(2000)) +
             " " + std::to_string(rng.Below(256)) + "," + std::to_string(rng.Below(256)) + " " +
             std::to_string(rng.Below(256)) + (kind < 8 ? " 42 extra" : "");
      ++i;
    }
    if (++lines == bad_line) line = "1 2 x 4 5 6 7";
    text += line + (rng.Below(4) == 0 ? "\r\n" : "\n");
  }
  text.pop_back();
  return text;
}

// Read(1) parses a block of about one line a call: the reading line by line the blocks must
// match, on 1 thread; against it, whole reads and odd chunks on 2 threads.
TEST(ParallelRead, MessyPtsReadsAsLineByLine) {
  TempDir dir;
  const std::string path = dir.File("messy.pts");
  WriteBytes(path, MessyPts(150000, 0));
  ASSERT_GT(std::filesystem::file_size(path), uint64_t{4} << 20) << "fewer blocks than meant";
  const PointCloud lines = ReadOn(1, path, 1);
  ASSERT_EQ(lines.size(), 150000u);
  EXPECT_TRUE(Bytes(lines) == Bytes(ReadAgreeing(path)));
  EXPECT_TRUE(Bytes(lines) == Bytes(ReadOn(2, path, 4097)));
}

TEST(ParallelRead, MessyPtsErrorIsTheLineByLineOne) {
  TempDir dir;
  const std::string path = dir.File("bad.pts");
  WriteBytes(path, MessyPts(100000, 76543));
  size_t points_lines = 0, points = 0;
  const std::string lines = ErrorOn(1, path, 1, &points_lines);
  EXPECT_EQ(lines, path + ": line 76543, column 3: not a number: 'x'");
  for (size_t chunk : {size_t{1} << 20, size_t{4097}}) {
    EXPECT_EQ(ErrorOn(2, path, chunk, &points), lines) << "chunks of " << chunk;
    EXPECT_EQ(points, points_lines / chunk * chunk) << "chunks of " << chunk;
  }
}

}  // namespace
}  // namespace candi::io
