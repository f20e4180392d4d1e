// Depth frame -> object-frame cloud, against geometry checkable by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "small_camera.hpp"

#include <cmath>

#include "core/perception/cloud_filter.hpp"
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

namespace {

// The full computation merge_into_voxels must equal: the model's points and the new ones
// downsampled, normals and colours averaged into the voxels.
VoxelCloud downsampled_together(const VoxelCloud& model, const PointCloud& points, const std::vector<Eigen::Vector3f>& normals,
                                const std::vector<Rgb>& colours, double voxel_m) {
  PointCloud all = model.points;
  all.insert(all.end(), points.begin(), points.end());
  std::vector<Eigen::Vector3f> all_normals = model.normals;
  all_normals.insert(all_normals.end(), normals.begin(), normals.end());
  VoxelCloud out;
  out.points = voxel_downsample(all, voxel_m);
  out.normals = voxel_normals(all, all_normals, out.points, voxel_m);
  if (!model.colours.empty() || !colours.empty()) {
    std::vector<Rgb> all_colours = model.colours;
    all_colours.resize(model.points.size(), kNoColour);
    if (colours.empty()) {
      all_colours.resize(all.size(), kNoColour);
    } else {
      all_colours.insert(all_colours.end(), colours.begin(), colours.end());
    }
    out.colours = voxel_colours(all, all_colours, out.points, voxel_m);
  }
  return out;
}

bool same_bits(const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return std::memcmp(a.data(), b.data(), sizeof(float) * 3) == 0; }

}  // namespace

TEST(MergeIntoVoxels, AddsToTheVoxelItFallsInAndKeepsTheOthersInVoxelOrder) {
  // 2 mm voxels. The model: one point in voxel (0,0,0) and one in (2,0,0).
  VoxelCloud model;
  model.points = {{0.0005f, 0.0005f, 0.0005f}, {0.0045f, 0.0005f, 0.0005f}};
  model.normals = {{0, 0, 1}, {1, 0, 0}};
  // New: one point in voxel (0,0,0) (their centroid is (1, 1, 1) mm, the normals' mean is along
  // (0, 1, 1)), one in the new voxel (1,0,0), between the two, with no normal.
  const PointCloud added = {{0.0015f, 0.0015f, 0.0015f}, {0.0030f, 0.0010f, 0.0010f}};
  merge_into_voxels(model, added, {{0, 1, 0}, {0, 0, 0}}, {}, 0.002);
  ASSERT_EQ(model.points.size(), 3u);
  EXPECT_NEAR(model.points[0].x(), 0.001f, 1e-9f);
  EXPECT_NEAR(model.points[0].z(), 0.001f, 1e-9f);
  EXPECT_NEAR(model.normals[0].y(), std::sqrt(0.5f), 1e-6f);
  EXPECT_NEAR(model.normals[0].z(), std::sqrt(0.5f), 1e-6f);
  EXPECT_FLOAT_EQ(model.points[1].x(), 0.0030f);  // the new voxel, in order between the others
  EXPECT_TRUE(model.normals[1].isZero());
  EXPECT_FLOAT_EQ(model.points[2].x(), 0.0045f);  // untouched
  EXPECT_EQ(model.normals[2], Eigen::Vector3f(1, 0, 0));
  EXPECT_TRUE(model.colours.empty());
  // The first coloured view: the model's voxels had no colour (kNoColour, 128), the touched one
  // averages it with the new point's 0: 64.
  merge_into_voxels(model, {{0.0011f, 0.0011f, 0.0011f}}, {{0, 0, 1}}, {Rgb{0, 0, 0}}, 0.002);
  ASSERT_EQ(model.colours.size(), 3u);
  EXPECT_EQ(model.colours[0], (Rgb{64, 64, 64}));
  EXPECT_EQ(model.colours[2], kNoColour);
}

TEST(MergeIntoVoxels, GivesBitForBitWhatDownsamplingEverythingAgainGives) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-0.05f, 0.05f), unit(-1.f, 1.f);
  std::uniform_int_distribution<int> byte(0, 255), pick(0, 19);
  for (const double voxel : {0.002, 0.0035}) {
    VoxelCloud model, full;
    for (int view = 0; view < 8; ++view) {
      PointCloud pts;
      std::vector<Eigen::Vector3f> normals;
      std::vector<Rgb> colours;
      const bool coloured = view >= 3 && view != 5;  // colour from the fourth view, none in the sixth
      for (int i = 0; i < 4000; ++i) {
        Eigen::Vector3f p(coord(rng), coord(rng), coord(rng));
        if (pick(rng) == 0) p.x() = static_cast<float>(voxel * std::round(p.x() / voxel));  // on a voxel face
        if (pick(rng) == 1) p.y() = std::numeric_limits<float>::quiet_NaN();              // dropped
        pts.push_back(p);
        normals.push_back(pick(rng) == 2 ? Eigen::Vector3f::Zero() : Eigen::Vector3f(unit(rng), unit(rng), unit(rng)).normalized());
        if (coloured) colours.push_back(Rgb{static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng))});
      }
      full = downsampled_together(full, pts, normals, colours, voxel);
      merge_into_voxels(model, pts, normals, colours, voxel);
      ASSERT_EQ(model.points.size(), full.points.size()) << "view " << view;
      ASSERT_EQ(model.colours.size(), full.colours.size()) << "view " << view;
      for (std::size_t i = 0; i < full.points.size(); ++i) {
        ASSERT_TRUE(same_bits(model.points[i], full.points[i])) << "view " << view << " point " << i;
        ASSERT_TRUE(same_bits(model.normals[i], full.normals[i])) << "view " << view << " point " << i;
        if (!full.colours.empty()) {
          ASSERT_EQ(model.colours[i], full.colours[i]) << "view " << view << " point " << i;
        }
      }
    }
  }
}

TEST(MergeIntoVoxels, AModelOutOfVoxelOrderIsMergedByTheFullComputation) {
  VoxelCloud model;
  model.points = {{0.0045f, 0.0005f, 0.0005f}, {0.0005f, 0.0005f, 0.0005f}};  // (2,0,0) before (0,0,0)
  model.normals = {{1, 0, 0}, {0, 0, 1}};
  merge_into_voxels(model, {{0.0041f, 0.0001f, 0.0001f}}, {{1, 0, 0}}, {}, 0.002);
  ASSERT_EQ(model.points.size(), 2u);
  EXPECT_FLOAT_EQ(model.points[0].x(), 0.0005f);  // sorted
  EXPECT_FLOAT_EQ(model.points[1].x(), 0.0043f);  // (4.5 + 4.1) / 2 mm
}

TEST(MergeIntoVoxels, WithoutAVoxelEveryPointIsKeptWithItsOwnNormal) {
  // voxel_normals too (it used to put every point in one voxel: floor(x / 0) is infinite).
  const PointCloud pts = {{0, 0, 0}, {1, 0, 0}};
  const std::vector<Eigen::Vector3f> own = voxel_normals(pts, {{0, 0, 2}, {0, 3, 0}}, pts, 0.0);
  EXPECT_EQ(own[0], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(own[1], Eigen::Vector3f(0, 1, 0));
  VoxelCloud model;
  model.points = {{0, 0, 0}};
  model.normals = {{0, 0, 1}};
  merge_into_voxels(model, {{0, 0, 0}, {1, 0, 0}}, {{1, 0, 0}, {0, 1, 0}}, {}, 0.0);
  ASSERT_EQ(model.points.size(), 3u);
  EXPECT_EQ(model.normals[0], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(model.normals[1], Eigen::Vector3f(1, 0, 0));
  EXPECT_EQ(model.normals[2], Eigen::Vector3f(0, 1, 0));
}

TEST(MergeIntoVoxels, NormalsOrColoursNotOnePerPointAreRefusedNamingTheCounts) {
  VoxelCloud model;
  try {
    merge_into_voxels(model, {{0, 0, 0}, {1, 0, 0}}, {{0, 0, 1}}, {}, 0.002);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("1 normals and 0 colours for 2 points"), std::string::npos) << e.what();
  }
}
