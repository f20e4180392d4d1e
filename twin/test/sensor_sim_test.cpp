// The named cameras as the twin renders them: the noise measured on a rendered plane at two
// distances against each model's sigma(z) (its datasheet figures, docs/cameras.md); the stereo
// shadow's width against f * b * (1/z_near - 1/z_far); flying pixels only at depth edges; grazing
// readings lost; the ideal camera untouched.
#include "twin/sensor_sim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "twin/test/render_scene.hpp"

namespace pbnbv::twin {
namespace {

// A fronto-parallel plane at depth z (the camera looks along +z).
std::string plane_at(double z) { return plane_box(Eigen::Vector3d(0, 0, z), Eigen::Quaterniond::Identity()); }

DepthImage render(const std::string& world, const DepthSensorModel& m) {
  egl();
  Scene scene(mjcf(world));
  DepthRenderer renderer(scene.model, "depth", m.intrinsics, m.range);
  return renderer.render(scene.data);
}

// Mean and standard deviation of (reading - z) over the central half of the image, and the
// fraction of its pixels with a reading.
struct Scatter {
  double mean_m = 0, sigma_m = 0, valid = 0;
};
Scatter scatter(const DepthImage& img, double z) {
  double sum = 0, sum2 = 0;
  long n = 0, total = 0;
  for (int v = img.height / 4; v < 3 * img.height / 4; ++v) {
    for (int u = img.width / 4; u < 3 * img.width / 4; ++u) {
      ++total;
      const double d = img.at(u, v);
      if (!(d > 0)) continue;
      sum += d - z;
      sum2 += (d - z) * (d - z);
      ++n;
    }
  }
  Scatter s;
  s.mean_m = sum / n;
  s.sigma_m = std::sqrt(sum2 / n - s.mean_m * s.mean_m);
  s.valid = static_cast<double>(n) / total;
  return s;
}

struct PlaneCase {
  CameraKind camera;
  double near_m, far_m;  // two distances inside the camera's range
};

class CameraNoise : public ::testing::TestWithParam<PlaneCase> {};

// Each camera's readings of a plane scatter by its model's sigma(z) at both distances (within
// 10 %), centred on the plane (within a fifth of sigma), nearly all present (only the random
// dropout lost: a plane facing the camera casts no shadow and has no edge or grazing part).
TEST_P(CameraNoise, APlaneScattersAsTheModelSaysAtTwoDistances) {
  const DepthSensorModel& m = depth_sensor_model(GetParam().camera);
  std::mt19937_64 rng(7);
  for (const double z : {GetParam().near_m, GetParam().far_m}) {
    DepthImage img = render(plane_at(z), m);
    ASSERT_NEAR(img.at(m.intrinsics.width / 2, m.intrinsics.height / 2), z, 1e-5);
    simulate_sensor(img, m.intrinsics, m, rng);
    const Scatter s = scatter(img, z);
    const double expected = m.reading_sigma_m(z);
    EXPECT_NEAR(s.sigma_m, expected, 0.1 * expected) << name_of(m.kind) << " at " << z << " m";
    EXPECT_LT(std::abs(s.mean_m), 0.2 * expected) << name_of(m.kind) << " at " << z << " m";
    EXPECT_GT(s.valid, 1.0 - m.dropout - 0.002) << name_of(m.kind) << " at " << z << " m";
  }
}

INSTANTIATE_TEST_SUITE_P(Cameras, CameraNoise,
                         ::testing::Values(PlaneCase{CameraKind::kD405, 0.15, 0.40},
                                           PlaneCase{CameraKind::kD435, 0.40, 1.20},
                                           PlaneCase{CameraKind::kAzureKinectNfov, 0.70, 2.00},
                                           PlaneCase{CameraKind::kStructuredLight, 0.50, 1.00}),
                         [](const auto& info) {
                           std::string n(name_of(info.param.camera));
                           for (char& c : n) c = c == '-' ? '_' : c;
                           return n;
                         });

// Stereo noise grows with the square of the distance: the D435's at 1.2 m is 9 times its at
// 0.4 m (without the rounding to 1 mm, which is most of the scatter at 0.4 m).
TEST(CameraNoise, StereoNoiseGrowsWithTheSquareOfDepth) {
  DepthSensorModel m = depth_sensor_model(CameraKind::kD435);
  m.depth_unit_m = 0;
  std::mt19937_64 rng(11);
  double sigma[2];
  int i = 0;
  for (const double z : {0.4, 1.2}) {
    DepthImage img = render(plane_at(z), m);
    simulate_sensor(img, m.intrinsics, m, rng);
    sigma[i++] = scatter(img, z).sigma_m;
  }
  EXPECT_NEAR(sigma[1] / sigma[0], 9.0, 0.9);
}

// A small plate 0.5 m away before a wall at 1 m: the D435's right imager (50 mm to the right)
// cannot see a band of the wall left of the plate, f b (1/0.5 - 1/1) = 33.7 px wide; right of
// the plate the wall reads.
TEST(CameraShadow, AStereoShadowLiesLeftOfANearObjectAsWideAsTheBaselineMakesIt) {
  const DepthSensorModel& m = depth_sensor_model(CameraKind::kD435);
  const std::string plate = "    <geom type=\"box\" size=\"0.05 0.05 0.005\" pos=\"0 0 0.505\"/>\n";
  DepthImage img = render(plane_at(1.0) + plate, m);
  DepthSensorModel shadows_only = m;  // the shadow alone: no noise, rounding or other loss
  shadows_only.noise_per_m2 = 0;
  shadows_only.depth_unit_m = 0;
  shadows_only.flying_pixels = 0;
  shadows_only.dropout = 0;
  std::mt19937_64 rng(3);
  const SensorSimStats stats = simulate_sensor(img, m.intrinsics, shadows_only, rng);
  const int v = m.intrinsics.height / 2;
  int left_edge = -1, right_edge = -1;  // the plate's columns in the middle row
  for (int u = 0; u < img.width; ++u) {
    if (img.at(u, v) > 0 && img.at(u, v) < 0.75) {
      if (left_edge < 0) left_edge = u;
      right_edge = u;
    }
  }
  ASSERT_GT(left_edge, 0);
  int band = 0;
  for (int u = left_edge - 1; u >= 0 && !(img.at(u, v) > 0); --u) ++band;
  const double expected = m.intrinsics.fx * 0.050 * (1 / 0.5 - 1 / 1.0);
  EXPECT_NEAR(band, expected, 1.5);
  EXPECT_GT(img.at(right_edge + 1, v), 0.99f);  // no shadow on the right
  EXPECT_NEAR(stats.shadowed, expected * (right_edge - left_edge + 1), 0.05 * expected * (right_edge - left_edge + 1));
}

// Time of flight at the same plate: readings between the plate and the wall (flying pixels) lie
// only next to the plate's outline, and about 80 % of the wall's pixels along it are such.
TEST(CameraFlyingPixels, FlyingPixelsLieOnlyAlongDepthEdges) {
  const DepthSensorModel& m = depth_sensor_model(CameraKind::kAzureKinectNfov);
  const std::string plate = "    <geom type=\"box\" size=\"0.1 0.1 0.005\" pos=\"0 0 0.805\"/>\n";
  DepthImage exact = render(plane_at(1.6) + plate, m);
  DepthImage img = exact;
  std::mt19937_64 rng(5);
  const SensorSimStats stats = simulate_sensor(img, m.intrinsics, m, rng);
  int between = 0, away_from_edge = 0, outline = 0;
  for (int v = 1; v + 1 < img.height; ++v) {
    for (int u = 1; u + 1 < img.width; ++u) {
      const float e = exact.at(u, v);
      const bool next_to_plate = e > 1.2f && (exact.at(u - 1, v) < 1.2f || exact.at(u + 1, v) < 1.2f ||
                                               exact.at(u, v - 1) < 1.2f || exact.at(u, v + 1) < 1.2f);
      outline += next_to_plate;
      const float d = img.at(u, v);
      if (d > 0.85f && d < 1.55f) {  // mixes lie in [0.88, 1.52]; the noise is 2.6 mm
        ++between;
        away_from_edge += !next_to_plate;
      }
    }
  }
  EXPECT_EQ(away_from_edge, 0);
  EXPECT_NEAR(between, 0.8 * outline, 0.1 * outline);
  // A few mixes are dropped after, or pushed past 1.55 m by multipath.
  EXPECT_NEAR(between, stats.flying, 0.03 * stats.flying);
}

// The D435 loses a plane seen at 85 degrees (its limit 75): most of it; seen at 30 degrees,
// only the random dropout.
TEST(CameraGrazing, ReadingsAreLostOnGrazingSurfacesOnly) {
  const DepthSensorModel& m = depth_sensor_model(CameraKind::kD435);
  for (const double tilt_deg : {30.0, 85.0}) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(tilt_deg * M_PI / 180, Eigen::Vector3d::UnitY()));
    DepthImage img = render(plane_box(Eigen::Vector3d(0, 0, 0.8), q), m);
    std::mt19937_64 rng(9);
    const SensorSimStats stats = simulate_sensor(img, m.intrinsics, m, rng);
    const double lost = static_cast<double>(stats.grazing) / stats.valid_in;
    if (tilt_deg < 45) {
      EXPECT_EQ(stats.grazing, 0);
    } else {
      // At 85 deg the loss probability is ((85 - 75) / 15)^2 = 0.44 at the centre, more left of it.
      EXPECT_GT(lost, 0.3) << tilt_deg;
    }
  }
}

// The ideal camera reads the exact depth.
TEST(CameraIdeal, TheIdealCameraChangesNothing) {
  const DepthSensorModel& m = depth_sensor_model(CameraKind::kIdeal);
  const std::string sphere = "    <geom type=\"sphere\" size=\"0.1\" pos=\"0 0 0.6\"/>\n";
  const DepthImage exact = render(plane_at(1.0) + sphere, m);
  DepthImage img = exact;
  std::mt19937_64 rng(1);
  const SensorSimStats stats = simulate_sensor(img, m.intrinsics, m, rng);
  EXPECT_EQ(img.depth_m, exact.depth_m);
  EXPECT_EQ(stats.shadowed + stats.flying + stats.grazing + stats.multipath + stats.dropped, 0);
}

// Multipath pushes the inside of a concave corner back and leaves a plane alone.
TEST(CameraMultipath, AConcaveCornerReadsFartherAPlaneDoesNot) {
  const DepthSensorModel& m = depth_sensor_model(CameraKind::kAzureKinectNfov);
  DepthSensorModel multipath_only = m;
  multipath_only.noise_m = multipath_only.noise_per_m = 0;
  multipath_only.depth_unit_m = 0;
  multipath_only.flying_pixels = 0;
  multipath_only.dropout = 0;
  multipath_only.grazing_limit_deg = 90;
  // Two walls meeting at 90 degrees in a vertical line 1.2 m straight ahead, each at 45 degrees
  // to the view: the corner is the farthest point of what the camera sees.
  const Eigen::Quaterniond left(Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond right(Eigen::AngleAxisd(-M_PI / 4, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d corner(0, 0, 1.2);
  const DepthImage exact = render(plane_box(corner, left) + plane_box(corner, right), m);
  DepthImage img = exact;
  std::mt19937_64 rng(2);
  const SensorSimStats stats = simulate_sensor(img, m.intrinsics, multipath_only, rng);
  const int u = m.intrinsics.width / 2, v = m.intrinsics.height / 2;
  EXPECT_GT(img.at(u, v) - exact.at(u, v), 1e-3);  // the corner: pushed back by millimetres
  EXPECT_GT(stats.multipath, 0);
  DepthImage flat = render(plane_at(1.2), m);
  const SensorSimStats flat_stats = simulate_sensor(flat, m.intrinsics, multipath_only, rng);
  EXPECT_EQ(flat_stats.multipath, 0);
}

}  // namespace
}  // namespace pbnbv::twin
