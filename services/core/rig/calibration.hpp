#pragma once
// Hand-eye and turntable calibration from depth alone: a sphere of known radius rests on the
// platter at a known point (the calibration mark: on the platter's +x axis, `offset_m` from the
// turntable axis, touching the platter top); the arm looks at it from many poses and turntable
// angles; its centre is fitted in each frame (fit_sphere_known_radius), and the hand-eye
// transform, the turntable axis and the turntable's zero are solved by least squares
// (solve_rig_calibration) from (joint readings, turntable reading, centre in the camera frame).
// The world frame is the rig file's (the arm base and its kinematics define it): the axis found
// is reported in it; the hand-eye transform and the zero are what a calibrated rig file holds
// (calibrated_rig_xml). Plain functions, no bus.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/base/setting.hpp"
#include "core/rig/rig.hpp"

namespace pbnbv {

// Where the calibration sphere sits: its centre in the object-mount frame (the platter top at
// the turntable's zero, z up the axis) is (offset_m, 0, radius_m).
struct CalibrationSphere {
  double radius_m = 0.05;
  double offset_m = 0.1;
  Eigen::Vector3d centre_in_mount() const { return {offset_m, 0.0, radius_m}; }
};
inline constexpr Setting<double> kSphereRadius{"sphere-radius", 0.05, 0.01, 0.15, "m",
                                               "radius of the calibration sphere"};
inline constexpr Setting<double> kSphereOffset{
    "sphere-offset", 0.1, 0.0, 0.2, "m",
    "distance of the calibration sphere's centre from the turntable axis, on the platter's +x axis (the mark)"};

// A sphere of known radius fitted to points.
struct SphereFit {
  bool ok = false;
  std::string why;                  // why not, when !ok
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int inliers = 0;
  double rms_m = 0;                 // of the inliers' distances to the sphere surface
  double cap_spread = 0;            // 1 - |mean unit normal| of the inliers: 0 = a point, ~0.5 = a hemisphere
};

struct SphereFitOptions {
  double inlier_m = 0.002;          // a point within this of the surface supports a sphere
  int iterations = 400;             // RANSAC samples
  int min_inliers = 300;
  double min_cap_spread = 0.1;      // fewer: the inliers are a small patch (a plane touching a sphere)
  uint64_t seed = 1;
};

// Robust fit of a sphere of radius `radius_m` to points seen from the origin (a camera frame):
// RANSAC on three points (the centre behind the surface, away from the origin), then least
// squares on the inliers. !ok with the reason when too few points support any sphere.
SphereFit fit_sphere_known_radius(const std::vector<Eigen::Vector3d>& points, double radius_m,
                                  const SphereFitOptions& options = {});

// One calibration frame: the readings at exposure and the sphere's centre seen in it.
struct SphereObservation {
  Vector6d q = Vector6d::Zero();    // arm joint readings, rad
  double turntable_rad = 0;         // turntable reading, rad
  Eigen::Vector3d centre_in_camera = Eigen::Vector3d::Zero();  // optical frame, m
};

struct RigCalibration {
  Pose flange_T_camera = Pose::Identity();  // hand-eye transform
  double turntable_zero_rad = 0;            // reading at the platter's zero (RigModel's meaning)
  // The turntable's frame at its zero as found, in the world: world_T_turntable (the model's)
  // times this correction (axis tilt and offset; identity when the model's axis is right).
  Pose turntable_correction = Pose::Identity();
  Eigen::Vector3d axis_direction_world = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d axis_point_world = Eigen::Vector3d::Zero();  // where the axis meets the platter top
  std::vector<double> residual_before_m;    // per observation: the model's prediction to the fit
  std::vector<double> residual_after_m;     // ... with the calibration
  std::vector<bool> used;                   // false: dropped as an outlier
  double rms_before_m = 0, rms_after_m = 0; // over the used observations
  int iterations = 0;
};

struct CalibrationSolveOptions {
  bool fit_axis = true;               // also solve the axis' tilt and offset (else the model's)
  double outlier_factor = 5;          // drop observations above this x the median residual ...
  double outlier_floor_m = 0.002;     // ... and above this
  int max_iterations = 100;
};

// The sphere's centre in the camera frame predicted by `rig` (its hand-eye transform and
// turntable zero) with the turntable frame corrected by `turntable_correction`.
Eigen::Vector3d predicted_sphere_centre(const RigModel& rig, const Pose& turntable_correction,
                                        const Eigen::Vector3d& centre_in_mount, const SphereObservation& o);

// Levenberg-Marquardt from the rig model's values. Throws std::invalid_argument when there are
// fewer observations than the unknowns need (4 with the axis, 3 without).
RigCalibration solve_rig_calibration(const RigModel& rig, const Eigen::Vector3d& centre_in_mount,
                                     const std::vector<SphereObservation>& observations,
                                     const CalibrationSolveOptions& options = {});

// The rig file's MJCF text with the body camera_optical's pose replaced by `flange_T_camera`
// and <custom><numeric name="pbnbv_turntable_zero"> set (the section made when there is none),
// edited as XML: comments, whitespace and every other element written back as they were. Throws
// std::runtime_error naming `path` when the text is not well-formed XML (with the byte and the
// reason), has no <mujoco> root or no camera_optical body.
std::string calibrated_rig_xml(const std::string& xml, const std::string& path, const Pose& flange_T_camera,
                               double turntable_zero_rad);

}  // namespace pbnbv
