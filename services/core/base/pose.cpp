#include "core/base/pose.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/base/units.hpp"

namespace pbnbv {

Pose look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
             const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward = target - eye;
  if (!(forward.norm() > 1e-12)) {
    throw std::invalid_argument("look_at: eye and target coincide");
  }
  const Eigen::Vector3d z = forward.normalized();
  Eigen::Vector3d x = z.cross(up);  // image right = forward x up  (y = down)
  if (!(x.norm() > 1e-9)) {
    throw std::invalid_argument("look_at: view direction is parallel to the up vector");
  }
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Pose pose = Pose::Identity();
  pose.linear().col(0) = x;
  pose.linear().col(1) = y;
  pose.linear().col(2) = z;
  pose.translation() = eye;
  return pose;
}

Pose look_at_z_up(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = (target - eye).normalized();
  if (std::abs(forward.z()) > 1.0 - 1e-9) return look_at(eye, target, Eigen::Vector3d::UnitX());
  return look_at(eye, target, Eigen::Vector3d::UnitZ());
}

double rotation_angle_rad(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  // For R = a^T b: sin(angle) = |vee(R - R^T)| / 2 and cos(angle) = (trace R - 1) / 2. atan2 of the
  // two is accurate at every angle, where acos of the cosine alone loses all digits near 0 (a
  // rotation of 1e-8 rad reads as 0 or 1.5e-8).
  const Eigen::Matrix3d r = a.transpose() * b;
  const Eigen::Vector3d v(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  return std::atan2(0.5 * v.norm(), 0.5 * (r.trace() - 1.0));
}

Pose pose_from_arrays(const double position_m[3], const double quat_wxyz[4],
                      const std::string& what) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(position_m[i])) {
      std::ostringstream os;
      os << what << ": position[" << i << "] is not finite (" << position_m[i] << ")";
      throw std::invalid_argument(os.str());
    }
  }
  Eigen::Quaterniond q(quat_wxyz[0], quat_wxyz[1], quat_wxyz[2], quat_wxyz[3]);
  const double n = q.norm();
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-3) {
    std::ostringstream os;
    os << what << ": quaternion (w,x,y,z) = (" << quat_wxyz[0] << ", " << quat_wxyz[1] << ", "
       << quat_wxyz[2] << ", " << quat_wxyz[3] << ") has norm " << n << ", expected 1";
    throw std::invalid_argument(os.str());
  }
  q.normalize();
  Pose pose = Pose::Identity();
  pose.linear() = q.toRotationMatrix();
  pose.translation() = Eigen::Vector3d(position_m[0], position_m[1], position_m[2]);
  return pose;
}

void pose_to_arrays(const Pose& pose, double position_m[3], double quat_wxyz[4]) {
  Eigen::Quaterniond q(pose.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  for (int i = 0; i < 3; ++i) position_m[i] = pose.translation()[i];
  quat_wxyz[0] = q.w();
  quat_wxyz[1] = q.x();
  quat_wxyz[2] = q.y();
  quat_wxyz[3] = q.z();
}

bool is_rigid(const Pose& pose, double tolerance) {
  const Eigen::Matrix4d& m = pose.matrix();
  if (!m.allFinite()) return false;
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > tolerance) return false;
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  return (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tolerance &&
         std::abs(r.determinant() - 1.0) <= tolerance;
}

double wrap_angle_rad(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a <= 0) a += 2.0 * kPi;
  return a - kPi;
}

double nearest_equivalent_angle_rad(double a, double reference) {
  return reference + wrap_angle_rad(a - reference);
}

}  // namespace pbnbv
