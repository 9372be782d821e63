// COPC out of a build (the scene's "copc") and out of a finished build (ExportCopc): a real small
// build of two point layers in a survey CRS; the files and what archive.json says of them; each
// file read back by candi's reader against the layer files; the same bytes for 1 and 2 threads,
// from the export and after resuming; bad build folders named; copc.js reads them where present.
#include "pipeline/copc_export.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <tuple>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "io/crs.h"
#include "io/las/las_io.h"
#include "io/point_io.h"
#include "pipeline/build.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::TempDir;

const Eigen::Vector3d kUtmSite(416000, 9168000, 250);  // UTM 49S, near Borobudur

// A point as the COPC files hold it: millimetres about the origin, colour, layer.
using Quantized = std::tuple<int64_t, int64_t, int64_t, uint8_t, uint8_t, uint8_t, int>;

std::vector<Quantized> QuantizedPoints(const PointCloud& c, const Eigen::Vector3d& origin,
                                       int layer) {
  std::vector<Quantized> q;
  const ScalarField* id = c.FindScalar(io::las_field::kPointSourceId);
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d p = (c.WorldPosition(i) - origin) / kCopcScale;
    q.emplace_back(std::llround(p.x()), std::llround(p.y()), std::llround(p.z()), c.colors[i].r,
                   c.colors[i].g, c.colors[i].b, id ? static_cast<int>(id->Get(i)) : layer);
  }
  std::sort(q.begin(), q.end());
  return q;
}

class CopcBuild : public ::testing::Test {
 protected:
  void SetUp() override {
    io::PointWriteOptions wide;
    wide.precision = io::PositionPrecision::kFloat64;
    PointCloud ground = render::UniformRectangle(6000, 30, 20, 0, {150, 140, 120}, 4);
    PointCloud wall = render::UniformRectangle(2500, 4, 3, 0.5, {200, 60, 40}, 5);
    for (Eigen::Vector3d& p : ground.positions) p += kUtmSite + Eigen::Vector3d(0.0004, 0, 0);
    for (Eigen::Vector3d& p : wall.positions) p += kUtmSite + Eigen::Vector3d(3, 2, 0);
    io::WritePointCloud(dir_.File("ground.ply"), ground, wide);
    io::WritePointCloud(dir_.File("wall.ply"), wall, wide);
  }

  json SceneJson() const {
    json j = {{"candi_scene", 1},
              {"name", "site one"},
              {"seed", 2},
              {"crs", "EPSG:32749"},
              {"render", {{"repeat_level", 2}, {"width", 32}, {"height", 24}}},
              {"copc", {{"layers", true}, {"scene", true}}}};
    j["layers"] = json::array(
        {{{"name", "ground"}, {"kind", "points"}, {"file", "ground.ply"}, {"crs", "scene"}},
         {{"name", "wall"},
          {"kind", "points"},
          {"file", "wall.ply"},
          {"crs", "scene"},
          {"color", {20, 30, 250}}}});
    return j;
  }

  json BuildInto(const std::string& out, int threads, bool resume = false,
                 uint64_t copc_memory_bytes = 0) const {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    testing::WriteBytes(dir_.File("scene.json"), SceneJson().dump(2));
    BuildOptions o;
    o.output = dir_.File(out);
    o.threads = threads;
    o.resume = resume;
    o.copc_memory_bytes = copc_memory_bytes;
    Build(o, LoadScene(dir_.File("scene.json")));
    return json::parse(ReadFileToString(dir_.File(out + "/archive.json")));
  }

  TempDir dir_;
};

TEST(CopcOptions, DefaultsWriteNothingAndTheExportNeedsABuild) {
  EXPECT_NO_THROW(CopcOptions().Check());
  CopcExportOptions o;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.build = "out";
  EXPECT_NO_THROW(o.Check());
  o.copc.scene = false;
  EXPECT_THROW(o.Check(), std::invalid_argument);  // nothing to write
  EXPECT_EQ(SceneCopcName("site one/a"), "copc/site_one_a.copc.laz");
}

TEST_F(CopcBuild, EveryLayerAndTheSceneReadBackAsTheLayerFiles) {
  const json a = BuildInto("out", 2);
  const Eigen::Vector3d origin(416000, 9168000,
                               300);  // LocalFrame::Auto: the centre on a 100 m grid
  ASSERT_EQ(a.at("frame").at("origin"), json::array({origin.x(), origin.y(), origin.z()}));
  const json& copc = a.at("copc");
  EXPECT_FALSE(copc.at("resumed").get<bool>());
  ASSERT_EQ(copc.at("layers").size(), 2u);
  std::vector<Quantized> all;
  for (int k = 0; k < 2; ++k) {
    const json& f = copc["layers"][k];
    const std::string name = a["layers"][k].at("name");
    EXPECT_EQ(f.at("name"), name);
    EXPECT_EQ(f.at("path"), "layers/" + name + ".copc.laz");
    EXPECT_EQ(f.at("points"), a["layers"][k].at("points"));
    const std::string path = dir_.File("out/" + f.at("path").get<std::string>());
    EXPECT_EQ(f.at("bytes").get<uint64_t>(), fs::file_size(path));
    const PointCloud layer = io::ReadPointCloud(dir_.File("out/layers/" + name + ".ply"));
    const PointCloud back = io::ReadPointCloud(path);
    EXPECT_EQ(back.meta.las.point_format, 7);
    EXPECT_EQ(back.meta.las.offset, origin);
    EXPECT_EQ(back.meta.las.creation_year, 1970);
    EXPECT_TRUE(io::SameCrs(back.meta.crs, "EPSG:32749")) << back.meta.crs;
    const std::vector<Quantized> expected = QuantizedPoints(layer, origin, k);
    EXPECT_EQ(QuantizedPoints(back, origin, -1), expected)
        << name;  // the layer's index as point source ID
    all.insert(all.end(), expected.begin(), expected.end());
  }
  std::sort(all.begin(), all.end());
  const json& scene = copc.at("scene");
  EXPECT_EQ(scene.at("path"), "copc/site_one.copc.laz");
  EXPECT_EQ(scene.at("points"), a.at("points"));
  const PointCloud back = io::ReadPointCloud(dir_.File("out/copc/site_one.copc.laz"));
  EXPECT_EQ(QuantizedPoints(back, origin, -1), all);
  const auto names = std::find_if(back.meta.las.vlrs.begin(), back.meta.las.vlrs.end(),
                                  [](const LasVlr& v) { return v.user_id == "candi"; });
  ASSERT_NE(names, back.meta.las.vlrs.end());
  EXPECT_EQ(names->data, "0=ground\n1=wall\n");
  const json timings = json::parse(ReadFileToString(dir_.File("out/timings.json")));
  EXPECT_TRUE(timings.contains("copc"));
}

// Builds on 1 and 2 threads, the export of the build's layers and a resumed build: one set of
// bytes.
TEST_F(CopcBuild, SameBytesFromEveryWay) {
  const std::vector<std::string> files = {"layers/ground.copc.laz", "layers/wall.copc.laz",
                                          "copc/site_one.copc.laz"};
  BuildInto("two", 1);
  fs::rename(dir_.File("two"), dir_.File("one"));
  BuildInto("two", 2);
  // The export, from a copy of what it reads: archive.json and the layer files.
  fs::create_directories(dir_.File("copy/layers"));
  for (const char* f : {"archive.json", "layers/ground.ply", "layers/wall.ply"})
    fs::copy_file(dir_.File(std::string("two/") + f), dir_.File(std::string("copy/") + f));
  CopcExportOptions e;
  e.build = dir_.File("copy");
  e.copc.layers = true;
  const std::vector<CopcFile> exported = ExportCopc(e);
  ASSERT_EQ(exported.size(), 3u);
  EXPECT_EQ(exported[2].path, dir_.File("copy/copc/site_one.copc.laz"));
  EXPECT_EQ(exported[1].layer, "wall");
  for (const std::string& f : files) {
    const std::string bytes = ReadFileToString(dir_.File("one/" + f));
    EXPECT_EQ(bytes, ReadFileToString(dir_.File("two/" + f))) << f;
    EXPECT_EQ(bytes, ReadFileToString(dir_.File("copy/" + f))) << f;
  }
  // --out: the scene's file elsewhere, nothing else.
  e.out = dir_.File("site.copc.laz");
  e.copc.layers = false;
  ASSERT_EQ(ExportCopc(e).size(), 1u);
  EXPECT_EQ(ReadFileToString(e.out), ReadFileToString(dir_.File("one/copc/site_one.copc.laz")));
  // Resuming: kept when present, redone when missing.
  EXPECT_TRUE(BuildInto("two", 2, true).at("copc").at("resumed").get<bool>());
  fs::remove(dir_.File("two/layers/wall.copc.laz"));
  const json a = BuildInto("two", 2, true);
  EXPECT_FALSE(a.at("copc").at("resumed").get<bool>());
  for (const std::string& f : files)
    EXPECT_EQ(ReadFileToString(dir_.File("one/" + f)), ReadFileToString(dir_.File("two/" + f)))
        << f;
  json one = json::parse(ReadFileToString(dir_.File("one/archive.json")));
  one["pack_resumed"] = true;  // the only difference
  EXPECT_EQ(one, a);
}

// The files whose records were spilled, by the writers' log lines, while f runs.
template <typename F>
std::vector<std::string> SpilledWhile(const F& f) {
  std::vector<std::string> spilled;
  const LogSink old = SetLogSink([&](LogLevel, const std::string& m) {
    const size_t at = m.find(": the COPC file's records pass its memory budget");
    if (at != std::string::npos) spilled.push_back(fs::path(m.substr(0, at)).filename().string());
  });
  f();
  SetLogSink(old);
  std::sort(spilled.begin(), spilled.end());
  return spilled;
}

// A build's and an export's memory budget reach every COPC file's writer: beyond it (here 1 KB)
// the records are spilled beside the file, and the files are the same bytes.
TEST_F(CopcBuild, TheMemoryBudgetSpillsEveryFilesRecordsAndKeepsItsBytes) {
  const std::vector<std::string> files = {"layers/ground.copc.laz", "layers/wall.copc.laz",
                                          "copc/site_one.copc.laz"};
  const std::vector<std::string> all = {"ground.copc.laz", "site_one.copc.laz", "wall.copc.laz"};
  EXPECT_TRUE(SpilledWhile([&] { BuildInto("memory", 2); }).empty());
  EXPECT_EQ(SpilledWhile([&] { BuildInto("spilled", 2, false, 1024); }), all);
  for (const std::string& f : files) {
    EXPECT_EQ(ReadFileToString(dir_.File("spilled/" + f)), ReadFileToString(dir_.File("memory/" + f)))
        << f;
  }
  CopcExportOptions e;
  e.build = dir_.File("memory");
  e.out = dir_.File("exported.copc.laz");
  e.copc.layers = true;
  e.copc.memory_bytes = 1024;
  EXPECT_EQ(SpilledWhile([&] { ExportCopc(e); }),
            (std::vector<std::string>{"exported.copc.laz", "ground.copc.laz", "wall.copc.laz"}));
  EXPECT_EQ(ReadFileToString(e.out), ReadFileToString(dir_.File("spilled/copc/site_one.copc.laz")));
  for (const auto& entry : fs::recursive_directory_iterator(dir_.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".candi-tmp-copc-"), std::string::npos)
        << "a spill folder left: " << entry.path();
  }
}

TEST_F(CopcBuild, AFolderThatIsNotABuildIsNamed) {
  CopcExportOptions e;
  auto expect_named = [&](const std::string& build, const std::string& named,
                          const std::string& what) {
    e.build = build;
    try {
      ExportCopc(e);
      ADD_FAILURE() << build;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(named), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find(what), std::string::npos) << error.what();
    }
  };
  expect_named(dir_.File("no_such"), dir_.File("no_such"), "not a folder");
  fs::create_directories(dir_.File("empty"));
  expect_named(dir_.File("empty"), dir_.File("empty"), "no archive.json");
  testing::WriteBytes(dir_.File("empty/archive.json"), "{\"name\": \"x\"}");
  expect_named(dir_.File("empty"), dir_.File("empty/archive.json"), "no \"crs\"");
  json bad = {{"name", "x"},
              {"crs", nullptr},
              {"frame", {{"origin", {0, 0, 0}}}},
              {"layers", {{{"name", "../up"}, {"file", "layers/up.ply"}}}}};
  testing::WriteBytes(dir_.File("empty/archive.json"), bad.dump());
  expect_named(dir_.File("empty"), dir_.File("empty/archive.json"),
               "/layers/0/name: not a layer name");
  BuildInto("out", 2);
  fs::remove(dir_.File("out/layers/wall.ply"));
  expect_named(dir_.File("out"), dir_.File("out/layers/wall.ply"), "missing");
}

TEST_F(CopcBuild, TheSceneKeyIsChecked) {
  json j = SceneJson();
  j["copc"]["layer"] = true;
  testing::WriteBytes(dir_.File("scene.json"), j.dump());
  EXPECT_THROW(LoadScene(dir_.File("scene.json")), InputError);
  j = SceneJson();
  j["copc"]["scene"] = 1;
  testing::WriteBytes(dir_.File("scene.json"), j.dump());
  try {
    LoadScene(dir_.File("scene.json"));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/copc/scene"), std::string::npos) << e.what();
  }
}

// copc.js, an independent reader, reads the whole scene's file: every node, every point.
TEST_F(CopcBuild, CopcJsReadsTheSceneFile) {
  std::string why;
  const std::string node = testing::NodeWith("copc", &why);
  if (node.empty()) GTEST_SKIP() << why << ": the build's COPC is not checked by copc.js";
  const json a = BuildInto("out", 2);
  const std::string script = testing::SourceDir() + "/tests/node/copc_records.js";
  const std::string file = dir_.File("out/copc/site_one.copc.laz");
  const std::string command = node + " '" + script + "' '" + file + "' '" +
                              dir_.File("records.bin") + "' > '" + dir_.File("out.json") + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const json r = json::parse(ReadFileToString(dir_.File("out.json")));
  EXPECT_EQ(r.at("count"), a.at("points"));
  EXPECT_EQ(r.at("pointSum"), a.at("points"));
  EXPECT_EQ(r.at("format"), 7);
  // Point source ID (bytes 20-21 of a format 7 record) is a layer's index.
  const std::string records = ReadFileToString(dir_.File("records.bin"));
  ASSERT_EQ(records.size(), a.at("points").get<size_t>() * 36);
  std::array<uint64_t, 2> per_layer{};
  for (size_t i = 0; i < records.size(); i += 36) {
    const unsigned id =
        static_cast<uint8_t>(records[i + 20]) | static_cast<uint8_t>(records[i + 21]) << 8;
    ASSERT_LT(id, 2u);
    ++per_layer[id];
  }
  EXPECT_EQ(per_layer[0], a["layers"][0].at("points").get<uint64_t>());
  EXPECT_EQ(per_layer[1], a["layers"][1].at("points").get<uint64_t>());
}

}  // namespace
}  // namespace candi::pipeline
