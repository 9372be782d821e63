#include "reconstruction/photogrammetry/georef/georef.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/check.h"
#include "core/rng.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

using V = Eigen::Vector3d;
using testing::TempDir;
using testing::WriteBytes;

// Survey frame near Borobudur (UTM 49S); the models are small, rotated and scaled.
const V kSite(416000.0, 9168000.0, 265.0);

// model = s R (survey - site) + t: a small model frame, as photogrammetry gives.
Sim3 ModelFromSurvey(double scale, double angle, const V& t) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, V(0.1, 0.2, 1).normalized()));
  return Sim3(scale, q, t - scale * (q * kSite));
}

std::vector<SurveyTarget> SiteTargets(int n, uint64_t seed, int checks) {
  Rng rng(seed);
  std::vector<SurveyTarget> targets;
  for (int i = 0; i < n; ++i) {
    SurveyTarget t;
    t.name = "T" + std::to_string(i);
    t.survey = kSite + V(rng.Uniform(-60, 60), rng.Uniform(-60, 60), rng.Uniform(0, 35));
    t.role = i < n - checks ? TargetRole::kControl : TargetRole::kCheck;
    t.accuracy = 0.003;
    targets.push_back(t);
  }
  return targets;
}

// Gives each target model coordinates: model = M * survey + noise.
void SetModel(const Sim3& model_from_survey, double noise, uint64_t seed,
              std::vector<SurveyTarget>* targets) {
  Rng rng(seed);
  for (SurveyTarget& t : *targets) {
    t.model = model_from_survey * t.survey +
              model_from_survey.scale * noise * V(rng.Normal(), rng.Normal(), rng.Normal());
    t.has_model = true;
  }
}

std::string Error(const std::string& text, const std::string& file = "t.csv") {
  TempDir dir;
  WriteBytes(dir.File(file), text);
  try {
    if (file == "picks.csv") {
      ReadImagePicks(dir.File(file));
    } else {
      ReadSurveyTargets(dir.File(file));
    }
  } catch (const InputError& e) {
    const std::string what = e.what();
    return what.substr(what.find(file) + file.size());
  }
  return "no error";
}

TEST(ReadSurveyTargets, ParsesControlCheckAndOptionalModelCoordinates) {
  TempDir dir;
  WriteBytes(dir.File("t.csv"),
             "# survey 2026-11-01\nName,E,N,H,Role,Accuracy,x,y,z\n"
             "A, 416000.123, 9168000.456, 265.789, control, 0.003, 1.5, 2.5, 3.5\r\n"
             "B,416010,9168010,266,CHECK,0.005,,,\n\n");
  const std::vector<SurveyTarget> t = ReadSurveyTargets(dir.File("t.csv"));
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0].survey, V(416000.123, 9168000.456, 265.789));
  EXPECT_TRUE(t[0].has_model);
  EXPECT_EQ(t[0].model, V(1.5, 2.5, 3.5));
  EXPECT_EQ(t[0].line, 3);
  EXPECT_EQ(t[1].role, TargetRole::kCheck);
  EXPECT_FALSE(t[1].has_model);
  EXPECT_DOUBLE_EQ(t[1].accuracy, 0.005);
}

TEST(ReadSurveyTargets, ErrorsNameTheLineAndField) {
  const std::string h = "name,E,N,H,role,accuracy\n";
  EXPECT_EQ(Error(h + "A,1,2,3,control,0.01\nB,1,x2,3,control,0.01\n"),
            ": line 3: field 'N': 'x2' is not a finite number");
  EXPECT_EQ(Error(h + "A,1,2,3,base,0.01\n"), ": line 2: field 'role': 'base'; must be control or check");
  EXPECT_EQ(Error(h + "A,1,2,3,check,0\n"), ": line 2: field 'accuracy': 0; must be > 0 m");
  EXPECT_EQ(Error(h + "A,1,2,3,check,0.01,7\n"), ": line 2: 7 fields; the header has 6");
  EXPECT_EQ(Error(h + "A,1,2,3,check,nan\n"), ": line 2: field 'accuracy': 'nan' is not a finite number");
  EXPECT_EQ(Error(h + "A,1,2,3,check,1\nA,1,2,3,check,1\n"), ": line 3: field 'name': 'A' appears twice");
  EXPECT_EQ(Error("name,E,N,role,accuracy\n"), ": line 1: header lacks the column 'H'");
  EXPECT_EQ(Error("name,E,N,H,role,accuracy,x,y,z\nA,1,2,3,check,1,1,,3\n"),
            ": line 2: field 'y': '' is not a finite number");
  EXPECT_EQ(Error(""), ": empty: no header row");
  EXPECT_EQ(Error(h), ": no targets (only a header)");
  EXPECT_EQ(Error("name,image,u,v\nA,img1.jpg,10,-\n", "picks.csv"),
            ": line 2: field 'v': '-' is not a finite number");
}

TEST(Georeference, FlagsABlunderAndReportsControlAndCheckRmse) {
  std::vector<SurveyTarget> targets = SiteTargets(14, 1, 4);
  const double noise = 0.002;  // m, per axis, in survey units
  SetModel(ModelFromSurvey(0.1, 2.0, V(1, 2, 3)), noise, 2, &targets);
  targets[3].model += V(0.03, 0, 0);  // 0.3 m in the survey frame
  const GeorefResult r = Georeference({}, targets, "t.csv");
  EXPECT_TRUE(r.fit.converged);
  for (size_t i = 0; i < targets.size(); ++i) EXPECT_EQ(r.outlier[i], i == 3) << i;
  EXPECT_NEAR(r.residuals[3].norm(), 0.3, 0.02);
  EXPECT_EQ(r.control.count, 9);
  EXPECT_EQ(r.check.count, 4);
  EXPECT_LT(r.control.d3, 3 * noise * std::sqrt(3.0));
  EXPECT_LT(r.check.d3, 3 * noise * std::sqrt(3.0));
  EXPECT_GT(r.check.d3, 0.2 * noise);
  EXPECT_NEAR(r.check.xy, std::hypot(r.check.x, r.check.y), 1e-12);
  EXPECT_NEAR(r.survey_from_model.scale, 10.0, 0.01);
  EXPECT_EQ(r.frame.origin, V(416000, 9168000, 300));  // integer shift near the targets
}

TEST(Georeference, NeedsThreeUsableControlTargets) {
  std::vector<SurveyTarget> targets = SiteTargets(5, 3, 3);
  SetModel(ModelFromSurvey(1, 0, V::Zero()), 0, 0, &targets);
  try {
    Georeference({}, targets, "t.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.csv: 2 usable control targets"), std::string::npos)
        << e.what();
  }
}

// A camera at `centre` looking at `at` (model frame), 1000 px focal length, 1000 x 800 image.
ProjectionMatrix Camera(const V& centre, const V& at) {
  const V z = (at - centre).normalized();
  const V x = z.cross(V(0, 0, 1)).normalized();
  const V y = z.cross(x);
  Eigen::Matrix3d r;
  r << x.transpose(), y.transpose(), z.transpose();
  Eigen::Matrix3d k;
  k << 1000, 0, 500, 0, 1000, 400, 0, 0, 1;
  ProjectionMatrix p;
  p << r, -r * centre;
  return k * p;
}

TEST(TriangulatePoint, RecoversAPointAndReportsReprojection) {
  const V x(1, 2, 0.5);
  std::vector<ProjectionMatrix> cams = {Camera(V(-5, -5, 5), x), Camera(V(5, -5, 5), x),
                                        Camera(V(0, 6, 4), x)};
  std::vector<Eigen::Vector2d> uv;
  Rng rng(4);
  for (const auto& p : cams) {
    uv.push_back((p * x.homogeneous()).hnormalized() + 0.5 * Eigen::Vector2d(rng.Normal(), rng.Normal()));
  }
  const Triangulation t = TriangulatePoint(cams, uv);
  EXPECT_TRUE(t.converged);
  EXPECT_TRUE(t.in_front);
  EXPECT_LT((t.point - x).norm(), 0.01);
  EXPECT_GT(t.rms_px, 0.05);
  EXPECT_LT(t.rms_px, 1.0);
  EXPECT_GE(t.max_px, t.rms_px);
  EXPECT_THROW(TriangulatePoint({cams[0]}, {uv[0]}), std::invalid_argument);
}

TEST(Georeference, PickedTargetsAreTriangulatedFromTheCameras) {
  std::vector<SurveyTarget> targets = SiteTargets(8, 5, 2);
  const Sim3 model_from_survey = ModelFromSurvey(0.05, 0.5, V(0.5, -0.5, 0));
  SetModel(model_from_survey, 0, 0, &targets);
  // Four cameras around and above the site (model frame: ~6 m across).
  V centre = V::Zero();
  for (const SurveyTarget& t : targets) centre += t.model / static_cast<double>(targets.size());
  std::map<std::string, ProjectionMatrix> cameras;
  for (int k = 0; k < 4; ++k) {
    const double a = k * M_PI / 2;
    cameras["img" + std::to_string(k) + ".jpg"] =
        Camera(centre + V(8 * std::cos(a), 8 * std::sin(a), 6), centre);
  }
  std::vector<ImagePick> picks;
  Rng rng(6);
  for (SurveyTarget& t : targets) {
    for (const auto& [name, p] : cameras) {
      picks.push_back({t.name, name, (p * t.model.homogeneous()).hnormalized() +
                                         0.2 * Eigen::Vector2d(rng.Normal(), rng.Normal()), 0});
    }
    t.has_model = false;
  }
  picks.push_back({"T0", "other_chunk.jpg", Eigen::Vector2d(1, 1), 0});
  picks.erase(picks.begin() + 8, picks.begin() + 11);  // T2 only in one image
  EXPECT_EQ(TriangulateTargets(picks, "picks.csv", cameras, &targets), 1);
  EXPECT_FALSE(targets[2].has_model);
  EXPECT_NE(targets[2].unused_reason.find("picked in 1 image"), std::string::npos);
  EXPECT_EQ(targets[0].views, 4);
  EXPECT_LT(targets[0].reprojection_px, 1.0);
  const GeorefResult r = Georeference({}, targets, "t.csv");
  EXPECT_EQ(r.check.count, 2);
  EXPECT_GE(r.control.count, 4);  // 5 triangulated control targets (one may be flagged)
  EXPECT_LT(r.check.d3, 0.1);  // 0.2 px at ~10 m, 1000 px focal: ~2 mm model, ~4 cm survey
  EXPECT_NEAR(r.survey_from_model.scale, 20, 0.1);
  picks.push_back({"T99", "img0.jpg", Eigen::Vector2d(1, 1), 12});
  EXPECT_THROW(TriangulateTargets(picks, "picks.csv", cameras, &targets), InputError);
}

// Two chunks, processed separately (each its own unknown similarity), share an overlap; georeferenced
// with the same targets they land in one frame where the overlap agrees to a millimetre.
TEST(Georeference, TiesSeparatelyProcessedChunksIntoOneFrame) {
  const std::vector<SurveyTarget> surveyed = SiteTargets(10, 7, 2);
  const Sim3 chunk_a = ModelFromSurvey(0.2, 1.0, V(10, -20, 5));
  const Sim3 chunk_b = ModelFromSurvey(3.0, -2.5, V(-100, 40, 9));
  std::vector<SurveyTarget> ta = surveyed, tb = surveyed;
  SetModel(chunk_a, 0.0005, 8, &ta);
  SetModel(chunk_b, 0.0005, 9, &tb);
  const GeorefResult ra = Georeference({}, ta, "a.csv"), rb = Georeference({}, tb, "b.csv");
  EXPECT_EQ(ra.frame, rb.frame);
  // The overlap: the same surface points expressed in each chunk's model frame.
  PointCloud a, b;
  Rng rng(10);
  for (int i = 0; i < 100; ++i) {
    const V world = kSite + V(rng.Uniform(-20, 20), rng.Uniform(-20, 20), rng.Uniform(0, 30));
    a.positions.push_back(chunk_a * world);
    b.positions.push_back(chunk_b * world);
  }
  ApplySimilarity(ra.survey_from_model, ra.frame, &a);
  ApplySimilarity(rb.survey_from_model, rb.frame, &b);
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a.positions[i] - b.positions[i]).norm());
  EXPECT_LT(worst, 0.002);
  EXPECT_GT(worst, 0.0);  // the targets are noisy, so the chunks differ a little
}

TEST(ApplySimilarity, KeepsSurveyCoordinatesExactAcrossShifts) {
  PointCloud cloud;
  cloud.frame.origin = V(1000, 2000, 0);  // an input already shifted
  cloud.positions = {V(0.25, 0.5, 1.0), V(-3, 4, 5)};
  cloud.SetSchema([] { PointSchema s; s.normals = true; return s; }());
  cloud.normals = {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(1, 0, 0)};
  const Sim3 t(2.0, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, V::UnitZ())),
               V(416000.001, 9168000.002, 100.003));
  LocalFrame out;
  out.origin = V(416000, 9168000, 0);
  const V expected = t * V(1000.25, 2000.5, 1.0);
  ApplySimilarity(t, out, &cloud);
  EXPECT_EQ(cloud.frame, out);
  EXPECT_LT((cloud.WorldPosition(0) - expected).norm(), 1e-8);
  EXPECT_LT((cloud.normals[1] - Eigen::Vector3f(0, 1, 0)).norm(), 1e-6);
}

}  // namespace
}  // namespace candi::photogrammetry
