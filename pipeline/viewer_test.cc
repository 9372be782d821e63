// The viewer's session without argv: what it serves, the packing of point files (a preview first
// when they are large, then every point on a thread of its own), the port it binds, bad inputs.
// Pages, frames and section exports are tested in the browser (tests/browser/view_*_test.py),
// and under mpirun by tests/browser/view_mpi_test.py.
#include "pipeline/viewer.h"

#include <gtest/gtest.h>

#include <mutex>
#include <string>
#include <vector>

#include "core/check.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"
#include "view/source.h"

namespace candi::pipeline {
namespace {

using testing::ExpectEachBreakRejected;
using testing::TempDir;

// A sheet of `points` points in survey coordinates, as a binary PLY (its points are records).
std::string Sheet(const TempDir& dir, size_t points) {
  PointCloud sheet = render::UniformRectangle(points, 8, 6, 0, {200, 40, 40}, 1);
  for (Eigen::Vector3d& p : sheet.positions) p += Eigen::Vector3d(500000.25, 9100000.5, 12);
  io::WritePointCloud(dir.File("sheet.ply"), sheet);
  return dir.File("sheet.ply");
}

ViewerOptions Quick() {
  ViewerOptions o;
  o.port = 0;
  o.server.threads = 1;
  return o;
}

// The tasks a viewer reports (label, then "finish"), and a serving that stops at once.
struct Recorder {
  std::mutex mutex;
  std::vector<std::string> events;
  std::string url;
  ViewerCallbacks Callbacks() {
    ViewerCallbacks c;
    c.progress.start = [this](const std::string& label,
                              const std::string& unit) -> ProgressCallback {
      Add(label + " (" + unit + ")");
      return nullptr;
    };
    c.progress.finish = [this] { Add("finish"); };
    c.serving = [this](view::Server& server) {
      Add("serving");
      url = server.Url();
      server.Stop();
    };
    return c;
  }
  void Add(const std::string& event) {
    std::lock_guard<std::mutex> lock(mutex);
    events.push_back(event);
  }
};

TEST(ViewerOptions, DefaultsPassAndEachRuleIsChecked) {
  ExpectEachBreakRejected<ViewerOptions>({}, {
                                                 [](ViewerOptions& o) { o.server.max_clients = 0; },
                                                 [](ViewerOptions& o) { o.port = -1; },
                                                 [](ViewerOptions& o) { o.port = 65536; },
                                                 [](ViewerOptions& o) {
                                                   o.colour_by.field = "intensity";
                                                   o.colour_by.lo = 2;
                                                   o.colour_by.hi = 1;
                                                 },
                                             });
}

TEST(ServeViewer, AnArchiveIsServedAsItIs) {
  TempDir dir;
  render::PackFiles(render::PackOptions(), {Sheet(dir, 2000)}, "", dir.File("archive"));
  Recorder r;
  ServeViewer(Quick(), {dir.File("archive")}, r.Callbacks());
  EXPECT_EQ(r.events, std::vector<std::string>({"serving"}));
  EXPECT_EQ(r.url.rfind("http://127.0.0.1:", 0), 0u) << r.url;
  EXPECT_NE(r.url.find("/?token="), std::string::npos) << r.url;
}

TEST(ServeViewer, LargePointFilesShowAPreviewWhileEveryPointIsPacked) {
  TempDir dir;
  const std::string file = Sheet(dir, 3000);
  ViewerOptions o = Quick();
  o.preview = 500;
  Recorder r;
  ServeViewer(o, {file}, r.Callbacks());  // returns once the whole is packed
  EXPECT_EQ(r.events, std::vector<std::string>(
                          {"view: packing a preview of 500 points (points)", "finish", "serving",
                           "view: packing all 3000 points (points)", "finish"}));
  // Below twice the preview, or with no preview, the files are packed whole at once.
  for (uint64_t preview : {uint64_t{1500}, uint64_t{0}}) {
    o.preview = preview;
    Recorder whole;
    ServeViewer(o, {file}, whole.Callbacks());
    EXPECT_EQ(whole.events, std::vector<std::string>(
                                {"view: packing 1 point file(s) (points)", "finish", "serving"}));
  }
}

TEST(ServeViewer, BadInputsAreRefusedBeforeAnythingIsServed) {
  TempDir dir;
  const std::string file = Sheet(dir, 500);
  render::PackFiles(render::PackOptions(), {file}, "", dir.File("archive"));
  Recorder r;
  EXPECT_THROW(ServeViewer(Quick(), {file, dir.File("archive")}, r.Callbacks()),
               std::invalid_argument);
  ViewerOptions coloured = Quick();
  coloured.colour_by.field = "intensity";
  EXPECT_THROW(ServeViewer(coloured, {dir.File("archive")}, r.Callbacks()), std::invalid_argument);
  EXPECT_THROW(ServeViewer(Quick(), {dir.File("missing.ply")}, r.Callbacks()), InputError);
  ViewerOptions bad = Quick();
  bad.server.max_clients = 0;
  EXPECT_THROW(ServeViewer(bad, {file}, r.Callbacks()), std::invalid_argument);
  // A port in use, given explicitly, is not replaced by another.
  const view::ViewerSource source =
      view::OpenViewerSource(dir.File("archive"), render::Orientation());
  const render::Archive archive(source.archive_dir);
  const view::Server taken(view::ServerOptions(), source, archive,
                           view::LocalRangeRenderer(archive));
  ViewerOptions same = Quick();
  same.port = taken.port();
  EXPECT_THROW(ServeViewer(same, {dir.File("archive")}, r.Callbacks()), InputError);
  EXPECT_EQ(std::count(r.events.begin(), r.events.end(), "serving"), 0);
}

}  // namespace
}  // namespace candi::pipeline
