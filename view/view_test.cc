// The viewer's parts below the server: the message parser, the Host/Origin checks, progressive
// accumulation (batches of ensembles give candi render's image, bit for bit), orthographic
// archive renders, picking, the first view.
#include <zlib.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/atomic_file.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/archive_render.h"
#include "render/spbr.h"
#include "render/splat_cloud.h"
#include "render/synthetic_scene.h"
#include "render/view_json.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"
#include "view/progressive.h"
#include "view/protocol.h"
#include "view/publish.h"
#include "view/server.h"
#include "view/source.h"

namespace candi::view {
namespace {

using candi::testing::TempDir;

const char* kView =
    R"({"type":"view","seq":3,"camera":{"projection":"perspective","width":64,"height":48,"eye":[10,-20,15],)"
    R"("target":[0,0,0],"up":[0,0,1],"fov_y_deg":40},"settings":{"repeat_level":20,"point_size":1.5,)"
    R"("background":[1,2,3],"brightness":2.5,"opaque":false,"seed":7}})";

TEST(Protocol, ParsesAViewAndAPick) {
  const ClientMessage m = ParseClientMessage(kView);
  EXPECT_EQ(m.type, MessageType::kView);
  EXPECT_EQ(m.seq, 3u);
  EXPECT_EQ(m.view.camera.width, 64);
  EXPECT_EQ(m.view.camera.eye, Eigen::Vector3d(10, -20, 15));
  EXPECT_EQ(m.view.settings.spbr.repeat_level, 20);
  EXPECT_EQ(m.view.settings.spbr.point_size, 1.5);
  EXPECT_EQ(m.view.settings.background, (Rgb8{1, 2, 3}));
  EXPECT_EQ(m.view.settings.brightness, Brightness::Gain(2.5));
  EXPECT_EQ(m.view.settings.spbr.seed, 7u);
  const ClientMessage p = ParseClientMessage(R"({"type":"pick","seq":4,"x":3.5,"y":-1})");
  EXPECT_EQ(p.type, MessageType::kPick);
  EXPECT_EQ(p.x, 3.5);
  EXPECT_EQ(p.y, -1);
}

TEST(Protocol, ParsesClippingAndSections) {
  std::string text = kView;
  text.insert(text.rfind("}}"), R"(,"clip":[[712345.678,9162345.1,0,0,1,0],[0,0,250.5,0,0,-1]])");
  const ClientMessage m = ParseClientMessage(text);
  ASSERT_EQ(m.view.settings.clip.planes.size(), 2u);
  EXPECT_EQ(m.view.settings.clip.planes[0].point, Eigen::Vector3d(712345.678, 9162345.1, 0));
  EXPECT_EQ(m.view.settings.clip.planes[1].normal, Eigen::Vector3d(0, 0, -1));
  EXPECT_FALSE(m.view.settings == ParseClientMessage(kView).view.settings);  // a new image
  const ClientMessage s = ParseClientMessage(
      R"({"type":"section","seq":9,"point":[1,2,3],"normal":[0,1,0],"thickness":0.25})");
  EXPECT_EQ(s.type, MessageType::kSection);
  EXPECT_EQ(s.section.point, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(s.section.thickness, 0.25);
  auto refused = [](const std::string& bad, const std::string& where) {
    try {
      ParseClientMessage(bad);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
    }
  };
  refused(R"({"type":"section","point":[1,2,3],"normal":[0,0,0],"thickness":1})", "/normal");
  refused(R"({"type":"section","point":[1,2,3],"normal":[0,1,0],"thickness":0})", "/thickness");
  refused(R"({"type":"section","point":[1,2,3],"thickness":1})", "/normal: missing");
  std::string bad = kView;
  bad.insert(bad.rfind("}}"), R"(,"clip":[[0,0,0,0,0,0]])");
  refused(bad, "/settings/clip/0");
  bad = kView;
  bad.insert(bad.rfind("}}"), R"(,"clip":[[0,0,0,1,0]])");
  refused(bad, "/settings/clip/0");
}

TEST(Protocol, RefusesMalformedMessagesNamingTheField) {
  auto refused = [](const std::string& text, const std::string& where) {
    try {
      ParseClientMessage(text);
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what() << " for " << text;
      return;
    }
    ADD_FAILURE() << "accepted: " << text;
  };
  refused("{", "byte");
  refused("[]", "expected a JSON object");
  refused(R"({"type":"hack"})", "/type");
  refused(R"({"type":"view"})", "/camera");
  refused(R"({"type":"view","camera":{"eye":[0,0,"x"]}})", "/eye/2");
  refused(R"({"type":"view","camera":{"eye":[1,2,3],"target":[1,2,3]}})", "/camera");
  refused(R"({"type":"view","camera":{"width":5000}})", "/camera");
  refused(R"({"type":"view","camera":{"eye":[1e300,0,0]}})", "/camera");
  refused(R"({"type":"view","camera":{},"settings":{"repeat_level":0}})", "/settings/repeat_level");
  refused(R"({"type":"view","camera":{},"settings":{"repeat_level":10001}})", "/settings/repeat_level");
  refused(R"({"type":"view","camera":{},"settings":{"point_size":1e999}})", "");
  refused(R"({"type":"view","camera":{},"settings":{"background":[0,0,256]}})", "/settings/background/2");
  refused(R"({"type":"view","camera":{},"settings":{"brightness":0}})", "/settings/brightness");
  refused(R"({"type":"view","camera":{},"settings":{"colour":1}})", "/settings/colour");
  refused(R"({"type":"view","camera":{},"seq":-1})", "/seq");
  refused(R"({"type":"pick","x":"a"})", "/x");
  refused(R"({"type":"pick","camera":{}})", "/camera");
  refused(std::string(kMaxMessageBytes + 1, ' '), "bytes");
  // Invalid UTF-8 in a key: refused, and the error reply is still valid JSON.
  try {
    ParseClientMessage("{\"type\":\"view\",\"camera\":{},\"\xff\":1}");
    ADD_FAILURE() << "accepted invalid UTF-8";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(ErrorReply(e.what()).find("\"error\""), std::string::npos);
  }
}

TEST(Protocol, HostAndOriginMustNameThisServer) {
  EXPECT_TRUE(HostAllowed("127.0.0.1:8765", "127.0.0.1", 8765));
  EXPECT_TRUE(HostAllowed("localhost:8765", "127.0.0.1", 8765));
  EXPECT_TRUE(HostAllowed("LOCALHOST:8765", "127.0.0.1", 8765));
  EXPECT_TRUE(HostAllowed("[::1]:8765", "127.0.0.1", 8765));
  EXPECT_FALSE(HostAllowed("127.0.0.1:8766", "127.0.0.1", 8765));
  EXPECT_FALSE(HostAllowed("127.0.0.1", "127.0.0.1", 8765));
  EXPECT_FALSE(HostAllowed("attacker.example:8765", "127.0.0.1", 8765));  // DNS rebinding
  EXPECT_FALSE(HostAllowed("192.168.1.5:8765", "127.0.0.1", 8765));
  EXPECT_FALSE(HostAllowed("", "127.0.0.1", 8765));
  EXPECT_FALSE(HostAllowed("127.0.0.1:8765:1", "127.0.0.1", 8765));
  // Serving the network: address literals, never names.
  EXPECT_TRUE(HostAllowed("192.168.1.5:8765", "0.0.0.0", 8765));
  EXPECT_FALSE(HostAllowed("attacker.example:8765", "0.0.0.0", 8765));
  EXPECT_TRUE(HostAllowed("10.0.0.2:8765", "10.0.0.2", 8765));
  EXPECT_FALSE(HostAllowed("10.0.0.3:8765", "10.0.0.2", 8765));
  EXPECT_TRUE(OriginAllowed("http://127.0.0.1:8765", "127.0.0.1", 8765));
  EXPECT_FALSE(OriginAllowed("http://attacker.example", "127.0.0.1", 8765));
  EXPECT_FALSE(OriginAllowed("null", "127.0.0.1", 8765));
  EXPECT_FALSE(OriginAllowed("https://127.0.0.1:8765", "127.0.0.1", 8765));
}

// An archive of a terraced solid in survey coordinates.
std::string MakeArchive(const TempDir& dir, uint64_t n, uint64_t chunk_points) {
  PointCloud cloud = render::TerracedSolid(n, 3);
  cloud.frame.origin = Eigen::Vector3d(500000, 9100000, 200);
  render::PackOptions o;
  o.chunk_points = chunk_points;
  const std::string path = dir.File("a.archive");
  render::PackArchive(o, {render::PackInputFromGenerator("solid", n, n, [&](uint64_t, uint64_t) { return cloud; })},
                      path);
  return path;
}

// A demo's output: the build in demo/archive (archive.json and the render archive in archive/).
std::string MakeDemoOutput(const TempDir& dir) {
  namespace fs = std::filesystem;
  const std::string build = dir.File("demo/archive");
  fs::create_directories(build);
  fs::rename(MakeArchive(dir, 3000, 512), build + "/archive");
  WriteFileAtomic(
      build + "/archive.json",
      R"({"name": "site", "licence": "CC0", "crs": {"definition": "EPSG:32749", "label": "UTM 49S"},
    "frame": {"origin": [500000, 9100000, 0]},
    "annotations": [{"title": "stair", "text": "", "position": [500000, 9100000, 201]}],
    "layers": [{"name": "solid", "kind": "points", "scanned": true, "method": "measured: a scan", "file": "layers/solid.ply",
                "sources": [{"path": "/home/someone/scans/solid.ply", "sha256": "ab12", "bytes": 9}]}]})");
  return dir.File("demo");
}

// What candi section opens, candi view and candi publish open: a demo's output too.
TEST(ViewerSource, OpensADemosOutputWithItsProvenance) {
  TempDir dir;
  const std::string demo = MakeDemoOutput(dir);
  const ViewerSource s = OpenViewerSource(demo, render::Orientation());
  EXPECT_EQ(s.kind, "build");
  EXPECT_EQ(s.title, "site");
  const render::Archive archive(s.archive_dir);
  const nlohmann::json page = nlohmann::json::parse(s.ToJson(archive.manifest()));
  const nlohmann::json& p = page.at("provenance");
  EXPECT_EQ(p.at("licence"), "CC0");
  EXPECT_EQ(p.at("annotations").size(), 1u);
  EXPECT_EQ(p.at("layers")[0].at("scanned"), true);
  // The source's file name and hash, not the build machine's path.
  EXPECT_EQ(p.at("layers")[0].at("sources")[0].at("file"), "solid.ply");
  EXPECT_EQ(page.dump().find("/home/someone"), std::string::npos);
  // A folder that is none of them is named.
  try {
    OpenViewerSource(dir.File("demo/archive/archive/.."), render::Orientation());
  } catch (const InputError& e) {
    ADD_FAILURE() << "a build folder is refused: " << e.what();
  }
  EXPECT_THROW(OpenViewerSource(dir.path(), render::Orientation()), InputError);
}

std::string Gunzip(const std::string& bytes) {
  z_stream z{};
  EXPECT_EQ(inflateInit2(&z, 15 + 16), Z_OK);
  std::string out(1 << 20, '\0'), all;
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  z.avail_in = static_cast<uInt>(bytes.size());
  int rc = Z_OK;
  while (rc == Z_OK) {
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = static_cast<uInt>(out.size());
    rc = inflate(&z, Z_NO_FLUSH);
    all.append(out.data(), out.size() - z.avail_out);
  }
  EXPECT_EQ(rc, Z_STREAM_END);
  inflateEnd(&z);
  return all;
}

// A site's page k of a group is, chunk by chunk, the slice ensemble k draws: every point of the
// archive once, in byte planes, gzip; the same bytes on 1 thread and 2.
TEST(Publish, PagesHoldEachEnsemblesSlicesAndEveryPointOnce) {
  TempDir dir;
  const std::string demo = MakeDemoOutput(dir);
  PublishOptions o;
  o.repeat_level = 7;
  o.group_points = 1200;
  o.threads = 1;
  const PublishStats stats = PublishSite(o, demo, dir.File("site"), render::Orientation());
  o.threads = 2;
  PublishSite(o, demo, dir.File("site2"), render::Orientation());
  EXPECT_TRUE(IsSite(dir.File("site")));
  const render::Archive archive(demo + "/archive/archive");
  const render::ArchiveManifest& m = archive.manifest();
  const nlohmann::json site = nlohmann::json::parse(ReadFileToString(dir.File("site/site.json")));
  const nlohmann::json& groups = site.at("data").at("groups");
  EXPECT_GT(groups.size(), 1u);
  EXPECT_EQ(stats.files, groups.size() * 7);
  EXPECT_EQ(site.at("scene").at("provenance").at("licence"), "CC0");
  uint64_t points = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    for (int k = 0; k < 7; ++k) {
      const std::string name = "data/" + std::to_string(g) + "/" + std::to_string(k) + ".bin";
      const std::string bytes = ReadFileToString(dir.File("site/" + name));
      EXPECT_EQ(bytes, ReadFileToString(dir.File("site2/" + name))) << name;
      EXPECT_EQ(bytes.size(), groups[g].at("pages")[k][0].get<uint64_t>());
      const std::string planes = Gunzip(bytes);
      const size_t n = planes.size() / 8;
      ASSERT_EQ(n, groups[g].at("pages")[k][1].get<uint64_t>()) << name;
      size_t at = 0;
      for (size_t c = groups[g].at("chunks")[0]; c < groups[g].at("chunks")[1].get<size_t>(); ++c) {
        std::vector<render::PointRun> runs;
        render::EnsembleSlices(m.chunks[c].count, m.chunks[c].first, 7, 1, k, 1.0, &runs);
        const uint64_t* words = archive.ChunkWords(c, true);
        for (const render::PointRun& r : runs) {
          for (uint64_t i = r.begin; i < r.end; ++i, ++at) {
            uint64_t w = 0;
            for (int j = 0; j < 8; ++j) w |= uint64_t{static_cast<uint8_t>(planes[j * n + at])} << (8 * j);
            ASSERT_EQ(w, words[i]) << name << " point " << at;
          }
        }
      }
      EXPECT_EQ(at, n);
      points += n;
    }
  }
  EXPECT_EQ(points, m.points);
  // An existing folder that is not a site is refused and left alone.
  std::filesystem::create_directories(dir.File("mine"));
  WriteFileAtomic(dir.File("mine/keep.txt"), "x");
  EXPECT_THROW(PublishSite(o, demo, dir.File("mine"), render::Orientation()), InputError);
  EXPECT_EQ(ReadFileToString(dir.File("mine/keep.txt")), "x");
  EXPECT_THROW(PublishSite(o, dir.path(), dir.File("site3"), render::Orientation()), InputError);
  EXPECT_FALSE(std::filesystem::exists(dir.File("site3")));
}

// The entries of `folder` (relative, sorted), recursively.
std::vector<std::string> Listing(const std::string& folder) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(folder)) {
    out.push_back(e.path().lexically_relative(folder).generic_string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Anything a publish left beside or inside its target: a build folder, an old copy.
std::vector<std::string> Leftovers(const std::string& folder) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(folder)) {
    const std::string name = e.path().filename().string();
    if (name.find(".candi-") != std::string::npos) out.push_back(e.path().string());
  }
  return out;
}

// Options for a site of several groups of the demo output's archive, at `L`.
PublishOptions SmallPages(int L) {
  PublishOptions o;
  o.repeat_level = L;
  o.group_points = 1200;
  return o;
}

// Republishing into a deployed site (a GitHub Pages folder) updates what publish wrote and keeps
// everything else: .git, CNAME, .nojekyll, the owner's own files and folders. The site is then
// the new one exactly: no page of the old L is left in data/.
TEST(Publish, RepublishingKeepsEveryFileItDidNotWrite) {
  namespace fs = std::filesystem;
  TempDir dir;
  const std::string demo = MakeDemoOutput(dir);
  PublishOptions o = SmallPages(7);
  const std::string site = dir.File("site");
  PublishSite(o, demo, site, render::Orientation());
  const std::vector<std::string> first = Listing(site);
  fs::create_directories(site + "/.git/refs");
  WriteFileAtomic(site + "/.git/HEAD", "ref: refs/heads/main\n");
  WriteFileAtomic(site + "/CNAME", "archive.example.org\n");
  WriteFileAtomic(site + "/.nojekyll", "");
  fs::create_directories(site + "/about");
  WriteFileAtomic(site + "/about/index.html", "<p>mine</p>");
  o.repeat_level = 3;
  PublishSite(o, demo, site, render::Orientation());
  EXPECT_EQ(ReadFileToString(site + "/.git/HEAD"), "ref: refs/heads/main\n");
  EXPECT_TRUE(fs::is_directory(site + "/.git/refs"));
  EXPECT_EQ(ReadFileToString(site + "/CNAME"), "archive.example.org\n");
  EXPECT_TRUE(fs::exists(site + "/.nojekyll"));
  EXPECT_EQ(ReadFileToString(site + "/about/index.html"), "<p>mine</p>");
  // The site itself: as a fresh publish of L = 3 writes it, byte for byte.
  PublishSite(o, demo, dir.File("fresh"), render::Orientation());
  std::vector<std::string> now = Listing(site);
  now.erase(std::remove_if(now.begin(), now.end(),
                           [](const std::string& p) {
                             return p.rfind(".git", 0) == 0 || p == "CNAME" || p == ".nojekyll" ||
                                    p.rfind("about", 0) == 0;
                           }),
            now.end());
  EXPECT_EQ(now, Listing(dir.File("fresh")));
  EXPECT_NE(now, first);
  for (const std::string& p : now) {
    if (fs::is_regular_file(site + "/" + p)) {
      EXPECT_EQ(ReadFileToString(site + "/" + p), ReadFileToString(dir.File("fresh/" + p))) << p;
    }
  }
  EXPECT_TRUE(Leftovers(dir.path()).empty()) << Leftovers(dir.path())[0];
  // An empty folder (made for the site) is a place for one.
  fs::create_directories(dir.File("empty"));
  PublishSite(o, demo, dir.File("empty"), render::Orientation());
  EXPECT_TRUE(IsSite(dir.File("empty")));
}

// What replacing data/ would delete is refused by name, before any work, and nothing changes.
TEST(Publish, RefusesToDeleteFilesInDataOrToReplaceAFolderWithAFile) {
  namespace fs = std::filesystem;
  TempDir dir;
  const std::string demo = MakeDemoOutput(dir);
  PublishOptions o = SmallPages(4);
  const std::string site = dir.File("site");
  PublishSite(o, demo, site, render::Orientation());
  const std::string index = ReadFileToString(site + "/site.json");
  WriteFileAtomic(site + "/data/notes.txt", "mine");
  fs::create_directories(site + "/data/0/extra");
  for (const std::string& bad : {std::string("data/notes.txt"), std::string("data/0/extra")}) {
    try {
      PublishSite(o, demo, site, render::Orientation());
      ADD_FAILURE() << "publish deleted " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
    fs::remove_all(site + "/" + bad);
  }
  EXPECT_EQ(ReadFileToString(site + "/site.json"), index);
  // A folder where the site's own file goes.
  fs::remove(site + "/viewer.css");
  fs::create_directories(site + "/viewer.css");
  EXPECT_THROW(PublishSite(o, demo, site, render::Orientation()), InputError);
  EXPECT_TRUE(fs::is_directory(site + "/viewer.css"));
  EXPECT_EQ(ReadFileToString(site + "/site.json"), index);
  EXPECT_TRUE(Leftovers(dir.path()).empty());
}

// A symbolic link to the deployed folder: that folder is updated in place (the link stays a
// link); a link to nothing is refused and nothing is made.
TEST(Publish, FollowsASymbolicLinkToTheFolderItUpdates) {
  namespace fs = std::filesystem;
  TempDir dir;
  const std::string demo = MakeDemoOutput(dir);
  PublishOptions o = SmallPages(5);
  fs::create_directories(dir.File("www"));
  PublishSite(o, demo, dir.File("www/site"), render::Orientation());
  WriteFileAtomic(dir.File("www/site/CNAME"), "x.org\n");
  fs::create_directory_symlink(dir.File("www/site"), dir.File("link"));
  o.repeat_level = 2;
  PublishSite(o, demo, dir.File("link") + "/", render::Orientation());
  EXPECT_TRUE(fs::is_symlink(dir.File("link")));
  const nlohmann::json site =
      nlohmann::json::parse(ReadFileToString(dir.File("www/site/site.json")));
  EXPECT_EQ(site.at("data").at("repeat_level"), 2);
  EXPECT_FALSE(fs::exists(dir.File("www/site/data/0/4.bin")));
  EXPECT_EQ(ReadFileToString(dir.File("www/site/CNAME")), "x.org\n");
  EXPECT_TRUE(Leftovers(dir.path()).empty());
  fs::create_directory_symlink(dir.File("nowhere"), dir.File("dangling"));
  try {
    PublishSite(o, demo, dir.File("dangling"), render::Orientation());
    ADD_FAILURE() << "a link to nothing was published into";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.File("nowhere")));
  EXPECT_TRUE(Leftovers(dir.path()).empty());
}

render::Camera WorldView(const render::Archive& archive, render::Projection projection) {
  const render::ArchiveManifest& m = archive.manifest();
  render::Camera c = render::FrameBox(m.bounds.Translated(m.frame.origin), 96, 64, Eigen::Vector3d(0.45, 0.7, -0.55),
                                      projection);
  return c;
}

TEST(Progressive, BatchesOfEnsemblesGiveTheWholeRenderBitForBit) {
  TempDir dir;
  const render::Archive archive(MakeArchive(dir, 20000, 1024));
  for (render::Projection projection : {render::Projection::kPerspective, render::Projection::kOrthographic}) {
    ViewState state;
    state.camera = WorldView(archive, projection);
    state.settings.spbr.repeat_level = 13;
    state.settings.spbr.seed = 5;
    state.settings.spbr.point_size = 1.5;
    // The whole render, as candi render draws it.
    render::ArchiveRenderOptions o;
    o.spbr.repeat_level = 13;
    o.spbr.seed = 5;
    o.spbr.point_size = 1.5;
    render::Camera local = state.camera;
    local.eye -= archive.manifest().frame.origin;
    local.target -= archive.manifest().frame.origin;
    const render::SpbrResult whole = render::RenderArchive(o, local, archive);
    const double gain = render::AutoBrightnessGain(whole);
    const Image8 expected = render::ToImage8(render::AverageImage(whole, state.settings.background, gain));

    ProgressiveImage image(archive, LocalRangeRenderer(archive), 2);
    image.Start(state);
    int steps = 0;
    for (int count : {1, 2, 4, 100}) {
      image.Step(count);
      ++steps;
      if (image.converged()) break;
    }
    EXPECT_EQ(steps, 4);
    ASSERT_TRUE(image.converged());
    double got_gain = 0;
    const Image8 got = image.Image(&got_gain);
    EXPECT_EQ(got_gain, gain);
    EXPECT_TRUE(got == expected) << "projection " << static_cast<int>(projection);
    // Something is drawn, and the two halves differ (not a blank image).
    int covered = 0;
    for (size_t i = 0; i < got.values().size(); i += 3) covered += got.values()[i] || got.values()[i + 1] || got.values()[i + 2];
    EXPECT_GT(covered, 96 * 64 / 10);
    // Restarting drops what was drawn.
    image.Start(state);
    EXPECT_EQ(image.ensembles(), 0);
    EXPECT_FALSE(image.converged());
    // A cancelled step adds nothing.
    EXPECT_THROW(image.Step(3, [] { return true; }), Cancelled);
    EXPECT_EQ(image.ensembles(), 0);
  }
}

// A sampled preview (the bound on a first frame): a random share of one ensemble's points,
// drawn but not counted; the accumulation that follows starts afresh, so the converged image is
// still candi render's, bit for bit, also at L = 1 (where the preview must not count as converged).
TEST(Progressive, SampledPreviewLeavesNoTraceInTheConvergedImage) {
  TempDir dir;
  const render::Archive archive(MakeArchive(dir, 20000, 1024));
  for (int L : {13, 1}) {
    ViewState state;
    state.camera = WorldView(archive, render::Projection::kPerspective);
    state.settings.spbr.repeat_level = L;
    state.settings.spbr.seed = 5;
    state.settings.spbr.point_size = 3;
    render::ArchiveRenderOptions o;
    o.spbr.repeat_level = L;
    o.spbr.seed = 5;
    o.spbr.point_size = 3;
    render::Camera local = state.camera;
    local.eye -= archive.manifest().frame.origin;
    local.target -= archive.manifest().frame.origin;
    const render::SpbrResult whole = render::RenderArchive(o, local, archive);
    const double gain = L > 1 ? render::AutoBrightnessGain(whole) : 1.0;
    const Image8 expected = render::ToImage8(render::AverageImage(whole, state.settings.background, gain));
    // The preview draws about the share asked for (runs round up), never the whole ensemble.
    o.ensemble_end = 1;
    const uint64_t one = render::RenderArchive(o, local, archive).copies;
    o.sample = 0.25;
    const uint64_t quarter = render::RenderArchive(o, local, archive).copies;
    EXPECT_GT(quarter, one / 5);
    EXPECT_LT(quarter, one / 3);

    ProgressiveImage image(archive, LocalRangeRenderer(archive), 2);
    image.Start(state);
    EXPECT_DOUBLE_EQ(image.EnsembleFootprint(), 20000.0 / L * 9);
    image.Step(5, nullptr, 0.25);
    EXPECT_TRUE(image.sampled());
    EXPECT_EQ(image.ensembles(), 0);
    EXPECT_FALSE(image.converged());
    double preview_gain = 0;
    const Image8 preview = image.Image(&preview_gain);
    EXPECT_EQ(preview_gain, 1.0);
    EXPECT_FALSE(preview == expected);
    for (int count : {1, 100}) {
      if (!image.converged()) image.Step(count);
    }
    EXPECT_FALSE(image.sampled());
    ASSERT_TRUE(image.converged());
    double got_gain = 0;
    EXPECT_TRUE(image.Image(&got_gain) == expected) << "L " << L;
    EXPECT_EQ(got_gain, gain);
  }
}

TEST(Progressive, OrthographicArchiveRenderAgreesWithTheInMemoryRenderer) {
  TempDir dir;
  const render::Archive archive(MakeArchive(dir, 20000, 2048));
  const PointCloud points = archive.ReadAll();
  render::SplatCloudOptions so;
  so.spbr.repeat_level = 1;
  so.spbr.seed = 1;
  const render::SplatCloud splats = render::BuildSplatCloud(so, {&points});
  render::Camera world = WorldView(archive, render::Projection::kOrthographic);
  render::Camera in_splats = world, in_archive = world;
  in_splats.eye -= splats.frame.origin, in_splats.target -= splats.frame.origin;
  in_archive.eye -= archive.manifest().frame.origin, in_archive.target -= archive.manifest().frame.origin;
  const render::SpbrResult a = render::RenderSpbr(render::SpbrOptions(), in_splats, splats);
  render::ArchiveRenderOptions o;
  o.spbr.repeat_level = 1;
  const render::SpbrResult b = render::RenderArchive(o, in_archive, archive);
  // Opaque (L = 1): the nearest point per pixel. The two renderers shift depths differently, so a
  // near tie may go either way; coverage must agree exactly and colours almost everywhere.
  size_t hits_a = 0, hits_b = 0, same = 0, covered = 0;
  for (size_t p = 0; p < a.sums.sums.size(); p += 4) {
    hits_a += a.sums.sums[p + 3];
    hits_b += b.sums.sums[p + 3];
    if (a.sums.sums[p + 3]) {
      ++covered;
      same += a.sums.sums[p] == b.sums.sums[p] && a.sums.sums[p + 1] == b.sums.sums[p + 1];
    }
  }
  EXPECT_EQ(hits_a, hits_b);
  EXPECT_GT(covered, 500u);
  EXPECT_GE(same, covered * 95 / 100);
}

using testing::OptionCheckMessage;

TEST(ViewModuleOptions, DefaultsPassCheck) {
  EXPECT_NO_THROW(PickOptions().Check());
  EXPECT_NO_THROW(ServerOptions().Check());
}

TEST(PickOptions, BadValuesNameTheField) {
  PickOptions o;
  o.radius_px = -1;
  EXPECT_EQ(OptionCheckMessage(o), "PickOptions::radius_px = -1; must be finite and >= 0");
  o = {};
  o.radius_px = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(OptionCheckMessage(o), "PickOptions::radius_px = nan; must be finite and >= 0");
  o = {};
  o.spbr.repeat_level = 0;
  EXPECT_EQ(OptionCheckMessage(o), "SpbrSettings::repeat_level = 0; must be in [1, 100000]");
  o = {};
  o.layer_fraction = {1, -0.5};
  EXPECT_EQ(OptionCheckMessage(o), "PickOptions::layer_fraction[1] = -0.5; must be in [0, 16]");
  o = {};
  o.clip = ClipRegion{{{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}}};
  EXPECT_EQ(OptionCheckMessage(o), "PickOptions::clip: plane 1 has a zero normal");
}

TEST(PickOptions, PickPointChecksThem) {
  TempDir dir;
  const render::Archive archive(MakeArchive(dir, 2000, 512));
  render::Camera local = WorldView(archive, render::Projection::kPerspective);
  local.eye -= archive.manifest().frame.origin, local.target -= archive.manifest().frame.origin;
  PickOptions o;
  o.spbr.repeat_level = 0;
  EXPECT_THROW(PickPoint(archive, local, 48, 32, o), std::invalid_argument);
}

TEST(PublishOptions, BadValuesNameTheField) {
  PublishOptions o;
  EXPECT_EQ(OptionCheckMessage(o), "no throw");
  o.repeat_level = 1001;
  EXPECT_EQ(OptionCheckMessage(o), "PublishOptions::repeat_level = 1001; must be in [0, 1000]");
  o = {};
  o.group_points = 0;
  EXPECT_EQ(OptionCheckMessage(o), "PublishOptions::group_points = 0; must be in [1, 2^28]");
  o = {};
  o.memory_mb = 8;
  EXPECT_EQ(OptionCheckMessage(o), "PublishOptions::memory_mb = 8; must be in [16, 65536]");
  o = {};
  o.threads = 257;
  EXPECT_EQ(OptionCheckMessage(o), "PublishOptions::threads = 257; must be in [0, 256]");
}

TEST(ServerOptions, BadValuesNameTheField) {
  ServerOptions o;
  o.port = 65536;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::port = 65536; must be in [0, 65535]");
  o = {};
  o.token = "a&b";
  EXPECT_EQ(OptionCheckMessage(o),
            "ServerOptions::token = a&b; must be letters, digits, - . _ ~ (or empty: random)");
  o.token = "Ab-1._~";
  EXPECT_EQ(OptionCheckMessage(o), "no throw");
  o = {};
  o.threads = -1;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::threads = -1; must be in [0, 256]");
  o = {};
  o.max_clients = 0;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::max_clients = 0; must be >= 1");
  o = {};
  o.first_frame_ms = 0;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::first_frame_ms = 0; must be finite and > 0");
  o = {};
  o.step_ms = 20;
  EXPECT_EQ(OptionCheckMessage(o),
            "ServerOptions::step_ms = 20; must be finite and >= first_frame_ms");
  o = {};
  o.jpeg_quality = 0;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::jpeg_quality = 0; must be in [1, 100]");
  o = {};
  o.max_connections = 15;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::max_connections = 15; must be >= max_clients");
  o = {};
  o.max_pixels = 0;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::max_pixels = 0; must be >= 1");
  o = {};
  o.preview_pixels = std::nan("");
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::preview_pixels = nan; must be finite and > 0");
  o = {};
  o.section_seconds = 0;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::section_seconds = 0; must be finite and > 0 s");
  o = {};
  o.section_max_points = 0;
  EXPECT_EQ(OptionCheckMessage(o), "ServerOptions::section_max_points = 0; must be >= 1");
}

TEST(Progressive, PickFindsTheNearestPointUnderThePixel) {
  TempDir dir;
  const render::Archive archive(MakeArchive(dir, 20000, 512));
  const render::ArchiveManifest& m = archive.manifest();
  render::Camera local = WorldView(archive, render::Projection::kPerspective);
  local.eye -= m.frame.origin, local.target -= m.frame.origin;
  const PointCloud points = archive.ReadAll();
  const render::Camera::Projector p = local.MakeProjector();
  // The nearest point of all projecting within 3 px of the image centre, by brute force.
  const double u = 48, v = 32;
  double best = 1e300;
  Eigen::Vector3d truth = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& x : points.positions) {
    double pu, pv, depth;
    if (p.Project(x, &pu, &pv, &depth) && (pu - u) * (pu - u) + (pv - v) * (pv - v) <= 9 && depth < best) {
      best = depth;
      truth = x;
    }
  }
  ASSERT_LT(best, 1e300) << "the centre shows the solid";
  const PickResult r = PickPoint(archive, local, u, v, PickOptions{});
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.local, truth);
  EXPECT_DOUBLE_EQ(r.depth, best);
  // Beside the image: nothing.
  EXPECT_FALSE(PickPoint(archive, local, -500, -500, PickOptions{}).hit);
}

// Two layers, one in front of the other: the pick lists both, nearest first; a hidden layer, a
// clipped-away one and the points a layer's share does not draw are never picked.
TEST(Progressive, PickTakesOnlyWhatIsShown) {
  TempDir dir;
  auto wall = [](double y, uint8_t red) {
    PointCloud c;
    PointSchema schema;
    schema.colors = true;
    c.SetSchema(schema);
    for (int i = 0; i < 200; ++i) {
      for (int j = 0; j < 200; ++j) {
        c.positions.push_back({-1 + 0.01 * i, y, -1 + 0.01 * j});
        c.colors.push_back({red, 0, 0});
      }
    }
    return c;
  };
  const PointCloud front = wall(0, 255), back = wall(2, 100);
  render::PackOptions po;
  po.chunk_points = 4096;
  render::PackArchive(po, {render::PackInputFromGenerator("front", 40000, 40000, [&](uint64_t, uint64_t) { return front; }),
                           render::PackInputFromGenerator("back", 40000, 40000, [&](uint64_t, uint64_t) { return back; })},
                      dir.File("two.archive"));
  const render::Archive archive(dir.File("two.archive"));
  ASSERT_EQ(archive.manifest().layers.size(), 2u);
  render::Camera camera;
  camera.width = 64, camera.height = 64;
  camera.eye = Eigen::Vector3d(0, -5, 0) - archive.manifest().frame.origin;
  camera.target = Eigen::Vector3d(0, 0, 0) - archive.manifest().frame.origin;
  PickOptions o;
  PickResult r = PickPoint(archive, camera, 32, 32, o);
  ASSERT_EQ(r.hits.size(), 2u);
  EXPECT_EQ(r.hits[0].layer, 0);
  EXPECT_EQ(r.hits[1].layer, 1);
  EXPECT_LT(r.hits[0].depth, r.hits[1].depth);
  EXPECT_NEAR((r.local + archive.manifest().frame.origin).y(), 0, 1e-3);
  // The front layer hidden: the back one's point.
  o.layer_fraction = {0, 1};
  r = PickPoint(archive, camera, 32, 32, o);
  ASSERT_EQ(r.hits.size(), 1u);
  EXPECT_EQ(r.hits[0].layer, 1);
  EXPECT_NEAR((r.local + archive.manifest().frame.origin).y(), 2, 1e-3);
  // The front layer clipped away (keep y >= 1).
  o.layer_fraction = {};
  o.clip = ClipRegion{{{Eigen::Vector3d(0, 1, 0) - archive.manifest().frame.origin, Eigen::Vector3d::UnitY()}}};
  r = PickPoint(archive, camera, 32, 32, o);
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.hits[0].layer, 1);
  // A share of 0.2 at L = 10: the picked point of the front layer is one its ensembles draw.
  o.clip = {};
  o.layer_fraction = {0.2, 1};
  o.spbr.repeat_level = 10;
  o.spbr.seed = 3;
  r = PickPoint(archive, camera, 32, 32, o);
  ASSERT_FALSE(r.hits.empty());
  ASSERT_EQ(r.hits[0].layer, 0);
  bool drawn = false;
  PointCloud points;
  for (size_t k = 0; k < archive.manifest().chunks.size(); ++k) {
    const render::ArchiveChunk& c = archive.manifest().chunks[k];
    if (c.layer != 0) continue;
    archive.ReadChunk(k, &points);
    for (int e = 0; e < 10; ++e) {
      std::vector<render::PointRun> runs;
      render::EnsembleSlices(c.count, c.first, 10, 3, e, 0.2, &runs);
      for (const render::PointRun& run : runs) {
        for (uint64_t i = run.begin; i < run.end; ++i) drawn |= points.positions[i] == r.hits[0].local;
      }
    }
  }
  EXPECT_TRUE(drawn);
}

TEST(ViewerSource, PointFilesColouredByAFieldCarryTheLegend) {
  // A sheet at survey coordinates whose distance runs from -1 (west) to +1 (east); one point
  // has none (NaN) and one lies outside the range.
  TempDir dir;
  PointCloud sheet = render::UniformRectangle(5000, 8, 6, 0, {10, 200, 10}, 3);
  sheet.frame.origin = Eigen::Vector3d(416000, 9168000, 100);
  const int k = sheet.AddScalarField("distance");
  for (size_t i = 0; i < sheet.size(); ++i) sheet.scalars[k].Set(i, sheet.positions[i].x() / 4 - 1);
  sheet.scalars[k].Set(0, std::numeric_limits<double>::quiet_NaN());
  sheet.scalars[k].Set(1, 7.0);
  const std::string file = dir.File("deviation.ply");
  io::WritePointCloud(file, sheet);
  FieldColouring colour_by;
  colour_by.field = "distance";
  colour_by.lo = -1;
  colour_by.hi = 1;
  ViewerSource source = PackViewerSource({file}, "", render::Orientation(), nullptr, colour_by);
  ASSERT_TRUE(source.legend.has_value());
  const render::Archive archive(source.archive_dir);
  const nlohmann::json scene = nlohmann::json::parse(source.ToJson(archive.manifest()));
  const nlohmann::json& legend = scene.at("legend");
  EXPECT_EQ(legend.at("field"), "distance");
  EXPECT_EQ(legend.at("scale"), "diverging");
  EXPECT_EQ(legend.at("lo"), -1.0);
  EXPECT_EQ(legend.at("undefined"), 1);
  EXPECT_EQ(legend.at("outside"), 1);
  EXPECT_EQ(legend.at("stops").size(), 11u);
  // Every archived point has its field's colour: west blue, east red, the two grey.
  const PointCloud packed = archive.ReadAll();
  ASSERT_EQ(packed.size(), sheet.size());
  size_t grey = 0, west_blue = 0, east_red = 0, west = 0, east = 0;
  for (size_t i = 0; i < packed.size(); ++i) {
    const Rgb8 c = packed.colors[i];
    const double x = packed.WorldPosition(i).x() - sheet.frame.origin.x();
    grey += c == kOutOfRangeGrey;
    if (x < 2) ++west, west_blue += c.b > c.r + 60;
    if (x > 6) ++east, east_red += c.r > c.b + 60;
  }
  EXPECT_EQ(grey, 2u);
  EXPECT_GE(west_blue + 1, west);
  EXPECT_GE(east_red + 1, east);
  // A pick reads the value back from the point's colour: looking straight down at x = 6 m
  // (distance 0.5), the picked point's value is its field's within the colour's width.
  const Eigen::Vector3d origin = archive.manifest().frame.origin;
  render::Camera top;
  top.width = 200;
  top.height = 200;
  top.target = sheet.frame.origin + Eigen::Vector3d(6, 3, 0) - origin;
  top.eye = top.target + Eigen::Vector3d(0, 0, 20);
  top.up = Eigen::Vector3d::UnitY();
  PickOptions po;
  po.spbr.repeat_level = 1;
  po.radius_px = 4;
  const PickResult pick = PickPoint(archive, top, 100, 100, po);
  ASSERT_TRUE(pick.hit);
  double half = 0;
  const std::optional<double> value = source.legend->ValueOfColour(pick.hits[0].colour, &half);
  ASSERT_TRUE(value.has_value());
  const double x = pick.hits[0].local.x() + origin.x() - sheet.frame.origin.x();
  EXPECT_NEAR(*value, x / 4 - 1, half + 1e-6);
  EXPECT_NEAR(*value, 0.5, 0.05);
  PickHitWorld w;
  w.field = true;
  w.value = value;
  w.value_half_width = half;
  const nlohmann::json reply = nlohmann::json::parse(PickReply(7, {w}));
  EXPECT_EQ(reply.at("hits")[0].at("value").get<double>(), *value);
  w.value.reset();  // grey: no value, said as null
  EXPECT_TRUE(nlohmann::json::parse(PickReply(7, {w})).at("hits")[0].at("value").is_null());
  std::error_code ec;
  std::filesystem::remove_all(source.temporary_dir, ec);
  // A file without the field names it (and the temporary folder is removed).
  colour_by.field = "lod95";
  try {
    PackViewerSource({file}, "", render::Orientation(), nullptr, colour_by);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("deviation.ply"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace candi::view
