#pragma once
// Poses, rotations and the camera optical-frame convention used everywhere.
//
// Frames:
//   world   - rig frame: z up; for the arm rig the origin is the turntable axis at the table top.
//   object  - the normalised mesh frame (bounding-box centre at the origin, z up), fixed to the
//             turntable top and turning with it. Every cloud, map and view is expressed here.
//   optical - camera frame: x right, y down, z forward along the optical axis (OpenCV).
#include <Eigen/Geometry>
#include <string>

namespace pbnbv {

// A rigid transform. a_T_b maps points expressed in frame b into frame a.
using Pose = Eigen::Isometry3d;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Optical-frame camera pose at `eye` looking at `target`, image "up" (-y) as close to `up` as
// possible. Throws std::invalid_argument when eye == target or the view direction is parallel
// to `up` (callers pick another up vector for views along it).
Pose look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
             const Eigen::Vector3d& up);

// Like look_at, but falls back to +x as the up hint when the view direction is (anti)parallel
// to +z, so any eye != target gives a pose (top and bottom views).
Pose look_at_z_up(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

// Angle of the rotation taking a to b, in radians, in [0, pi].
double rotation_angle_rad(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

// Pose from a position and a unit quaternion given as w, x, y, z. Throws std::invalid_argument
// naming `what` when a value is not finite or the quaternion norm is off by more than 1e-3.
Pose pose_from_arrays(const double position_m[3], const double quat_wxyz[4],
                      const std::string& what);
// Writes a pose into a position and a unit quaternion (w, x, y, z; w >= 0).
void pose_to_arrays(const Pose& pose, double position_m[3], double quat_wxyz[4]);

// Whether `pose` is a rigid transform: every entry finite, the rotation orthonormal with
// determinant +1 to within `tolerance`, the last row (0, 0, 0, 1).
bool is_rigid(const Pose& pose, double tolerance = 1e-6);

// Wraps an angle into (-pi, pi].
double wrap_angle_rad(double a);
// The angle equal to `a` modulo 2*pi that is nearest to `reference`.
double nearest_equivalent_angle_rad(double a, double reference);

}  // namespace pbnbv
