// The page's data: cloud decimation, ellipsoids as mesh parameters, candidates scored by F, the
// scene's JSON, and the scenes of a scan folder; each checked against numbers worked by hand.
#include "core/view/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/base/units.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "file_test_util.hpp"
#include "sphere_ellipsoid.hpp"
#include "core/base/format.hpp"
#include "core/scan/scan_record.hpp"

namespace pbnbv {
namespace {

using testing::sphere_ellipsoid;

// 10 x 10 x 10 points, 1 cm apart, at 0.5, 1.5, ... 9.5 cm.
PointCloud grid_cloud() {
  PointCloud c;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k) c.emplace_back(0.005f + 0.01f * i, 0.005f + 0.01f * j, 0.005f + 0.01f * k);
  return c;
}

TEST(DecimateCloud, OnePointPerVoxelAndTheEdgeGrowsUntilItFits) {
  // 2 cm voxels hold 2 x 2 x 2 points: 5^3 = 125 remain.
  EXPECT_EQ(decimate_cloud(grid_cloud(), 0.02, 1000).size(), 125u);
  // At most 100: the edge grows to 3 cm, 4 voxels per axis (keys 0,0,0,1,1,1,2,2,2,3): 64.
  EXPECT_EQ(decimate_cloud(grid_cloud(), 0.02, 100).size(), 64u);
  EXPECT_TRUE(decimate_cloud({}, 0.02, 100).empty());
  EXPECT_THROW(decimate_cloud(grid_cloud(), 0.0, 100), std::invalid_argument);
  EXPECT_THROW(decimate_cloud(grid_cloud(), 0.01, 0), std::invalid_argument);
}

TEST(EllipsoidMesh, TheUnitSphereLandsOnTheEllipsoidsAxes) {
  Ellipsoid e;
  e.cls = EllipsoidClass::kFrontier;
  e.centre = {0.1, -0.2, 0.3};
  e.semi_axes = {0.05, 0.02, 0.01};
  // A reflection (det -1): the mesh must still get a proper rotation.
  e.axes = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  e.axes.col(2) *= -1;
  const EllipsoidMesh m = ellipsoid_mesh(e);
  EXPECT_TRUE(m.frontier);
  EXPECT_NEAR(m.quat_xyzw.norm(), 1.0, 1e-12);
  const Eigen::Quaterniond q(m.quat_xyzw[3], m.quat_xyzw[0], m.quat_xyzw[1], m.quat_xyzw[2]);
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d drawn = m.centre + q * m.scale.cwiseProduct(Eigen::Vector3d::Unit(k));
    const Eigen::Vector3d tip = e.centre + e.semi_axes[k] * e.axes.col(k);
    const Eigen::Vector3d other_tip = e.centre - e.semi_axes[k] * e.axes.col(k);
    EXPECT_LT(std::min((drawn - tip).norm(), (drawn - other_tip).norm()), 1e-12) << "axis " << k;
  }
}

TEST(ScoreCandidates, ASphereAtTheCentreScoresItsProjectedDiscEverywhere) {
  // B = +-5 cm: R = 0.6 + 0.0866 m. A frontier sphere r = 5 cm at B's centre, seen on axis from
  // distance R by every candidate: a disc of radius f r / sqrt(R^2 - r^2) = 50.82 px, 8114 px^2.
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Constant(-0.05), Eigen::Vector3d::Constant(0.05));
  CandidateSpec spec;
  spec.num_views = 100;
  spec.num_parallels = 10;
  spec.area = CandidateArea::kFullSphere;
  spec.working_distance_m = 0.6;
  const CameraIntrinsics camera;  // 1280 x 720, f = 696
  const std::vector<ScoredCandidate> c = score_candidates({sphere_ellipsoid({0, 0, 0}, 0.05, EllipsoidClass::kFrontier)}, box, spec, camera);
  ASSERT_EQ(c.size(), 100u);
  const double d = 0.6 + 0.5 * std::sqrt(3 * 0.1 * 0.1);
  const double rho = camera.fx * 0.05 / std::sqrt(d * d - 0.05 * 0.05);
  for (const ScoredCandidate& s : c) {
    EXPECT_NEAR(s.quality, kPi * rho * rho, 0.01 * kPi * rho * rho);
    EXPECT_NEAR(s.object_T_camera.translation().norm(), d, 1e-9);
  }
  EXPECT_NEAR(kPi * rho * rho, 8114, 5);
}

TEST(ScoreCandidates, ShadeRunsFromTheLowestToTheHighestF) {
  // An occupied sphere on the +x side in front of the frontier one: cameras on +x see it nearer
  // (weight 1, the frontier 0.5) and score lowest; cameras on -x score highest.
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Constant(-0.1), Eigen::Vector3d::Constant(0.1));
  CandidateSpec spec;
  spec.num_views = 200;
  spec.num_parallels = 10;
  spec.area = CandidateArea::kFullSphere;
  const std::vector<ScoredCandidate> c =
      score_candidates({sphere_ellipsoid({0, 0, 0}, 0.05, EllipsoidClass::kFrontier), sphere_ellipsoid({0.08, 0, 0}, 0.03, EllipsoidClass::kOccupied)},
                       box, spec, CameraIntrinsics{});
  ASSERT_EQ(c.size(), 200u);
  int lo = 0, hi = 0;
  for (int i = 0; i < 200; ++i) {
    EXPECT_GE(c[i].shade, 0.0);
    EXPECT_LE(c[i].shade, 1.0);
    if (c[i].quality < c[lo].quality) lo = i;
    if (c[i].quality > c[hi].quality) hi = i;
  }
  EXPECT_DOUBLE_EQ(c[lo].shade, 0.0);
  EXPECT_DOUBLE_EQ(c[hi].shade, 1.0);
  EXPECT_GT(c[lo].object_T_camera.translation().x(), 0.5);
  EXPECT_LT(c[hi].object_T_camera.translation().x(), 0.0);
}

TEST(SceneJson, FlatArraysWithTheirCounts) {
  Scene s;
  s.scan_id = "box-1";
  s.view = 2;
  s.cloud = {{1, 2, 3}, {4, 5, 6}};
  s.cloud_points_total = 10;
  s.frontier = {{0.5f, 0, 0}};
  s.views_taken = {Pose::Identity(), Pose(Eigen::Translation3d(0, 0, 1))};
  const nlohmann::json j = scene_json(s);
  EXPECT_EQ(j["cloud_points"], 2);
  EXPECT_EQ(j["cloud"].size(), 6u);
  EXPECT_FLOAT_EQ(j["cloud"][5].get<float>(), 6.0f);
  EXPECT_EQ(j["frontier"].size(), 3u);
  EXPECT_EQ(j["views_taken"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["views_taken"][1]["position_m"][2].get<double>(), 1.0);
  EXPECT_TRUE(j["chosen"].is_null());
  EXPECT_TRUE(j["coverage_percent"].is_null());
  s.chosen = Pose::Identity();
  EXPECT_FALSE(scene_json(s)["chosen"].is_null());
}

class ScanFolder : public testing::TempDirTest {};

// A view taken from `pose` and merged, its frame frames/view_NNN.ply, its map's B 10 cm wide.
ViewRecord view_entry(int i, const Pose& pose) {
  ViewRecord v;
  v.view = i;
  v.capture = CaptureResult{};
  v.capture->ok = true;
  v.capture->object_T_camera = pose;
  v.registration = RegisteredCloud{};
  v.registration->accepted = true;
  v.registration->cloud.object_T_camera = pose;
  v.registration->frame_file = frame_file_of(i);
  v.map = VoxelMapSummary{};
  v.map->bbox_min_m = Eigen::Vector3d::Constant(-0.05);
  v.map->bbox_max_m = Eigen::Vector3d::Constant(0.05);
  v.map->resolution_m = 0.03;
  return v;
}

TEST_F(ScanFolder, OneScenePerViewWithTheCloudSoFarAndTheNextPlan) {
  std::filesystem::create_directories(path("frames"));
  write_ply({{0.01f, 0, 0}, {0.02f, 0, 0}}, path("frames/view_001.ply"));     // 2 points, 1 cm apart
  write_ply({{0, 0.05f, 0}, {0, 0.06f, 0}, {0, 0.07f, 0}}, path("frames/view_002.ply"));
  const Pose p0(Eigen::Translation3d(0.7, 0, 0));
  const Pose p1(Eigen::Translation3d(0, 0.7, 0));
  RecordedScan scan;
  scan.pbnbv_version = "test";
  scan.settings.scan_id = "sphere-1";
  scan.settings.camera = CameraIntrinsics{1280, 720, 696.0, 696.0, 640.0, 360.0};
  scan.settings.candidates = 50;
  scan.settings.parallels = 5;
  scan.settings.area = CandidateArea::kFullSphere;
  scan.status.state = "done";
  scan.status.message = "view budget reached";
  ViewRecord v1 = view_entry(1, p1);
  v1.plan = PlanRecord{};
  v1.plan->map_of_view = 0;
  v1.plan->plan.iteration = 1;
  v1.plan->plan.outcome = PlanOutcome::kView;
  v1.plan->plan.num_candidates = 50;
  v1.plan->plan.sphere_radius_m = 0.6 + 0.5 * std::sqrt(3 * 0.1 * 0.1);
  v1.plan->plan.object_T_camera = p1;
  v1.plan->plan.view_quality = 8114.0;
  EllipsoidSummary e;
  e.frontier = true;
  e.semi_axes_m = Eigen::Vector3d::Constant(0.05);
  e.num_voxels = 4;
  v1.plan->ellipsoids = EllipsoidSetSummary{};
  v1.plan->ellipsoids->ellipsoids = {e};
  scan.views = {view_entry(0, p0), v1};
  write_json_atomic(to_json(scan), path("scan.json"));

  const std::vector<Scene> s = load_scan_folder(dir_.string(), 0.001, 1000);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].view, 1);
  EXPECT_EQ(s[0].cloud.size(), 2u);
  EXPECT_EQ(s[1].cloud.size(), 5u);
  EXPECT_EQ(s[1].cloud_points_total, 5u);
  EXPECT_EQ(s[0].views_taken.size(), 1u);
  EXPECT_EQ(s[1].views_taken.size(), 2u);
  // After view 1: the plan of view 2, 50 candidates all scoring the centred disc (d_c = 0.6 m).
  ASSERT_EQ(s[0].candidates.size(), 50u);
  EXPECT_EQ(s[0].plan_candidates, 50);
  EXPECT_NEAR(s[0].candidates[0].quality, 8114, 0.01 * 8114);
  ASSERT_TRUE(s[0].chosen.has_value());
  EXPECT_NEAR((s[0].chosen->translation() - p1.translation()).norm(), 0, 1e-12);
  ASSERT_EQ(s[0].ellipsoids.size(), 1u);
  EXPECT_TRUE(s[0].ellipsoids[0].frontier);
  // After the last view: no plan.
  EXPECT_TRUE(s[1].candidates.empty());
  EXPECT_FALSE(s[1].chosen.has_value());
  EXPECT_NE(s[1].status.find("view 2 of 2"), std::string::npos);
}

TEST_F(ScanFolder, AFolderWithoutScanJsonIsNamed) {
  try {
    load_scan_folder(dir_.string(), 0.005, 1000);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("has no scan.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(dir_.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_scan_folder(path("nothing-here"), 0.005, 1000), std::runtime_error);
}

}  // namespace
}  // namespace pbnbv
