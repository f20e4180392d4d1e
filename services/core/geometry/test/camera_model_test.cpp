// The depth camera model: how a frame's uint16 counts decode into metres.
#include "core/geometry/camera_model.hpp"
#include "core/geometry/lens_distortion.hpp"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <cmath>
#include <stdexcept>
#include <string>

using namespace pbnbv;

TEST(CameraModel, DecodesLittleEndianCountsAndRejectsABadFrame) {
  const std::vector<uint8_t> bytes = {0x10, 0x27, 0x00, 0x00, 0xff, 0xff, 0x01, 0x00};  // 10000, 0, 65535, 1
  const std::vector<float> d = decode_depth_u16(bytes, 2, 2, 1e-4);
  EXPECT_FLOAT_EQ(d[0], 1.0f);
  EXPECT_FLOAT_EQ(d[1], 0.0f);
  EXPECT_NEAR(d[2], 6.5535f, 1e-6);
  EXPECT_NEAR(d[3], 1e-4f, 1e-9);
  try {
    decode_depth_u16(bytes, 3, 2, 1e-4);
    FAIL() << "a size mismatch must throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("8 bytes"), std::string::npos) << e.what();
  }
  EXPECT_THROW(decode_depth_u16(bytes, 2, 2, 0.0), std::invalid_argument);
  EXPECT_THROW(decode_depth_u16({}, 0, 0, 1e-4), std::invalid_argument);
}

// ---- lens distortion ----------------------------------------------------------------------

namespace {

// A strong lens (a wide-angle time-of-flight camera's order of magnitude, stronger in k1).
LensDistortion strong_lens() { return LensDistortion{-0.35, 0.15, 0.0012, -0.0018, -0.03}; }

// Planar depth of the plane n.(X - p0) = 0 along pinhole pixel (u, v)'s ray; 0 when behind.
float plane_depth(const CameraIntrinsics& k, double u, double v, const Eigen::Vector3d& p0, const Eigen::Vector3d& n) {
  const Eigen::Vector3d ray((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
  const double t = n.dot(p0) / n.dot(ray);
  return t > 0 ? static_cast<float>(t) : 0.0f;
}

}  // namespace

// Our Brown-Conrady model is OpenCV's: cv::projectPoints with the same coefficients puts every
// point at the same pixel, and undistort_normalised inverts it.
TEST(LensDistortion, DistortsAsOpenCvAndInvertsExactly) {
  const CameraIntrinsics k{640, 480, 500, 500, 321.5, 238.25};
  const LensDistortion d = strong_lens();
  std::vector<cv::Point3d> points;
  for (double x = -0.6; x <= 0.61; x += 0.15) {
    for (double y = -0.45; y <= 0.46; y += 0.15) points.emplace_back(x, y, 1.0);
  }
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const std::array<double, 5> c = d.coefficients();
  std::vector<cv::Point2d> pixels;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, std::vector<double>(c.begin(), c.end()), pixels);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d p(points[i].x, points[i].y);
    const Eigen::Vector2d xd = distort_normalised(d, p);
    EXPECT_NEAR(k.fx * xd.x() + k.cx, pixels[i].x, 1e-9) << p.transpose();
    EXPECT_NEAR(k.fy * xd.y() + k.cy, pixels[i].y, 1e-9) << p.transpose();
    EXPECT_LT((undistort_normalised(d, xd) - p).norm(), 1e-12) << p.transpose();
  }
  EXPECT_EQ(undistort_normalised(LensDistortion{}, Eigen::Vector2d(0.3, -0.2)), Eigen::Vector2d(0.3, -0.2));
}

// A tilted plane seen through the strong lens (pinhole_cover's image resampled by distort_depth,
// as the twin renders it) and undistorted again comes out as the pinhole camera sees it: every
// pixel within 1e-5 relative of the ray-plane depth, so the back-projected points lie on the plane.
// Back-projected as if pinhole, the distorted image is 10s of mm off it.
TEST(LensDistortion, APlaneThroughAStrongLensComesOutFlat) {
  const CameraIntrinsics k{320, 240, 260, 260, 160.5, 119.5};
  const LensDistortion d = strong_lens();
  d.validate(k, "test camera");
  const Eigen::Vector3d p0(0.02, -0.01, 0.8), n = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const CameraIntrinsics big = pinhole_cover(k, d);
  EXPECT_GT(big.width, k.width);  // barrel distortion: the corners see wider than the pinhole
  std::vector<float> pinhole(static_cast<std::size_t>(big.width) * big.height);
  for (int v = 0; v < big.height; ++v) {
    for (int u = 0; u < big.width; ++u) pinhole[static_cast<std::size_t>(v) * big.width + u] = plane_depth(big, u, v, p0, n);
  }
  const std::vector<float> seen = distort_depth(pinhole, big, k, d);
  const std::vector<float> back = undistort_depth(seen, k, d);
  double worst = 0, worst_naive = 0;
  int valid = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * k.width + u;
      ASSERT_GT(seen[i], 0.0f) << "no reading at " << u << ", " << v << " of the distorted image";
      const float want = plane_depth(k, u, v, p0, n);
      if (back[i] > 0) {
        ++valid;
        worst = std::max(worst, static_cast<double>(std::abs(back[i] - want) / want));
      }
      const Eigen::Vector3d naive = back_project(k, u, v, seen[i]);
      worst_naive = std::max(worst_naive, std::abs(n.dot(naive - p0)));
    }
  }
  EXPECT_EQ(valid, k.width * k.height);  // barrel: every pinhole ray lands inside the distorted image
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(worst_naive, 0.01);
  EXPECT_EQ(undistort_depth(seen, k, LensDistortion{}), seen);
}

TEST(LensDistortion, CoefficientsThatAreNoLensAreRefusedByName) {
  const CameraIntrinsics k{640, 480, 500, 500, 320, 240};
  auto why = [&](const LensDistortion& d) {
    try {
      d.validate(k, "rig.xml pbnbv_camera");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(why(strong_lens()), "");
  EXPECT_NE(why(LensDistortion{std::nan(""), 0, 0, 0, 0}).find("rig.xml pbnbv_camera: distortion k1 = nan"), std::string::npos);
  EXPECT_NE(why(LensDistortion{0, 0, 2.0, 0, 0}).find("distortion p1 = 2"), std::string::npos);
  // k1 = -1.2 turns the radius back at r = 0.53, inside this image (corner at r = 0.8).
  EXPECT_NE(why(LensDistortion{-1.2, 0, 0, 0, 0}).find("fold the image over"), std::string::npos);
}
