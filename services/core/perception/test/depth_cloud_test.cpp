// Depth frame -> object-frame cloud, against geometry checkable by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "small_camera.hpp"

#include <cmath>

#include "core/perception/depth_cloud.hpp"

using namespace pbnbv;

namespace {

using pbnbv::testing::small_camera;

}  // namespace

TEST(DepthCloud, FlatDepthBackProjectsOntoThePlaneInTheObjectFrame) {
  const CameraIntrinsics k = small_camera();
  // Camera 1 m above the object origin looking straight down: depth 1 m everywhere is the
  // plane z = 0 of the object frame.
  const Pose object_T_camera = look_at(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  const std::vector<float> depth(k.width * k.height, 1.0f);
  CloudStats stats;
  const PointCloud cloud = depth_to_object_cloud(depth, k, DepthRange{0.1, 3.0}, object_T_camera, CloudCrop{}, 0.0, &stats);
  ASSERT_EQ(cloud.size(), static_cast<std::size_t>(k.width * k.height));
  EXPECT_EQ(stats.num_valid_pixels, k.width * k.height);
  EXPECT_EQ(stats.num_cropped, 0);
  for (const auto& p : cloud) EXPECT_NEAR(p.z(), 0.0, 1e-6);
  // The footprint: pixel u spans x = (u - cx) / fx * 1 m, so the cloud's extent is
  // (width - 1) / fx by (height - 1) / fy.
  Eigen::Vector3f lo = cloud[0], hi = cloud[0];
  for (const auto& p : cloud) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  EXPECT_NEAR(hi.x() - lo.x() + hi.y() - lo.y(), (63 + 47) / 50.0, 1e-5);
}

TEST(DepthCloud, InvalidOutOfRangeAndNonFinitePixelsAreSkipped) {
  const CameraIntrinsics k = small_camera();
  std::vector<float> depth(k.width * k.height, 1.0f);
  depth[0] = 0.0f;                 // no return
  depth[1] = std::nanf("");        // NaN
  depth[2] = 0.05f;                // nearer than the range
  depth[3] = 5.0f;                 // farther than the range
  depth[4] = INFINITY;
  CloudStats stats;
  const PointCloud cloud = depth_to_object_cloud(depth, k, DepthRange{0.1, 3.0}, Pose::Identity(), CloudCrop{}, 0.0, &stats);
  EXPECT_EQ(stats.num_valid_pixels, k.width * k.height - 5);
  EXPECT_EQ(cloud.size(), static_cast<std::size_t>(k.width * k.height - 5));
}

TEST(DepthCloud, AllNanFrameGivesAnEmptyCloud) {
  const CameraIntrinsics k = small_camera();
  const std::vector<float> depth(k.width * k.height, std::nanf(""));
  CloudStats stats;
  const PointCloud cloud = depth_to_object_cloud(depth, k, DepthRange{}, Pose::Identity(), CloudCrop{}, 0.002, &stats);
  EXPECT_TRUE(cloud.empty());
  EXPECT_EQ(stats.num_valid_pixels, 0);
}

// The turntable top 2 mm higher than the kinematics say (a rig error), tilted 0.5 degrees, its
// readings scattered by 1 mm (a noisy camera), and a plate 20 mm above it: the plane found lies
// 2 mm up with a sigma of 1 mm, every reading of the top is dropped (4 mm clearance + 3 sigma
// above the plane found) and every reading of the plate is kept.
TEST(DepthCloud, TheTurntableTopIsFoundInTheFrameAndDroppedWithItsNoise) {
  const CameraIntrinsics k = small_camera();
  const Pose object_T_camera = look_at(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  std::mt19937_64 rng(4);
  std::normal_distribution<double> noise(0.0, 0.001);
  const double slope = std::tan(0.5 * M_PI / 180);
  std::vector<float> depth(static_cast<std::size_t>(k.width) * k.height);
  int plate = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      // The camera looks down -z from z = 1 with its x along the object's x: depth 1 - z at the
      // ray's (x, y) (the slope is small enough to take x at the unit plane's).
      const Eigen::Vector3d ray = object_T_camera.linear() * back_project(k, u, v, 1.0);
      const bool on_plate = std::abs(ray.x()) < 0.05 && std::abs(ray.y()) < 0.05;
      plate += on_plate;
      const double z = on_plate ? 0.020 : 0.002 + slope * ray.x() + noise(rng);
      depth[static_cast<std::size_t>(v) * k.width + u] = static_cast<float>(1.0 - z);
    }
  }
  CloudCrop crop;
  crop.ground_z_m = 0.0;
  crop.ground_clearance_m = 0.004;
  CloudStats stats;
  const PointCloud kept = depth_to_object_cloud(depth, k, DepthRange{}, object_T_camera, crop, 0.0, &stats);
  EXPECT_NEAR(stats.ground_offset_m, 0.002, 2e-4);
  EXPECT_NEAR(stats.ground_sigma_m, 0.001, 1e-4);
  EXPECT_EQ(static_cast<int>(kept.size()), plate);
  for (const auto& p : kept) EXPECT_NEAR(p.z(), 0.020, 1e-5);
  // Without the fit, the fixed 4 mm clearance keeps the top's readings that noise lifts above it.
  crop.fit_ground = false;
  EXPECT_GT(depth_to_object_cloud(depth, k, DepthRange{}, object_T_camera, crop, 0.0, &stats).size(),
            static_cast<std::size_t>(plate) + 10);
}

TEST(DepthCloud, CropRemovesTheGroundAndPointsOutsideTheWorkingVolume) {
  const CameraIntrinsics k = small_camera();
  // Looking down from 1 m at the plane z = 0; the ground is declared at z = 0 with 4 mm
  // clearance: everything is cropped. Lower the ground to -0.1: nothing is.
  const Pose object_T_camera = look_at(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX());
  const std::vector<float> depth(k.width * k.height, 1.0f);
  CloudCrop crop;
  crop.ground_z_m = 0.0;
  crop.ground_clearance_m = 0.004;
  CloudStats stats;
  EXPECT_TRUE(depth_to_object_cloud(depth, k, DepthRange{}, object_T_camera, crop, 0.0, &stats).empty());
  EXPECT_EQ(stats.num_cropped, k.width * k.height);
  crop.ground_z_m = -0.1;
  EXPECT_EQ(depth_to_object_cloud(depth, k, DepthRange{}, object_T_camera, crop, 0.0, &stats).size(),
            static_cast<std::size_t>(k.width * k.height));
  // A working volume |x| <= 0.1 keeps the pixel columns with |u - cx| / fx <= 0.1.
  crop.volume_m = Eigen::AlignedBox3d(Eigen::Vector3d(-0.1, -1, -1), Eigen::Vector3d(0.1, 1, 1));
  const PointCloud kept = depth_to_object_cloud(depth, k, DepthRange{}, object_T_camera, crop, 0.0, &stats);
  for (const auto& p : kept) EXPECT_LE(std::abs(p.x()), 0.1 + 1e-6);
  EXPECT_EQ(static_cast<int>(kept.size()) + stats.num_cropped, k.width * k.height);
  EXPECT_GT(kept.size(), 0u);
}
