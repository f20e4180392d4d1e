// Forward kinematics of the rig and joint-space helpers. See rig.hpp (and the chain's formula
// in rig_model.cpp's header comment).
#include <algorithm>
#include <cmath>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/rig/rig_internal.hpp"

namespace pbnbv {

using namespace rig_internal;

namespace {

// ---------------------------------------------------------------------------------------------
// Arm forward kinematics on the base frame, along the chain.

// The motion of a hinge joint in its body frame: rotation by q about the axis through anchor.
Pose joint_motion(const ChainJoint& j, double q) {
  Pose m = Pose::Identity();
  m.linear() = Eigen::AngleAxisd(q, j.axis).toRotationMatrix();
  m.translation() = j.anchor - m.linear() * j.anchor;
  return m;
}

Pose chain_base_T_flange(const RigModel& rig, const Vector6d& q) {
  Pose t = Pose::Identity();
  for (int i = 0; i < 6; ++i) t = t * rig.chain[i].parent_T_body * joint_motion(rig.chain[i], q[i]);
  return t * rig.last_T_flange;
}

Pose free_world_T_flange(const Vector6d& q) {
  Pose p = Pose::Identity();
  p.translation() = q.head<3>();
  p.linear() = rot_z(q[3]) * rot_y(q[4]) * rot_x(q[5]);
  return p;
}

// Rotation angle between a and b, accurate near zero (atan2 of sine and cosine).
double rotation_error(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d r = a.transpose() * b;
  const double s = 0.5 * Eigen::Vector3d(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)).norm();
  const double c = 0.5 * (r.trace() - 1.0);
  return std::atan2(s, c);
}

}  // namespace

namespace rig_internal {

// Flange in the base frame and the geometric Jacobian (rows: linear velocity of the flange
// origin, angular velocity; base frame). Rotation and translation kept apart (no 4x4 products).
Pose chain_fk_jacobian(const RigModel& rig, const Vector6d& q, Matrix6d* jac) {
  Eigen::Vector3d z[6], p[6];
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (int i = 0; i < 6; ++i) {
    const ChainJoint& j = rig.chain[i];
    t += r * j.parent_T_body.translation();
    r = r * j.parent_T_body.linear();
    z[i] = r * j.axis;
    p[i] = t + r * j.anchor;
    // Rotation by q about the axis through the anchor (Rodrigues).
    const double c = std::cos(q[i]), s = std::sin(q[i]);
    const Eigen::Vector3d& a = j.axis;
    Eigen::Matrix3d k;
    k << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    const Eigen::Matrix3d rj = Eigen::Matrix3d::Identity() + s * k + (1 - c) * (k * k);
    t += r * (j.anchor - rj * j.anchor);
    r = r * rj;
  }
  Pose f = Pose::Identity();
  f.translation() = t + r * rig.last_T_flange.translation();
  f.linear() = r * rig.last_T_flange.linear();
  for (int i = 0; i < 6; ++i) {
    jac->block<3, 1>(0, i) = z[i].cross(f.translation() - p[i]);
    jac->block<3, 1>(3, i) = z[i];
  }
  return f;
}

bool within_limits(const RigModel& rig, const Vector6d& q, int* bad_joint) {
  for (int i = 0; i < 6; ++i) {
    if (q[i] < rig.q_lower[i] - kLimitTol || q[i] > rig.q_upper[i] + kLimitTol) {
      if (bad_joint) *bad_joint = i;
      return false;
    }
  }
  return true;
}

// Adds q (and its +-2*pi variants of revolute joints whose range allows them) to `out` when
// within limits; otherwise records the first violation.
void expand_variants(const RigModel& rig, const Vector6d& q, const std::array<bool, 6>& revolute,
                     std::vector<Vector6d>* out, std::string* first_violation) {
  std::vector<Vector6d> cands{q};
  for (int i = 0; i < 6; ++i) {
    if (!revolute[i]) continue;
    std::vector<Vector6d> next;
    for (const Vector6d& c : cands) {
      // All equivalents c[i] + 2*pi*k inside [lower, upper]; keep the wrapped one if none.
      const double base = wrap_angle_rad(c[i]);
      bool any = false;
      for (int k = -2; k <= 2; ++k) {
        const double v = base + 2.0 * kPi * k;
        if (v >= rig.q_lower[i] - kLimitTol && v <= rig.q_upper[i] + kLimitTol) {
          Vector6d n = c;
          n[i] = std::clamp(v, rig.q_lower[i], rig.q_upper[i]);
          next.push_back(n);
          any = true;
        }
      }
      if (!any) {
        Vector6d n = c;
        n[i] = base;
        next.push_back(n);
      }
    }
    cands.swap(next);
  }
  for (const Vector6d& c : cands) {
    int bad = -1;
    if (within_limits(rig, c, &bad)) {
      out->push_back(c);
    } else if (first_violation && first_violation->empty()) {
      *first_violation = rig.joint_names[bad] + " = " + fixed(c[bad]) + " rad (" +
                         fixed(rad_to_deg(c[bad]), 1) + " deg) outside [" + fixed(rig.q_lower[bad]) + ", " +
                         fixed(rig.q_upper[bad]) + "]";
    }
  }
}

// Pose error (position m, rotation rad).
std::pair<double, double> pose_error(const Pose& a, const Pose& b) {
  return {(a.translation() - b.translation()).norm(), rotation_error(a.linear(), b.linear())};
}

// The value of joint i equal to v up to whole turns, within the limits, nearest `reference`
// (v itself when no other turn fits).
double nearest_in_limits(const RigModel& rig, int i, double v, double reference) {
  double best = v;
  for (int k = -2; k <= 2; ++k) {
    const double w = nearest_equivalent_angle_rad(v, reference) + 2.0 * kPi * k;
    if (w < rig.q_lower[i] - kLimitTol || w > rig.q_upper[i] + kLimitTol) continue;
    if (std::abs(w - reference) < std::abs(best - reference)) best = std::clamp(w, rig.q_lower[i], rig.q_upper[i]);
  }
  return best;
}

// Same configuration up to whole turns of each joint.
bool same_modulo_turns(const Vector6d& a, const Vector6d& b) {
  for (int i = 0; i < 6; ++i) {
    if (std::abs(wrap_angle_rad(a[i] - b[i])) > 1e-6) return false;
  }
  return true;
}

}  // namespace rig_internal

Pose flange_in_world(const RigModel& rig, const Vector6d& q) {
  if (rig.kind == RigKind::kFree) return rig.world_T_base * free_world_T_flange(q);
  return rig.world_T_base * chain_base_T_flange(rig, q);
}

Pose camera_in_world(const RigModel& rig, const Vector6d& q) {
  return flange_in_world(rig, q) * rig.flange_T_camera;
}

Pose object_in_world(const RigModel& rig, double turntable_rad, double object_z_m) {
  if (rig.kind == RigKind::kFree || !rig.has_turntable) return Pose::Identity();
  Pose p = rig.world_T_turntable;
  p.linear() = p.linear() * rot_z(turntable_rad - rig.turntable_zero_rad);
  p.translation() += p.linear().col(2) * object_z_m;
  return p;
}

Pose camera_in_object(const RigModel& rig, const Vector6d& q, double turntable_rad,
                      double object_z_m) {
  return object_in_world(rig, turntable_rad, object_z_m).inverse() * camera_in_world(rig, q);
}

}  // namespace pbnbv
