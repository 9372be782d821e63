// candi render's archive path without mpirun: the whole image in this process, as
// RenderArchiveEnsembles draws it, and a failure thrown as it comes (under mpirun, the ranks'
// split is tested end to end by tests/archive_cli_test.cc).
#include "pipeline/render_ranks.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

using testing::TempDir;

// A sheet in survey coordinates, packed into DIR/archive.
std::string Archive(const TempDir& dir) {
  PointCloud sheet = render::UniformRectangle(5000, 8, 6, 0, {200, 40, 40}, 1);
  for (Eigen::Vector3d& p : sheet.positions) p += Eigen::Vector3d(500000.25, 9100000.5, 12);
  io::WritePointCloud(dir.File("sheet.ply"), sheet);
  render::PackFiles(render::PackOptions(), {dir.File("sheet.ply")}, "", dir.File("archive"));
  return dir.File("archive");
}

// A small image of a few ensembles.
RenderOptions Small() {
  RenderOptions o;
  o.image.width = 64, o.image.height = 48, o.image.spbr.repeat_level = 4;
  return o;
}

TEST(RenderArchiveOnRanks, WithoutMpiTheWholeImageInThisProcess) {
  TempDir dir;
  const std::string archive = Archive(dir);
  int failed = 0;
  const RanksReporting reporting{nullptr, [&](const auto&, int) { ++failed; }};
  const RanksRender r = RenderArchiveOnRanks(Small(), archive, reporting);
  EXPECT_TRUE(r.root);
  EXPECT_TRUE(r.failures.empty());
  EXPECT_EQ(failed, 0);
  const RenderedImage whole = RenderArchiveEnsembles(Small(), render::Archive(archive), 0, 1);
  EXPECT_EQ(r.image.result.ensembles, 4);
  EXPECT_TRUE(r.image.result.sums == whole.result.sums);
  EXPECT_EQ(r.image.mode, whole.mode);
}

TEST(RenderArchiveOnRanks, WithoutMpiAFailureIsThrownAsItComes) {
  TempDir dir;
  const RanksReporting reporting;
  EXPECT_THROW(RenderArchiveOnRanks(Small(), dir.File("nowhere"), reporting), InputError);
  RenderOptions alpha = Small();
  alpha.alpha = {0.5};
  EXPECT_THROW(RenderArchiveOnRanks(alpha, Archive(dir), reporting), std::invalid_argument);
}

}  // namespace
}  // namespace candi::pipeline
