// Voxel-grid downsampling against centroids worked out by hand.
#include "core/perception/cloud_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace pbnbv {
namespace {

TEST(VoxelDownsample, GridCentroids) {
  // 10 x 10 x 10 points at (i + 0.5) cm: voxel 2 cm holds i = 2j, 2j + 1, centroid (2j + 1) cm.
  PointCloud c;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      for (int k = 0; k < 10; ++k) {
        c.emplace_back((i + 0.5f) * 0.01f, (j + 0.5f) * 0.01f, (k + 0.5f) * 0.01f);
      }
    }
  }
  std::reverse(c.begin(), c.end());  // output order must not depend on input order
  const PointCloud d = voxel_downsample(c, 0.02);
  ASSERT_EQ(d.size(), 125u);
  for (int a = 0; a < 5; ++a) {
    for (int b = 0; b < 5; ++b) {
      for (int e = 0; e < 5; ++e) {
        const Eigen::Vector3f expected(0.01f + 0.02f * a, 0.01f + 0.02f * b, 0.01f + 0.02f * e);
        const Eigen::Vector3f got = d[static_cast<size_t>(25 * a + 5 * b + e)];
        EXPECT_NEAR((got - expected).norm(), 0.0f, 1e-6f) << a << b << e;
      }
    }
  }
}

TEST(VoxelDownsample, NegativeCoordinatesUseFloor) {
  const PointCloud c = {{-0.005f, 0.005f, 0}, {-0.015f, 0.015f, 0}, {0.005f, 0.005f, 0}};
  const PointCloud d = voxel_downsample(c, 0.02);
  ASSERT_EQ(d.size(), 2u);  // x voxels -1 and 0
  EXPECT_NEAR((d[0] - Eigen::Vector3f(-0.01f, 0.01f, 0)).norm(), 0.0f, 1e-7f);
  EXPECT_NEAR((d[1] - Eigen::Vector3f(0.005f, 0.005f, 0)).norm(), 0.0f, 1e-7f);
}

TEST(VoxelDownsample, NonPositiveVoxelReturnsInput) {
  const PointCloud c = {{1, 2, 3}, {1, 2, 3}, {4, 5, 6}};
  EXPECT_EQ(voxel_downsample(c, 0.0), c);
  EXPECT_EQ(voxel_downsample(c, -1.0), c);
  EXPECT_TRUE(voxel_downsample({}, 0.01).empty());
}

TEST(VoxelDownsample, DropsNonFiniteAndIsDeterministic) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  PointCloud c;
  for (int i = 0; i < 200000; ++i) c.emplace_back(u(rng), u(rng), u(rng));
  c.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0, 0);
  c.emplace_back(0, std::numeric_limits<float>::infinity(), 0);
  const PointCloud a = voxel_downsample(c, 0.1);
  EXPECT_EQ(a.size(), 8000u);  // 20^3 voxels, all occupied
  for (const auto& p : a) EXPECT_TRUE(p.allFinite());
  // Sorted by key: x-voxel non-decreasing.
  for (size_t i = 1; i < a.size(); ++i) {
    EXPECT_LE(std::floor(a[i - 1].x() / 0.1f), std::floor(a[i].x() / 0.1f) + 1e-6f);
  }
  std::shuffle(c.begin(), c.end(), rng);
  const PointCloud b = voxel_downsample(c, 0.1);
  ASSERT_EQ(b.size(), a.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR((a[i] - b[i]).norm(), 0.0f, 1e-6f);
  // Very wide spread (keys don't fit 64 packed bits): the fallback path gives the same answer
  // layout, sorted by x then y then z.
  const PointCloud wide = {{1e15f, 0, 0}, {-1e15f, 1, 0}, {0, -1e15f, 1e15f}, {0, 0, 0}};
  const PointCloud w = voxel_downsample(wide, 1e-3);
  ASSERT_EQ(w.size(), 4u);
  EXPECT_EQ(w[0], wide[1]);
  EXPECT_EQ(w[1], wide[2]);
  EXPECT_EQ(w[2], wide[3]);
  EXPECT_EQ(w[3], wide[0]);
}

}  // namespace
}  // namespace pbnbv
