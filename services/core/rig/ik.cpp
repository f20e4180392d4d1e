// Inverse kinematics: the analytic solution of the spherical-wrist layout, the free rig's, and
// the choice between them, the parallel-axes one (parallel_ik.cpp) and the general IK
// (general_ik.cpp). See rig.hpp.
#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/rig/rig_internal.hpp"

namespace pbnbv {

using namespace rig_internal;

namespace {

// Damped least-squares polish of an arm solution (numerical Jacobian); rarely needed.
Vector6d polish_arm(const RigModel& rig, const Pose& target, Vector6d q) {
  for (int it = 0; it < 5; ++it) {
    const Pose cur = flange_in_world(rig, q);
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = target.translation() - cur.translation();
    const Eigen::AngleAxisd aa(target.linear() * cur.linear().transpose());
    e.tail<3>() = aa.angle() * aa.axis();
    if (e.norm() < 1e-13) break;
    Eigen::Matrix<double, 6, 6> jac;
    const double h = 1e-7;
    for (int j = 0; j < 6; ++j) {
      Vector6d qh = q;
      qh[j] += h;
      const Pose ph = flange_in_world(rig, qh);
      jac.block<3, 1>(0, j) = (ph.translation() - cur.translation()) / h;
      const Eigen::AngleAxisd da(ph.linear() * cur.linear().transpose());
      jac.block<3, 1>(3, j) = da.angle() * da.axis() / h;
    }
    const double lambda = 1e-6;
    const Eigen::Matrix<double, 6, 6> a =
        jac.transpose() * jac + lambda * Eigen::Matrix<double, 6, 6>::Identity();
    q += a.ldlt().solve(jac.transpose() * e);
  }
  return q;
}

}  // namespace

namespace rig_internal {

std::optional<Vector6d> verified_arm_solution(const RigModel& rig, const Pose& world_T_flange, const Vector6d& raw) {
  Vector6d q = raw;
  for (int i = 0; i < 6; ++i) q[i] = wrap_angle_rad(q[i]);
  auto [ep, er] = pose_error(flange_in_world(rig, q), world_T_flange);
  if (ep > 1e-10 || er > 1e-10) {
    q = polish_arm(rig, world_T_flange, q);
    std::tie(ep, er) = pose_error(flange_in_world(rig, q), world_T_flange);
  }
  if (ep > kVerifyPosTol || er > kVerifyRotTol) return std::nullopt;
  return q;
}

std::vector<Vector6d> checked_arm_solutions(const RigModel& rig, const Pose& world_T_flange, const std::vector<Vector6d>& raw,
                                            std::string* why_none) {
  const std::array<bool, 6> revolute{true, true, true, true, true, true};
  std::vector<Vector6d> sols;
  std::string violation;
  for (const Vector6d& q : raw) {
    if (const auto v = verified_arm_solution(rig, world_T_flange, q)) expand_variants(rig, *v, revolute, &sols, &violation);
  }
  // Remove duplicates (singular cases can produce the same configuration twice).
  std::vector<Vector6d> uniq;
  for (const Vector6d& q : sols) {
    bool dup = false;
    for (const Vector6d& u : uniq) dup = dup || (q - u).cwiseAbs().maxCoeff() < 1e-9;
    if (!dup) uniq.push_back(q);
  }
  if (uniq.empty() && why_none) {
    *why_none = "all " + std::to_string(raw.size()) + " solutions violate joint limits" +
                (violation.empty() ? std::string() : " (e.g. " + violation + ")");
  }
  return uniq;
}

// Arm IK; q_ref resolves the free angles at singularities (wrist centre on the A1 axis, q5 = 0).
std::vector<Vector6d> arm_ik(const RigModel& rig, const Pose& world_T_flange,
                             const Vector6d& q_ref, std::string* why_none) {
  const ArmGeometry& g = rig.arm;
  const Pose t = rig.world_T_base.inverse() * world_T_flange;
  const Eigen::Matrix3d r06 = t.linear();
  const Eigen::Vector3d wc = t.translation() - g.d6 * r06.col(0);
  const double big_l = std::hypot(g.d4, g.a3);
  const double phi = std::atan2(g.a3, g.d4);

  std::vector<double> q1s;
  if (std::hypot(wc.x(), wc.y()) < 1e-12) {
    q1s = {q_ref[0], q_ref[0] + kPi};  // shoulder singularity: any q1 works
  } else {
    const double q1 = std::atan2(wc.y(), wc.x());
    q1s = {q1, q1 + kPi};
  }

  std::vector<Vector6d> raw;
  double reach_dist = -1;
  bool any_reach = false;
  for (double q1 : q1s) {
    q1 = wrap_angle_rad(q1);
    const double r = std::cos(q1) * wc.x() + std::sin(q1) * wc.y() - g.a1;
    const double s = wc.z() - g.d1;
    const double dist2 = r * r + s * s;
    if (reach_dist < 0) reach_dist = std::sqrt(dist2);
    double k = (dist2 - g.a2 * g.a2 - big_l * big_l) / (2.0 * g.a2 * big_l);
    if (std::abs(k) > 1.0 + 1e-12) continue;
    any_reach = true;
    k = std::clamp(k, -1.0, 1.0);
    const double ac = std::acos(k);
    const double beta = std::atan2(s, r);
    for (double sign : {1.0, -1.0}) {
      const double delta = sign * ac;  // = phi - q3
      const double q3 = phi - delta;
      const double gamma = std::atan2(big_l * std::sin(delta), g.a2 + big_l * std::cos(delta));
      const double q2 = wrap_angle_rad(gamma - beta);
      const Eigen::Matrix3d r03 = rot_z(q1) * rot_y(q2 + q3);
      const Eigen::Matrix3d m = r03.transpose() * r06;  // = Rx(q4) Ry(q5) Rx(q6)
      const double sb = std::hypot(m(1, 0), m(2, 0));
      const double q5 = std::atan2(sb, m(0, 0));
      if (sb < 1e-10) {
        // Wrist singular (q5 = 0 or pi): only q4 +- q6 is defined; keep q4 at the reference.
        const double q4 = q_ref[3];
        Vector6d q;
        if (m(0, 0) > 0) {  // m = Rx(q4 + q6)
          q << q1, q2, q3, q4, 0.0, std::atan2(m(2, 1), m(1, 1)) - q4;
        } else {  // m = Ry(pi) Rx(q6 - q4)
          const Eigen::Matrix3d n = rot_y(kPi).transpose() * m;
          q << q1, q2, q3, q4, kPi, std::atan2(n(2, 1), n(1, 1)) + q4;
        }
        raw.push_back(q);
        continue;
      }
      const double q4 = std::atan2(m(1, 0), -m(2, 0));
      const double q6 = std::atan2(m(0, 1), m(0, 2));
      Vector6d qa, qb;
      qa << q1, q2, q3, q4, q5, q6;
      qb << q1, q2, q3, q4 + kPi, -q5, q6 + kPi;
      raw.push_back(qa);
      raw.push_back(qb);
    }
  }

  if (!any_reach) {
    if (why_none) {
      const double max_reach = g.a2 + big_l;
      const double min_reach = std::abs(g.a2 - big_l);
      *why_none = "out of reach: wrist centre is " + fixed(reach_dist, 3) +
                  " m from the shoulder (A2 axis), reach is " +
                  (reach_dist > max_reach ? fixed(max_reach, 3) + " m"
                                          : "at least " + fixed(min_reach, 3) + " m");
    }
    return {};
  }

  return checked_arm_solutions(rig, world_T_flange, raw, why_none);
}

// Free-rig IK: slides = position, ZYX Euler angles of the flange rotation.
std::vector<Vector6d> free_ik(const RigModel& rig, const Pose& world_T_flange,
                              const Vector6d& q_ref, std::string* why_none) {
  const Eigen::Matrix3d r = world_T_flange.linear();
  const Eigen::Vector3d p = world_T_flange.translation();
  std::vector<Vector6d> raw;
  const double cp = std::hypot(r(0, 0), r(1, 0));
  if (cp < 1e-9) {
    // Gimbal lock (tool axis vertical, pitch = +-pi/2): only yaw -+ roll is defined; keep yaw
    // at the reference and solve roll.
    const double pitch = r(2, 0) < 0 ? kPi / 2 : -kPi / 2;
    const double yaw = q_ref[3];
    // R = Rz(yaw) Ry(pitch) Rx(roll); Rz(yaw)^T R = Ry(pitch) Rx(roll).
    const Eigen::Matrix3d n = rot_y(pitch).transpose() * rot_z(yaw).transpose() * r;  // Rx(roll)
    const double roll = std::atan2(n(2, 1), n(1, 1));
    Vector6d q;
    q << p, yaw, pitch, roll;
    raw.push_back(q);
  } else {
    const double pitch = std::atan2(-r(2, 0), cp);
    const double yaw = std::atan2(r(1, 0), r(0, 0));
    const double roll = std::atan2(r(2, 1), r(2, 2));
    Vector6d q;
    q << p, yaw, pitch, roll;
    raw.push_back(q);
    // The second ZYX solution (pitch' = pi - pitch) is outside a +-pi/2 pitch range, but keep
    // it for rigs with wider ranges.
    Vector6d q2;
    q2 << p, yaw + kPi, kPi - pitch, roll + kPi;
    q2[4] = wrap_angle_rad(q2[4]);
    raw.push_back(q2);
  }
  const std::array<bool, 6> revolute{false, false, false, true, true, true};
  std::vector<Vector6d> sols;
  std::string violation;
  for (const Vector6d& q : raw) {
    Vector6d qq = q;
    const auto [ep, er] = pose_error(flange_in_world(rig, qq), world_T_flange);
    if (ep > kVerifyPosTol || er > kVerifyRotTol) continue;
    expand_variants(rig, qq, revolute, &sols, &violation);
  }
  if (sols.empty() && why_none) {
    *why_none = "all " + std::to_string(raw.size()) + " solutions violate joint limits" +
                (violation.empty() ? std::string() : " (e.g. " + violation + ")");
  }
  return sols;
}

std::vector<Vector6d> ik_with_ref(const RigModel& rig, const Pose& world_T_flange,
                                  const Vector6d& q_ref, std::string* why_none) {
  if (rig.kind == RigKind::kFree) return free_ik(rig, world_T_flange, q_ref, why_none);
  if (rig.ik == IkMethod::kGeneral) return general_ik(rig, world_T_flange, q_ref, why_none);
  if (rig.ik == IkMethod::kParallelAxes) return parallel_axes_ik(rig, world_T_flange, q_ref, why_none);
  if (!rig.spherical_wrist) {
    throw std::invalid_argument("rig model " + rig.model_path +
                                ": the analytic IK needs the spherical-wrist layout; use the general IK");
  }
  return arm_ik(rig, world_T_flange, q_ref, why_none);
}

}  // namespace rig_internal

std::vector<Vector6d> inverse_kinematics(const RigModel& rig, const Pose& world_T_flange,
                                         std::string* why_none, const Vector6d& q_ref) {
  return ik_with_ref(rig, world_T_flange, q_ref, why_none);
}

}  // namespace pbnbv
