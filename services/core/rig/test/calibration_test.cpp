// Hand-eye and turntable calibration: sphere fits to points sampled on a sphere (with a plane
// and clutter around it), and the least-squares solve on sphere centres computed from a known
// "true" rig: exact data recover the truth to 1e-6, noisy data within the calibration's targets.
#include "core/rig/calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/base/units.hpp"
#include "file_test_util.hpp"

namespace pbnbv {
namespace {

using testing::file_text;

constexpr double kDeg = kPi / 180;

// The visible side of a sphere seen from the origin (points facing the origin), a plane `gap_m`
// below it (the camera looks along +z, image y down) and uniformly scattered clutter.
std::vector<Eigen::Vector3d> scene(const Eigen::Vector3d& centre, double r, double sigma, int clutter, uint64_t seed,
                                   double gap_m = 0.01) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> pts;
  while (pts.size() < 5000) {
    const Eigen::Vector3d d = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const Eigen::Vector3d p = centre + r * d;
    if (d.dot(-p.normalized()) <= 0.05) continue;  // facing away from the camera
    pts.push_back(p + sigma * Eigen::Vector3d(n(rng), n(rng), n(rng)));
  }
  // A plane under the sphere (normal towards the camera's -y), 5000 points.
  for (int i = 0; i < 5000; ++i) {
    pts.emplace_back(0.3 * u(rng), centre.y() + r + gap_m, centre.z() + 0.3 * u(rng));
  }
  for (int i = 0; i < clutter; ++i) pts.emplace_back(0.4 * u(rng), 0.4 * u(rng), 0.5 + 0.3 * u(rng));
  return pts;
}

TEST(SphereFit, ExactPointsGiveTheCentre) {
  const Eigen::Vector3d c(0.03, -0.02, 0.55);
  const SphereFit f = fit_sphere_known_radius(scene(c, 0.05, 0, 2000, 1), 0.05);
  ASSERT_TRUE(f.ok) << f.why;
  EXPECT_LT((f.centre - c).norm(), 1e-9);
  EXPECT_GE(f.inliers, 5000);
  EXPECT_GT(f.cap_spread, 0.2);  // the visible side of a sphere, not a patch
}

TEST(SphereFit, APlaneTouchingTheSphereBiasesTheCentreByLessThanAMicrometre) {
  // The plane the sphere rests on, uncropped: its points next to the contact lie within the
  // inlier band (pbnbv calibrate crops them: 10 mm above the platter).
  const Eigen::Vector3d c(0.03, -0.02, 0.55);
  const SphereFit f = fit_sphere_known_radius(scene(c, 0.05, 0, 0, 1, 0.0), 0.05);
  ASSERT_TRUE(f.ok) << f.why;
  EXPECT_LT((f.centre - c).norm(), 1e-5);
}

TEST(SphereFit, NoisyPointsGiveTheCentreWithinATenthOfAMillimetre) {
  const Eigen::Vector3d c(-0.08, 0.05, 0.7);
  const SphereFit f = fit_sphere_known_radius(scene(c, 0.04, 0.0005, 3000, 2), 0.04);
  ASSERT_TRUE(f.ok) << f.why;
  EXPECT_LT((f.centre - c).norm(), 1e-4);
  EXPECT_NEAR(f.rms_m, 0.0005, 0.0002);
}

TEST(SphereFit, APlaneAloneIsNoSphere) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Eigen::Vector3d> plane;
  for (int i = 0; i < 20000; ++i) plane.emplace_back(u(rng), 0.1, 0.6 + u(rng));
  const SphereFit f = fit_sphere_known_radius(plane, 0.05);
  EXPECT_FALSE(f.ok);
  EXPECT_FALSE(f.why.empty());
}

TEST(SphereFit, TooFewPointsAreRefusedWithTheCount) {
  const SphereFit f = fit_sphere_known_radius({Eigen::Vector3d(0, 0, 1)}, 0.05);
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.why.find("1 points"), std::string::npos) << f.why;
}

class Calibration : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = load_rig(default_rig_path(RigKind::kArm));
    truth_ = model_;
    // 5 mm / 1 deg hand-eye error, 0.5 deg zero; the axis tilted 0.2 deg and 1 mm off.
    Pose err = Pose::Identity();
    err.translation() = Eigen::Vector3d(3, -3, 2.6457513).normalized() * 0.005;
    err.linear() = Eigen::AngleAxisd(1 * kDeg, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
    truth_.flange_T_camera = model_.flange_T_camera * err;
    truth_.turntable_zero_rad = 0.5 * kDeg;
    axis_ = Pose::Identity();
    axis_.linear() = Eigen::AngleAxisd(0.2 * kDeg, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
    axis_.translation() = Eigen::Vector3d(0.001, -0.0005, 0.0003);
  }

  // Frames from poses around home with varied turntable angles: the centre through the truth.
  std::vector<SphereObservation> observations(int n, double sigma_m, uint64_t seed) const {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    std::normal_distribution<double> g(0, 1);
    std::vector<SphereObservation> obs;
    for (int i = 0; i < n; ++i) {
      SphereObservation o;
      for (int j = 0; j < 6; ++j) o.q[j] = model_.q_home[j] + 0.3 * u(rng);
      o.turntable_rad = 2 * kPi * i / n;
      o.centre_in_camera = predicted_sphere_centre(truth_, axis_, sphere_.centre_in_mount(), o) +
                           sigma_m * Eigen::Vector3d(g(rng), g(rng), g(rng));
      obs.push_back(o);
    }
    return obs;
  }

  RigModel model_, truth_;
  Pose axis_;
  CalibrationSphere sphere_;
};

TEST_F(Calibration, ExactCentresRecoverTheTrueRig) {
  const RigCalibration c = solve_rig_calibration(model_, sphere_.centre_in_mount(), observations(20, 0, 1));
  EXPECT_LT((c.flange_T_camera.translation() - truth_.flange_T_camera.translation()).norm(), 1e-6);
  EXPECT_LT(rotation_angle_rad(c.flange_T_camera.linear(), truth_.flange_T_camera.linear()), 1e-6);
  EXPECT_NEAR(c.turntable_zero_rad, truth_.turntable_zero_rad, 1e-6);
  EXPECT_LT((c.axis_direction_world - axis_.linear().col(2)).norm(), 1e-6);
  EXPECT_LT((c.axis_point_world - (model_.world_T_turntable * axis_).translation()).norm(), 1e-6);
  EXPECT_LT(c.rms_after_m, 1e-8);
  // Before: the 5 mm / 1 deg mount error and the 0.5 deg zero (1 mm at the sphere) show.
  EXPECT_GT(c.rms_before_m, 0.004);
}

TEST_F(Calibration, WithoutTheAxisTheModelsAxisIsKept) {
  axis_ = Pose::Identity();
  CalibrationSolveOptions o;
  o.fit_axis = false;
  const RigCalibration c = solve_rig_calibration(model_, sphere_.centre_in_mount(), observations(12, 0, 2), o);
  EXPECT_LT((c.flange_T_camera.translation() - truth_.flange_T_camera.translation()).norm(), 1e-6);
  EXPECT_NEAR(c.turntable_zero_rad, truth_.turntable_zero_rad, 1e-6);
  EXPECT_TRUE(c.turntable_correction.isApprox(Pose::Identity()));
}

TEST_F(Calibration, NoisyCentresAndAWrongFrameStayWithinTheTargets) {
  // 0.1 mm noise on every centre (a sphere fit's), and one frame's centre 30 mm off.
  std::vector<SphereObservation> obs = observations(30, 1e-4, 3);
  obs[7].centre_in_camera.x() += 0.03;
  const RigCalibration c = solve_rig_calibration(model_, sphere_.centre_in_mount(), obs);
  EXPECT_FALSE(c.used[7]);
  EXPECT_EQ(std::count(c.used.begin(), c.used.end(), false), 1);
  EXPECT_LT((c.flange_T_camera.translation() - truth_.flange_T_camera.translation()).norm(), 0.5e-3);
  EXPECT_LT(rotation_angle_rad(c.flange_T_camera.linear(), truth_.flange_T_camera.linear()), 0.05 * kDeg);
  EXPECT_NEAR(c.turntable_zero_rad, truth_.turntable_zero_rad, 0.05 * kDeg);
  EXPECT_NEAR(c.rms_after_m, std::sqrt(3.0) * 1e-4, 0.5e-4);  // the noise, nothing more
}

TEST_F(Calibration, TooFewFramesAreRefused) {
  EXPECT_THROW(solve_rig_calibration(model_, sphere_.centre_in_mount(), observations(3, 0, 4)), std::invalid_argument);
}

// Every shipped arm rig file (the UR5e's header comment names a <custom> section: the file must
// be edited as XML, not as text) calibrates into a file MuJoCo loads, with the new mount and zero,
// everything else as it was: the comments byte for byte, the other bodies' poses.
TEST_F(Calibration, EveryShippedRigFileLoadsWithTheNewMountAndZero) {
  for (const std::string file : {"rig_arm.xml", "rig_ur5e.xml"}) {
    const std::string source = std::filesystem::path(default_rig_path(RigKind::kArm)).parent_path() / file;
    const RigModel before = load_rig(source);
    const std::string text = file_text(source);
    const std::string xml = calibrated_rig_xml(text, source, truth_.flange_T_camera, 0.01);
    // The header comment, up to <mujoco, is untouched.
    const auto head = text.find("<mujoco");
    ASSERT_NE(head, std::string::npos) << file;
    EXPECT_EQ(xml.substr(0, xml.find("<mujoco")), text.substr(0, head)) << file;
    // Next to the original (its includes and meshes resolve the same way).
    const std::string path = source + ".calibrated-" + std::to_string(::getpid()) + ".xml";
    std::ofstream(path) << xml;
    RigModel r;
    ASSERT_NO_THROW(r = load_rig(path)) << file << ":\n" << xml.substr(0, 2000);
    std::filesystem::remove(path);
    EXPECT_LT((r.flange_T_camera.translation() - truth_.flange_T_camera.translation()).norm(), 1e-12) << file;
    EXPECT_LT(rotation_angle_rad(r.flange_T_camera.linear(), truth_.flange_T_camera.linear()), 1e-9) << file;
    EXPECT_DOUBLE_EQ(r.turntable_zero_rad, 0.01) << file;
    EXPECT_TRUE(r.world_T_turntable.isApprox(before.world_T_turntable, 1e-12)) << file;
    EXPECT_EQ(r.joint_names, before.joint_names) << file;
    // A reading equal to the zero puts the platter at its zero; the object turns with the rest.
    EXPECT_TRUE(object_in_world(r, 0.01, 0).isApprox(before.world_T_turntable, 1e-12)) << file;
    EXPECT_TRUE(object_in_world(r, 0.01 + 0.3, 0).isApprox(object_in_world(before, 0.3, 0), 1e-12)) << file;
    // Calibrating a calibrated file replaces the zero, never adds a second one.
    const std::string again = calibrated_rig_xml(xml, path, truth_.flange_T_camera, 0.02);
    EXPECT_EQ(again.find("name=\"pbnbv_turntable_zero\""), again.rfind("name=\"pbnbv_turntable_zero\"")) << file;
    EXPECT_NE(again.find("data=\"0.02\""), std::string::npos) << file;
  }
}

// Elements named in comments are left alone; a file with no <custom> section gets one; a file that
// is not XML, or has no camera body, is refused with its name and the reason.
TEST(CalibratedRigXml, CommentsAreNotElementsAndBrokenFilesAreNamed) {
  const std::string xml =
      "<!-- <custom> and <body name=\"camera_optical\" pos=\"9 9 9\"> in a comment -->\n"
      "<mujoco>\n  <worldbody>\n    <body name=\"camera_optical\" pos=\"1 2 3\" euler=\"0 0 1\"/>\n  </worldbody>\n"
      "</mujoco>\n";
  const std::string out = calibrated_rig_xml(xml, "mine.xml", Pose::Identity(), 0.5);
  EXPECT_EQ(out.substr(0, out.find("<mujoco")), xml.substr(0, xml.find("<mujoco")));
  EXPECT_NE(out.find("<body name=\"camera_optical\" pos=\"0 0 0\" quat=\"1 0 0 0\"/>"), std::string::npos) << out;
  EXPECT_EQ(out.find("euler"), std::string::npos) << out;
  EXPECT_NE(out.find("<custom>"), out.rfind("<custom>")) << out;  // the comment's and the new section's
  EXPECT_NE(out.find("<numeric name=\"pbnbv_turntable_zero\" data=\"0.5\"/>"), std::string::npos) << out;
  try {
    calibrated_rig_xml("<mujoco><worldbody></mujoco>", "broken.xml", Pose::Identity(), 0.0);
    ADD_FAILURE() << "a file that is not well-formed was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.xml: not well-formed XML"), std::string::npos) << e.what();
  }
  try {
    calibrated_rig_xml("<mujoco><worldbody/></mujoco>", "nocam.xml", Pose::Identity(), 0.0);
    ADD_FAILURE() << "a file without a camera body was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nocam.xml: no <body name=\"camera_optical\">"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pbnbv
