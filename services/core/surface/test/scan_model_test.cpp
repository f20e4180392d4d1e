// The registration service's model of a scan and the files it writes for each view, from
// hand-made views: frames/view_NNN.ply, cloud.ply (merged, downsampled), what each view added,
// depth/view_NNN.png and .json, a restart from cloud.ply, and the revision that says what is stale.
#include "core/surface/scan_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/perception/neighbours.hpp"
#include "file_test_util.hpp"

using namespace pbnbv;
using nlohmann::json;

namespace {

using ScanModelTest = pbnbv::testing::TempDirTest;

TEST_F(ScanModelTest, AcceptedViewsAreMergedAndDownsampledRejectedOnesOnlyKeptInFrames) {
  ScanModel model(dir_, 0.002, 0.005);
  const Pose pose = Pose::Identity();
  // Two points 0.5 mm apart fall into one 2 mm voxel: merged into their centroid.
  const ModelUpdate u0 =
      model.add_view(0, {Eigen::Vector3f(0.0105f, 0.0105f, 0.0105f), Eigen::Vector3f(0.5f, 0, 0)}, {}, pose, true);
  const ModelUpdate u1 = model.add_view(1, {Eigen::Vector3f(0.0110f, 0.0105f, 0.0105f)}, {}, pose, true);
  const ModelUpdate u2 = model.add_view(2, {Eigen::Vector3f(-0.3f, 0, 0), Eigen::Vector3f(-0.2f, 0, 0)}, {}, pose, false);
  EXPECT_EQ(u0.frame_file, "frames/view_001.ply");  // files count views from 1
  EXPECT_EQ(u2.frame_file, "frames/view_003.ply");
  EXPECT_FALSE(u0.normals_from_depth);              // none sent: fitted to the neighbours
  EXPECT_TRUE(u1.new_surface.has_value());
  EXPECT_FALSE(u2.new_surface.has_value()) << "a rejected view is not merged";
  EXPECT_EQ(read_ply((dir_ / "frames/view_003.ply").string()).size(), 2u);
  const PointCloud cloud = read_ply((dir_ / "cloud.ply").string());
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(model.points().size(), 2u);
  bool centroid = false;
  for (const auto& p : cloud) centroid |= std::abs(p.x() - 0.01075f) < 1e-6f;
  EXPECT_TRUE(centroid) << "the two close points become their centroid";
  // New surface: the first view is all new (100 % of an empty model); the second's one point is
  // 0.5 mm from the model, within the 5 mm radius: nothing new.
  EXPECT_EQ(u0.new_surface->new_points, 2);
  EXPECT_EQ(u0.new_surface->percent_of_model(), 100.0);
  EXPECT_EQ(u1.new_surface->new_points, 0);
  EXPECT_EQ(u1.new_surface->model_points, 2);
  EXPECT_EQ(u1.new_surface->radius_m, 0.005);
}

// A wall 0.5 m in front of a 64 x 48 camera (fx = fy = 50 px) looking along the object's -x from
// x = 0.7: the normals sent with it (+x, towards the camera) go into its frame and the merged
// cloud; without normals they are fitted to the neighbours and face the camera all the same. The
// camera pose is in each PLY header; the depth image's file has the camera model beside it.
TEST_F(ScanModelTest, FramesCarryTheirNormalsTheCameraPoseAndTheDepthImage) {
  ScanModel model(dir_, 0.002, 0.005);
  const Pose pose = look_at_z_up(Eigen::Vector3d(0.7, 0, 0), Eigen::Vector3d::Zero());
  const CameraIntrinsics k{64, 48, 50.0, 50.0, 32.0, 24.0};
  PointCloud points;
  for (int v = 2; v < 46; v += 4) {
    for (int u = 2; u < 62; u += 4) points.push_back((pose * back_project(k, u, v, 0.5)).cast<float>());
  }
  const std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f::UnitX());
  const ModelUpdate u0 = model.add_view(0, points, normals, pose, true);
  EXPECT_TRUE(u0.normals_from_depth);
  CloudExtras extras;
  ASSERT_EQ(read_ply((dir_ / "frames/view_001.ply").string(), extras).size(), points.size());
  ASSERT_EQ(extras.normals.size(), points.size());
  for (const auto& n : extras.normals) EXPECT_EQ(n, Eigen::Vector3f::UnitX());
  ASSERT_EQ(extras.camera_poses.size(), 1u);
  EXPECT_TRUE(extras.camera_poses[0].isApprox(pose, 1e-6));
  CloudExtras merged;
  read_ply((dir_ / "cloud.ply").string(), merged);
  ASSERT_FALSE(merged.normals.empty());
  for (const auto& n : merged.normals) EXPECT_NEAR(n.x(), 1.0f, 1e-5f);
  ASSERT_EQ(merged.camera_poses.size(), 1u);

  // No normals sent: fitted to the nearest points, facing the camera.
  const ModelUpdate u1 = model.add_view(1, points, {}, pose, false);
  EXPECT_FALSE(u1.normals_from_depth);
  read_ply((dir_ / "frames/view_002.ply").string(), extras);
  for (const auto& n : extras.normals) EXPECT_NEAR(n.x(), 1.0f, 1e-4f);
  EXPECT_THROW(model.add_view(2, points, {Eigen::Vector3f::UnitX()}, pose, true), std::invalid_argument)
      << "one normal for " << points.size() << " points";

  // The depth image and the camera model beside it.
  const std::vector<float> depth(64 * 48, 0.5f);
  std::vector<std::string> written;
  const std::string file = model.write_depth(0, DepthImage{&depth, k, DepthRange{0.1, 2.0}, 7}, pose, true,
                                             [&](const std::vector<float>& d, int w, int h, int scale,
                                                 const std::string& path) {
                                               EXPECT_EQ(d.size(), static_cast<std::size_t>(w * h));
                                               EXPECT_EQ(scale, 10000);  // 0.1 mm: the range (2 m) fits
                                               written.push_back(path);
                                             });
  EXPECT_EQ(file, "depth/view_001.png");
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0], (dir_ / "depth" / "view_001.png").string());
  const json j = read_json((dir_ / "depth" / "view_001.json").string());
  EXPECT_EQ(j["image"], "view_001.png");
  EXPECT_EQ(j["width"], 64);
  EXPECT_EQ(j["height"], 48);
  EXPECT_EQ(j["fx"], 50.0);
  EXPECT_EQ(j["cy"], 24.0);
  EXPECT_EQ(j["depth_scale"], 10000);
  // Open3D's intrinsic matrix, column-major: fx 0 0 | 0 fy 0 | cx cy 1.
  EXPECT_EQ(j["intrinsic_matrix"], json({50.0, 0.0, 0.0, 0.0, 50.0, 0.0, k.cx, 24.0, 1.0}));
  EXPECT_EQ(j["depth_frame_seq"], 7);
  EXPECT_EQ(j["registered"], true);
  EXPECT_TRUE(pose_from_json(j["object_T_camera"], "object_T_camera").isApprox(pose, 1e-12));
  // The trajectory: one camera, its extrinsic the inverse of the pose (column-major).
  const json t = read_json((dir_ / "trajectory.json").string());
  EXPECT_EQ(t["class_name"], "PinholeCameraTrajectory");
  ASSERT_EQ(t["parameters"].size(), 1u);
  const std::vector<double> e = t["parameters"][0]["extrinsic"].get<std::vector<double>>();
  ASSERT_EQ(e.size(), 16u);
  const Eigen::Matrix4d extrinsic = Eigen::Map<const Eigen::Matrix4d>(e.data());
  EXPECT_TRUE((pose.matrix() * extrinsic).isIdentity(1e-12)) << extrinsic;
  EXPECT_EQ(t["parameters"][0]["intrinsic"]["intrinsic_matrix"], j["intrinsic_matrix"]);
  EXPECT_EQ(t["pbnbv_views"], json({"depth/view_001.json"}));
}

TEST_F(ScanModelTest, ARestartedModelContinuesFromCloudPly) {
  {
    ScanModel model(dir_, 0.002, 0.005);
    model.add_view(0, {Eigen::Vector3f(0.01f, 0, 0), Eigen::Vector3f(0.02f, 0, 0)}, {}, Pose::Identity(), true);
  }
  ScanModel again(dir_, 0.002, 0.005);
  ASSERT_TRUE(again.restore());
  EXPECT_EQ(again.points().size(), 2u);
  EXPECT_EQ(again.normals().size(), 2u);
  EXPECT_EQ(again.camera_poses().size(), 1u);
  // The next view is counted against the restored model: 1 of its 2 points is new.
  const ModelUpdate u = again.add_view(1, {Eigen::Vector3f(0.0205f, 0, 0), Eigen::Vector3f(0.1f, 0, 0)}, {},
                                       Pose::Identity(), true);
  EXPECT_EQ(u.new_surface->model_points, 2);
  EXPECT_EQ(u.new_surface->new_points, 1);
  EXPECT_FALSE(ScanModel(dir_ / "none", 0.002, 0.005).restore()) << "no cloud.ply: nothing to continue";
}

// Two views placed again at once (a view 10 mm along x, another turned 90 degrees about z): their
// frames' points, normals and poses move, the third stays, cloud.ply is the three frames merged
// again; each frame taken back into its camera frame is what the camera saw, moved or not.
TEST_F(ScanModelTest, ViewsPlacedAgainMoveTheirFramesAndTheMergedCloud) {
  ScanModel model(dir_, 0.0, 0.005);
  const Pose camera = look_at_z_up(Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Zero());
  const std::vector<Eigen::Vector3f> up{Eigen::Vector3f(1, 0, 0)};
  model.add_view(0, {Eigen::Vector3f(0.01f, 0, 0)}, up, camera, true);
  model.add_view(1, {Eigen::Vector3f(0.02f, 0, 0)}, up, camera, true);
  model.add_view(2, {Eigen::Vector3f(0.03f, 0, 0)}, up, camera, true);
  Pose shift = Pose::Identity();
  shift.translation() = Eigen::Vector3d(0.01, 0, 0);
  Pose turn = Pose::Identity();
  turn.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  model.move_views({{0, shift}, {2, turn}}, {0, 1, 2});
  CloudExtras e0, e2;
  const PointCloud f0 = read_ply((dir_ / "frames/view_001.ply").string(), e0);
  const PointCloud f2 = read_ply((dir_ / "frames/view_003.ply").string(), e2);
  EXPECT_NEAR(f0[0].x(), 0.02f, 1e-6f);
  EXPECT_NEAR(f2[0].y(), 0.03f, 1e-6f);  // (0.03, 0, 0) turned to (0, 0.03, 0)
  EXPECT_NEAR(e2.normals[0].y(), 1.0f, 1e-6f);
  EXPECT_TRUE(e0.camera_poses[0].isApprox(shift * camera, 1e-9));
  const PointCloud merged = read_ply((dir_ / "cloud.ply").string());
  ASSERT_EQ(merged.size(), 3u);
  EXPECT_EQ(model.points().size(), 3u);
  PointCloud seen;
  std::vector<Eigen::Vector3f> normals;
  for (int v : {0, 1, 2}) {
    model.view_in_camera_frame(v, seen, normals);
    ASSERT_EQ(seen.size(), 1u);
    const Eigen::Vector3d expected = camera.inverse() * Eigen::Vector3d(0.01 * (v + 1), 0, 0);
    EXPECT_NEAR((seen[0].cast<double>() - expected).norm(), 0.0, 1e-6) << "view " << v;
    EXPECT_NEAR((normals[0].cast<double>() - camera.linear().transpose() * Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-6);
  }
  EXPECT_ANY_THROW(model.view_in_camera_frame(7, seen, normals));  // no such frame
}

// What is derived from the merged cloud (the registration service's prepared ICP model and k-d
// tree) is current while the revision stands: a merged view, a view placed again, a restart and a
// new scan each change it; a view kept only in its frame does not; the new surface against a tree
// built beforehand is the same as against the cloud.
TEST_F(ScanModelTest, TheRevisionChangesWithTheMergedCloudOnly) {
  ScanModel model(dir_, 0.0, 0.005);
  const std::uint64_t r0 = model.revision();
  model.add_view(0, {Eigen::Vector3f(0.01f, 0, 0)}, {}, Pose::Identity(), true);
  const std::uint64_t r1 = model.revision();
  EXPECT_NE(r1, r0);
  const NeighbourIndex tree(model.points());
  model.add_view(1, {Eigen::Vector3f(0.5f, 0, 0)}, {}, Pose::Identity(), false);  // not merged
  EXPECT_EQ(model.revision(), r1);
  const ModelUpdate u = model.add_view(2, {Eigen::Vector3f(0.012f, 0, 0), Eigen::Vector3f(0.2f, 0, 0)}, {},
                                       Pose::Identity(), true, {}, &tree);
  EXPECT_EQ(u.new_surface->model_points, 1);
  EXPECT_EQ(u.new_surface->new_points, 1);  // 2 mm from the model: not new; 19 cm: new
  const std::uint64_t r2 = model.revision();
  EXPECT_NE(r2, r1);
  Pose shift = Pose::Identity();
  shift.translation() = Eigen::Vector3d(0.01, 0, 0);
  model.move_views({{0, shift}}, {0, 2});
  EXPECT_NE(model.revision(), r2);
  const std::uint64_t r3 = model.revision();
  model.move_frame(shift);
  EXPECT_NE(model.revision(), r3);
  const std::uint64_t r4 = model.revision();
  ASSERT_TRUE(model.restore());
  EXPECT_NE(model.revision(), r4);
  const std::uint64_t r5 = model.revision();
  model.clear();
  EXPECT_NE(model.revision(), r5);
}

TEST(ScanModel, WithoutAFolderNothingIsWritten) {
  ScanModel model({}, 0.002, 0.005);
  const ModelUpdate u = model.add_view(0, {Eigen::Vector3f(0.01f, 0, 0)}, {}, Pose::Identity(), true);
  EXPECT_TRUE(u.frame_file.empty());
  EXPECT_EQ(model.points().size(), 1u);
  EXPECT_THROW(ScanModel({}, 0.002, 0.0), std::invalid_argument) << "a new-surface radius of 0";
}

}  // namespace
