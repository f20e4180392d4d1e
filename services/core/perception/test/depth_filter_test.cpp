// The depth filter against images whose every pixel is known: planes (fronto-parallel and
// steep), a sphere before a wall, a depth edge with mixed pixels, floating specks.
#include "core/perception/depth_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace pbnbv {
namespace {

CameraIntrinsics camera() {
  CameraIntrinsics k;
  k.width = 320;
  k.height = 240;
  k.fx = k.fy = 300;
  k.cx = 160;
  k.cy = 120;
  return k;
}

// Planar depth of the plane through (0, 0, z0) tilted by `tilt_deg` about the camera's y axis.
std::vector<float> plane(const CameraIntrinsics& k, double z0, double tilt_deg) {
  const double t = std::tan(tilt_deg * M_PI / 180);
  std::vector<float> d(static_cast<std::size_t>(k.width) * k.height);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      // z = z0 + t x with x = (u - cx) z / fx  =>  z = z0 / (1 - t (u - cx) / fx)
      const double z = z0 / (1 - t * (u - k.cx) / k.fx);
      d[static_cast<std::size_t>(v) * k.width + u] = z > 0 && z < 5 ? static_cast<float>(z) : 0.0f;
    }
  }
  return d;
}

int valid(const std::vector<float>& d) {
  int n = 0;
  for (const float z : d) n += z > 0;
  return n;
}

// A plane facing the camera and planes tilted by 40 and 55 degrees (seen at up to 55 + 28 = 83
// degrees at the image's edge, under the 88 kept): every reading stays.
TEST(DepthFilter, APlanesReadingsAllStayFacingOrSteep) {
  const CameraIntrinsics k = camera();
  for (const double tilt : {0.0, 40.0, 55.0}) {
    std::vector<float> d = plane(k, 0.6, tilt);
    const int before = valid(d);
    const DepthFilterStats s = filter_depth(d, k);
    EXPECT_EQ(valid(d), before) << tilt;
    EXPECT_EQ(s.flying + s.speckle_pixels, 0) << tilt;
  }
}

// A sphere of 0.1 m at 0.6 m before a wall at 1 m, exact: its silhouette's outermost pixels lie
// at most sqrt(2 R z / f) = 20 mm behind their inner neighbours, less than the 88 degree
// allowance (57 mm): nothing is removed.
TEST(DepthFilter, AnExactSphereBeforeAWallLosesNothing) {
  const CameraIntrinsics k = camera();
  std::vector<float> d = plane(k, 1.0, 0);
  const Eigen::Vector3d c(0, 0, 0.6);
  const double r = 0.1;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1);
      const double a = ray.squaredNorm(), b = ray.dot(c), disc = b * b - a * (c.squaredNorm() - r * r);
      if (disc >= 0) d[static_cast<std::size_t>(v) * k.width + u] = static_cast<float>((b - std::sqrt(disc)) / a);
    }
  }
  const int before = valid(d);
  const DepthFilterStats s = filter_depth(d, k);
  EXPECT_EQ(valid(d), before);
  EXPECT_EQ(s.flying + s.speckle_pixels, 0);
}

// Left half at 0.5 m, right half at 0.9 m, the first column of the right half read as a mix
// (25 % to 75 % of the way back): every mixed reading goes, every reading of the two planes stays.
TEST(DepthFilter, FlyingPixelsOnADepthEdgeGoAndThePlanesStay) {
  const CameraIntrinsics k = camera();
  std::vector<float> d(static_cast<std::size_t>(k.width) * k.height);
  const int edge = k.width / 2;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) d[static_cast<std::size_t>(v) * k.width + u] = u < edge ? 0.5f : 0.9f;
    const double a = 0.25 + 0.5 * (v % 7) / 6.0;
    d[static_cast<std::size_t>(v) * k.width + edge] = static_cast<float>(0.5 + a * 0.4);
  }
  const DepthFilterStats s = filter_depth(d, k);
  for (int v = 1; v + 1 < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const float z = d[static_cast<std::size_t>(v) * k.width + u];
      if (u == edge) {
        EXPECT_EQ(z, 0.0f) << "mixed pixel at row " << v;
      } else {
        EXPECT_GT(z, 0.0f) << u << "," << v;
      }
    }
  }
  EXPECT_EQ(s.flying, k.height - 2);  // the first and last rows have no pixel above or below
}

// A 3 x 3 speck floating at 0.3 m before a wall at 1 m goes; a 6 x 6 patch and a 1-pixel-wide,
// 40-pixel-long wire (real thin things) stay.
TEST(DepthFilter, SpecklesGoRealSmallThingsStay) {
  const CameraIntrinsics k = camera();
  std::vector<float> d = plane(k, 1.0, 0);
  const auto put = [&](int u0, int v0, int w, int h, float z) {
    for (int v = v0; v < v0 + h; ++v)
      for (int u = u0; u < u0 + w; ++u) d[static_cast<std::size_t>(v) * k.width + u] = z;
  };
  put(50, 50, 3, 3, 0.3f);
  put(150, 50, 6, 6, 0.3f);
  put(250, 100, 1, 40, 0.4f);
  const DepthFilterStats s = filter_depth(d, k);
  EXPECT_EQ(s.speckles, 1);
  EXPECT_EQ(s.speckle_pixels, 9);
  EXPECT_EQ(s.flying, 0);
  EXPECT_EQ(d[50 * k.width + 51], 0.0f);
  EXPECT_EQ(d[52 * k.width + 152], 0.3f);
  EXPECT_EQ(d[120 * k.width + 250], 0.4f);
}

TEST(DepthFilter, ASizeThatDisagreesWithTheCameraIsNamed) {
  std::vector<float> d(10, 1.0f);
  EXPECT_THROW(filter_depth(d, camera()), std::invalid_argument);
}

}  // namespace
}  // namespace pbnbv
