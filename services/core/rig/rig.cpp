// The rig read from its MJCF file, its kinematics and the reachability check. See rig.hpp.
//
// Arm kinematics: the chain of 6 hinge joints as the MJCF body tree gives it (RigModel::chain):
//   base_T_flange = prod_i [ parent_T_body_i  T(anchor_i) R(axis_i, q_i) T(-anchor_i) ]
//                   last_T_flange
// which is what MuJoCo's mj_kinematics computes, so the two agree to rounding.
// Analytic IK for the spherical-wrist KUKA layout (detected on load: all joint frames parallel
// to the base frame at q = 0, the arm stretched forward along the base +x):
//   base_T_flange = Rz(q1) T(a1,0,d1) Ry(q2) T(a2,0,0) Ry(q3) T(0,0,a3) Rx(q4) T(d4,0,0) Ry(q5)
//                   T(d6,0,0) Rx(q6)
// General IK for any other chain: Levenberg-Marquardt (damped least squares with adaptive
// damping) on the chain's geometric Jacobian, from several seeds, joint limits respected.
//
// Free rig (virtual gantry): world_T_flange = T(x,y,z) Rz(yaw) Ry(pitch) Rx(roll).
//
// ReachabilityChecker: per candidate turntable angle (the view brought to the preferred
// azimuth, then +-15 ... +-90 deg around it) the IK solutions are ordered by a joint-space
// distance to q_current weighted by the joint speed limits (~ motion time); the first one that
// (1) collides with nothing (arm-side geoms vs table, floor, pedestal, arm base, turntable and
// the keep-out box, with 5 mm clearance) and (2) has a free line of sight from the optical
// centre to the object (rays to the keep-out box centre and its corners pulled 20% inwards
// must not hit a rendered rig geom, e.g. the arm's own links or the pedestal) wins. The line of
// sight is checked first (cheaper); when what blocks or collides does not depend on the
// configuration (the environment blocks the view, or the camera itself collides) no other
// solution at that angle is tried. With the general IK the solutions come in stages of seeds
// (in a batch the neighbouring candidate's solution; the current configuration and home; spread
// seeds), each stage checked before the next is solved.
#include "core/rig/rig.hpp"
#include "core/base/install_paths.hpp"
#include "core/base/format.hpp"
#include "core/base/units.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace pbnbv {

namespace {

constexpr double kLimitTol = 1e-9;      // joint-limit tolerance, rad (m)
constexpr double kVerifyPosTol = 1e-6;  // IK verification, m
constexpr double kVerifyRotTol = 1e-6;  // IK verification, rad
constexpr double kContactMargin = 0.005;  // clearance required by the collision check, m


Eigen::Matrix3d rot_x(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
Eigen::Matrix3d rot_y(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
Eigen::Matrix3d rot_z(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

Pose pose_from_mj(const mjtNum pos[3], const mjtNum quat[4]) {
  Pose p = Pose::Identity();
  Eigen::Quaterniond q(quat[0], quat[1], quat[2], quat[3]);
  p.linear() = q.normalized().toRotationMatrix();
  p.translation() = Eigen::Vector3d(pos[0], pos[1], pos[2]);
  return p;
}

Pose body_local_pose(const mjModel* m, int b) {
  return pose_from_mj(m->body_pos + 3 * b, m->body_quat + 4 * b);
}

// Pose of body b in the world with all joints at zero (composition of body offsets; joints are
// checked to be absent or at their zero position by the callers).
Pose body_world_pose_static(const mjModel* m, int b) {
  Pose p = Pose::Identity();
  while (b > 0) {
    p = body_local_pose(m, b) * p;
    b = m->body_parentid[b];
  }
  return p;
}

struct MjModelDeleter {
  void operator()(mjModel* m) const { if (m) mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { if (d) mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using DataPtr = std::unique_ptr<mjData, MjDataDeleter>;

ModelPtr load_mj_model(const std::string& path) {
  {
    std::ifstream f(path);
    if (!f.good()) throw std::runtime_error("rig model " + path + ": cannot open the file");
  }
  char err[1000] = {0};
  // The MJCF parser keeps global state; serialise loads (checkers are built per thread).
  static std::mutex load_mutex;
  mjModel* m = nullptr;
  {
    std::lock_guard<std::mutex> lock(load_mutex);
    m = mj_loadXML(path.c_str(), nullptr, err, sizeof(err));
  }
  if (!m) throw std::runtime_error("rig model " + path + ": MuJoCo cannot load it: " + err);
  return ModelPtr(m);
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error("rig model " + path + ": " + what);
}

std::string custom_text(const mjModel* m, const std::string& path, const char* name) {
  const int id = mj_name2id(m, mjOBJ_TEXT, name);
  if (id < 0) fail(path, std::string("missing <custom><text name=\"") + name + "\">");
  return std::string(m->text_data + m->text_adr[id]);
}

std::vector<double> custom_numeric(const mjModel* m, const std::string& path, const char* name,
                                   int expected_size) {
  const int id = mj_name2id(m, mjOBJ_NUMERIC, name);
  if (id < 0) fail(path, std::string("missing <custom><numeric name=\"") + name + "\">");
  if (m->numeric_size[id] != expected_size) {
    fail(path, std::string("custom numeric ") + name + " has " +
                   std::to_string(m->numeric_size[id]) + " values, expected " +
                   std::to_string(expected_size));
  }
  const mjtNum* p = m->numeric_data + m->numeric_adr[id];
  return std::vector<double>(p, p + expected_size);
}

// The optional <custom> camera (RigCamera); throws naming the file and the value.
std::optional<RigCamera> read_camera(const mjModel* m, const std::string& path) {
  const int id_text = mj_name2id(m, mjOBJ_TEXT, "pbnbv_camera_id");
  if (mj_name2id(m, mjOBJ_NUMERIC, "pbnbv_camera") < 0) {
    if (id_text >= 0) fail(path, "pbnbv_camera_id is given without <custom><numeric name=\"pbnbv_camera\">");
    return std::nullopt;
  }
  const std::vector<double> v = custom_numeric(m, path, "pbnbv_camera", 8);
  RigCamera c;
  for (int i : {0, 1}) {
    if (!(v[i] >= 1 && v[i] <= 16384 && v[i] == std::round(v[i]))) {
      fail(path, std::string("pbnbv_camera ") + (i == 0 ? "width" : "height") + " = " + std::to_string(v[i]) +
                     " is not a whole number of pixels in [1, 16384] (data=\"width height fx fy cx cy depth_min "
                     "depth_max\")");
    }
  }
  c.intrinsics = CameraIntrinsics{static_cast<int>(v[0]), static_cast<int>(v[1]), v[2], v[3], v[4], v[5]};
  c.range = DepthRange{v[6], v[7]};
  try {
    c.intrinsics.validate();
    c.range.validate();
  } catch (const std::invalid_argument& e) {
    fail(path, std::string("pbnbv_camera (data=\"width height fx fy cx cy depth_min depth_max\"): ") + e.what());
  }
  if (id_text >= 0) c.id = std::string(m->text_data + m->text_adr[id_text]);
  return c;
}

int body_id(const mjModel* m, const std::string& path, const char* name) {
  const int id = mj_name2id(m, mjOBJ_BODY, name);
  if (id < 0) fail(path, std::string("missing body \"") + name + "\"");
  return id;
}

bool near(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = 1e-9) {
  return (a - b).cwiseAbs().maxCoeff() <= tol;
}

std::string vec_str(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

bool is_identity_rotation(const Pose& p, double tol = 1e-9) {
  return (p.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tol;
}

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

using Matrix6d = Eigen::Matrix<double, 6, 6>;

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

Pose free_world_T_flange(const Vector6d& q) {
  Pose p = Pose::Identity();
  p.translation() = q.head<3>();
  p.linear() = rot_z(q[3]) * rot_y(q[4]) * rot_x(q[5]);
  return p;
}

bool within_limits(const RigModel& rig, const Vector6d& q, int* bad_joint = nullptr) {
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

// Rotation angle between a and b, accurate near zero (atan2 of sine and cosine).
double rotation_error(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d r = a.transpose() * b;
  const double s = 0.5 * Eigen::Vector3d(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)).norm();
  const double c = 0.5 * (r.trace() - 1.0);
  return std::atan2(s, c);
}

// Pose error (position m, rotation rad).
std::pair<double, double> pose_error(const Pose& a, const Pose& b) {
  return {(a.translation() - b.translation()).norm(), rotation_error(a.linear(), b.linear())};
}

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

  const std::array<bool, 6> revolute{true, true, true, true, true, true};
  std::vector<Vector6d> sols;
  std::string violation;
  for (const Vector6d& q : raw) {
    Vector6d qq = q;
    for (int i = 0; i < 6; ++i) qq[i] = wrap_angle_rad(qq[i]);
    // Verify (and polish if needed) before expanding variants.
    auto [ep, er] = pose_error(flange_in_world(rig, qq), world_T_flange);
    if (ep > 1e-10 || er > 1e-10) {
      qq = polish_arm(rig, world_T_flange, qq);
      std::tie(ep, er) = pose_error(flange_in_world(rig, qq), world_T_flange);
    }
    if (ep > kVerifyPosTol || er > kVerifyRotTol) continue;
    expand_variants(rig, qq, revolute, &sols, &violation);
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

// ---------------------------------------------------------------------------------------------
// General IK (any 6R chain).

constexpr int kSeedIterations = 40;        // LM iterations per seed (typically 5-15 suffice)
constexpr double kConvergedError = 1e-24;  // squared pose error (m^2 + rad^2) counted converged
constexpr double kMaxStepRad = 0.5;        // largest joint step per iteration
constexpr int kStallWindow = 5;            // LM gives up when the error has not fallen below
constexpr double kStallRatioFast = 0.25;   // this fraction of itself within the window: the
constexpr double kStallRatioFull = 0.9;    // reachability check gives up early, the full search
                                           // late
constexpr int kFullSearchSpreadSeeds = 32;  // inverse_kinematics(): spread seeds after ref, home
constexpr int kReachSpreadSeeds = 6;       // ReachabilityChecker: spread seeds when the near
                                           // seeds give no collision-free solution

// target - current as a twist: position (m), rotation vector (rad), both in the same frame.
Vector6d twist_error(const Pose& target, const Pose& cur) {
  Vector6d e;
  e.head<3>() = target.translation() - cur.translation();
  const Eigen::Matrix3d r = target.linear() * cur.linear().transpose();
  const Eigen::Vector3d v(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  const double s = 0.5 * v.norm(), c = 0.5 * (r.trace() - 1.0);
  if (c < -0.99) {  // near pi: the skew part loses the axis
    const Eigen::AngleAxisd aa(r);
    e.tail<3>() = aa.angle() * aa.axis();
  } else {
    e.tail<3>() = s < 1e-15 ? Eigen::Vector3d(0.5 * v) : Eigen::Vector3d(std::atan2(s, c) / (2 * s) * v);
  }
  return e;
}

// Joint i's value brought into its limits: a 2*pi turn (the same geometry) when that fits, else
// clamped.
double into_limits(const RigModel& rig, int i, double v) {
  const double lo = rig.q_lower[i], hi = rig.q_upper[i];
  if (v < lo) {
    const double w = v + 2.0 * kPi * std::ceil((lo - v) / (2.0 * kPi));
    return w <= hi ? w : lo;
  }
  if (v > hi) {
    const double w = v - 2.0 * kPi * std::ceil((v - hi) / (2.0 * kPi));
    return w >= lo ? w : hi;
  }
  return v;
}

// Levenberg-Marquardt from `seed` towards base_T_target (flange in the base frame); joints kept
// within their limits at every step. True when the pose error vanished.
bool lm_solve(const RigModel& rig, const Pose& base_T_target, const Vector6d& seed, int max_iter,
              double stall_ratio, Vector6d* q_out) {
  Vector6d q;
  for (int i = 0; i < 6; ++i) q[i] = into_limits(rig, i, seed[i]);
  Matrix6d jac, jac_next;
  Vector6d e = twist_error(base_T_target, chain_fk_jacobian(rig, q, &jac));
  double f = e.squaredNorm();
  double lambda = 1e-3;
  double f_before = f;  // error kStallWindow iterations ago
  for (int it = 0; it < max_iter && f > kConvergedError; ++it) {
    if (it > 0 && it % kStallWindow == 0) {
      if (f > stall_ratio * f_before) break;  // stalled: a local minimum or a joint limit in the way
      f_before = f;
    }
    Matrix6d a = jac.transpose() * jac;
    a.diagonal().array() += lambda;
    Vector6d dq = a.llt().solve(jac.transpose() * e);  // a is positive definite
    const double mx = dq.cwiseAbs().maxCoeff();
    if (!(mx < 1e9)) return false;  // NaN or runaway
    if (mx > kMaxStepRad) dq *= kMaxStepRad / mx;
    Vector6d qn = q + dq;
    for (int i = 0; i < 6; ++i) qn[i] = into_limits(rig, i, qn[i]);
    const Vector6d en = twist_error(base_T_target, chain_fk_jacobian(rig, qn, &jac_next));
    const double fn = en.squaredNorm();
    if (fn < f) {
      q = qn;
      e = en;
      f = fn;
      jac = jac_next;
      lambda = std::max(lambda * 0.1, 1e-12);
    } else {
      lambda *= 10.0;
      if (lambda > 1e4) break;  // stuck in a local minimum or against a limit
    }
  }
  if (f > kConvergedError) return false;
  *q_out = q;
  return true;
}

// Quasi-random configurations spread over the joint ranges (Halton sequence; ranges wider than
// one turn cut to +-pi, other turns being the same geometry).
std::vector<Vector6d> spread_seeds(const RigModel& rig, int n) {
  static constexpr int kBases[6] = {2, 3, 5, 7, 11, 13};
  std::vector<Vector6d> out;
  for (int k = 1; k <= n; ++k) {
    Vector6d q;
    for (int i = 0; i < 6; ++i) {
      double f = 1, r = 0;
      for (int x = k; x > 0; x /= kBases[i]) {
        f /= kBases[i];
        r += f * (x % kBases[i]);
      }
      const double lo = std::max(rig.q_lower[i], -kPi), hi = std::min(rig.q_upper[i], kPi);
      q[i] = lo + r * (hi - lo);
    }
    out.push_back(q);
  }
  return out;
}

// Upper bound of the distance from joint 1's axis point to the flange origin: each joint turns
// the rest of the chain about its own axis point, so the distances between consecutive axis
// points (and from the last to the flange) never change.
double chain_reach_bound(const RigModel& rig, Eigen::Vector3d* first_anchor) {
  Pose t = Pose::Identity();
  double sum = 0;
  Eigen::Vector3d prev;
  for (int i = 0; i < 6; ++i) {
    t = t * rig.chain[i].parent_T_body;
    const Eigen::Vector3d p = t * rig.chain[i].anchor;
    if (i == 0) *first_anchor = p;
    else sum += (p - prev).norm();
    prev = p;
  }
  return sum + ((t * rig.last_T_flange).translation() - prev).norm();
}

// "out of reach" reason when the flange pose is provably beyond the chain's reach, else "".
std::string general_out_of_reach(const RigModel& rig, const Pose& base_T_target) {
  Eigen::Vector3d p1;
  const double bound = chain_reach_bound(rig, &p1);
  const double dist = (base_T_target.translation() - p1).norm();
  if (dist <= bound + 1e-9) return "";
  return "out of reach: the flange is " + fixed(dist, 3) + " m from the first joint, the arm reaches at most " +
         fixed(bound, 3) + " m";
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

}  // namespace

namespace {

bool general_ik_seed(const RigModel& rig, const Pose& world_T_flange, const Vector6d& seed,
                     double stall_ratio, Vector6d* q) {
  Vector6d sol;
  if (!lm_solve(rig, rig.world_T_base.inverse() * world_T_flange, seed, kSeedIterations, stall_ratio, &sol)) {
    return false;
  }
  const auto [ep, er] = pose_error(flange_in_world(rig, sol), world_T_flange);
  if (ep > kVerifyPosTol || er > kVerifyRotTol || !within_limits(rig, sol)) return false;
  *q = sol;
  return true;
}

}  // namespace

bool general_ik_from_seed(const RigModel& rig, const Pose& world_T_flange, const Vector6d& seed,
                          Vector6d* q) {
  if (rig.kind != RigKind::kArm) throw std::invalid_argument("general_ik_from_seed: not an arm rig");
  return general_ik_seed(rig, world_T_flange, seed, kStallRatioFull, q);
}

namespace {

// General IK: the distinct solutions reached from q_ref, home and the spread seeds, with their
// +-2*pi variants.
std::vector<Vector6d> general_ik(const RigModel& rig, const Pose& world_T_flange,
                                 const Vector6d& q_ref, std::string* why_none) {
  const std::string far = general_out_of_reach(rig, rig.world_T_base.inverse() * world_T_flange);
  if (!far.empty()) {
    if (why_none) *why_none = far;
    return {};
  }
  std::vector<Vector6d> seeds{q_ref, rig.q_home};
  const std::vector<Vector6d> spread = spread_seeds(rig, kFullSearchSpreadSeeds);
  seeds.insert(seeds.end(), spread.begin(), spread.end());
  std::vector<Vector6d> distinct;
  for (const Vector6d& seed : seeds) {
    Vector6d q;
    if (!general_ik_seed(rig, world_T_flange, seed, kStallRatioFull, &q)) continue;
    bool dup = false;
    for (const Vector6d& d : distinct) dup = dup || same_modulo_turns(d, q);
    if (!dup) distinct.push_back(q);
  }
  const std::array<bool, 6> revolute{true, true, true, true, true, true};
  std::vector<Vector6d> sols;
  std::string violation;
  for (const Vector6d& q : distinct) expand_variants(rig, q, revolute, &sols, &violation);
  if (sols.empty() && why_none) {
    *why_none = distinct.empty()
                    ? "no IK solution within the joint limits from " + std::to_string(seeds.size()) +
                          " seeds (out of reach or beyond the limits)"
                    : "all " + std::to_string(distinct.size()) + " solutions violate joint limits" +
                          (violation.empty() ? std::string() : " (e.g. " + violation + ")");
  }
  return sols;
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
  if (!rig.spherical_wrist) {
    throw std::invalid_argument("rig model " + rig.model_path +
                                ": the analytic IK needs the spherical-wrist layout; use the general IK");
  }
  return arm_ik(rig, world_T_flange, q_ref, why_none);
}

// ---------------------------------------------------------------------------------------------
// Loader helpers.

struct ChainSpec {
  const char* name;
  int type;             // mjJNT_HINGE / mjJNT_SLIDE
  Eigen::Vector3d axis;  // in the body frame at zero
};

void check_chain_joints(const mjModel* m, const std::string& path,
                        const std::vector<ChainSpec>& spec, std::vector<int>* joint_ids,
                        std::vector<int>* body_ids) {
  int prev_body = -1;
  for (const ChainSpec& s : spec) {
    const int j = mj_name2id(m, mjOBJ_JOINT, s.name);
    if (j < 0) fail(path, std::string("missing joint \"") + s.name + "\"");
    if (m->jnt_type[j] != s.type) {
      fail(path, std::string("joint \"") + s.name + "\" must be a " +
                     (s.type == mjJNT_HINGE ? "hinge" : "slide") + " joint");
    }
    const Eigen::Vector3d axis(m->jnt_axis[3 * j], m->jnt_axis[3 * j + 1], m->jnt_axis[3 * j + 2]);
    if (!near(axis, s.axis)) {
      fail(path, std::string("joint \"") + s.name + "\" has axis " + vec_str(axis) +
                     ", the layout needs " + vec_str(s.axis));
    }
    const Eigen::Vector3d jpos(m->jnt_pos[3 * j], m->jnt_pos[3 * j + 1], m->jnt_pos[3 * j + 2]);
    if (!near(jpos, Eigen::Vector3d::Zero())) {
      fail(path, std::string("joint \"") + s.name + "\" must sit at its body origin (pos " +
                     vec_str(jpos) + ")");
    }
    if (!m->jnt_limited[j]) fail(path, std::string("joint \"") + s.name + "\" has no range");
    if (std::abs(m->qpos0[m->jnt_qposadr[j]]) > 1e-12) {
      fail(path, std::string("joint \"") + s.name + "\" has a nonzero reference position");
    }
    const int b = m->jnt_bodyid[j];
    if (m->body_jntnum[b] != 1) {
      fail(path, std::string("body of joint \"") + s.name + "\" must carry exactly one joint");
    }
    if (prev_body >= 0 && m->body_parentid[b] != prev_body) {
      fail(path, std::string("joint \"") + s.name + "\" is not on the child body of the "
                     "previous joint's body");
    }
    if (!is_identity_rotation(body_local_pose(m, b))) {
      fail(path, std::string("body of joint \"") + s.name +
                     "\" must not be rotated relative to its parent");
    }
    joint_ids->push_back(j);
    body_ids->push_back(b);
    prev_body = b;
  }
}

// Pose of body `to` in the frame of its ancestor `from` (all joints at zero).
Pose relative_static_pose(const mjModel* m, int from, int to) {
  Pose p = Pose::Identity();
  for (int b = to; b != from; b = m->body_parentid[b]) p = body_local_pose(m, b) * p;
  return p;
}

// The spherical-wrist KUKA layout (ArmGeometry) of the chain, if it has it.
bool match_spherical_wrist(const RigModel& rig, ArmGeometry* g) {
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  const std::array<Eigen::Vector3d, 6> axes{ez, ey, ey, ex, ey, ex};
  // link_1 at the base origin; link_2 at (a1, 0, d1); link_3 at (a2, 0, 0);
  // link_4 at (0, 0, a3); link_5 at (d4, 0, 0); link_6 at (d6, 0, 0).
  const std::array<Eigen::Vector3d, 6> mask{
      Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(1, 0, 0),
      Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 0, 0)};
  for (int i = 0; i < 6; ++i) {
    const ChainJoint& j = rig.chain[i];
    const Eigen::Vector3d off = j.parent_T_body.translation();
    if (!near(j.axis, axes[i]) || !near(j.anchor, Eigen::Vector3d::Zero()) ||
        !is_identity_rotation(j.parent_T_body) || !near(off.cwiseProduct(mask[i]), off)) {
      return false;
    }
  }
  if (!near(rig.last_T_flange.translation(), Eigen::Vector3d::Zero()) || !is_identity_rotation(rig.last_T_flange)) {
    return false;
  }
  g->a1 = rig.chain[1].parent_T_body.translation().x();
  g->d1 = rig.chain[1].parent_T_body.translation().z();
  g->a2 = rig.chain[2].parent_T_body.translation().x();
  g->a3 = rig.chain[3].parent_T_body.translation().z();
  g->d4 = rig.chain[4].parent_T_body.translation().x();
  g->d6 = rig.chain[5].parent_T_body.translation().x();
  return g->a2 > 0 && g->d4 > 0 && g->d6 >= 0;
}

// The arm's chain: the hinge joints on the path from the world to body "flange", base first.
void load_arm_chain(const mjModel* m, const std::string& path, int flange, RigModel* rig) {
  std::vector<int> jids;  // flange first
  for (int b = flange; b > 0; b = m->body_parentid[b]) {
    const char* bn = mj_id2name(m, mjOBJ_BODY, b);
    const std::string body = bn ? std::string("body \"") + bn + "\"" : "body " + std::to_string(b);
    if (m->body_jntnum[b] > 1) {
      fail(path, body + " carries " + std::to_string(m->body_jntnum[b]) +
                     " joints; the arm chain takes one hinge joint per body");
    }
    if (m->body_jntnum[b] == 0) continue;
    const int j = m->body_jntadr[b];
    const char* jn = mj_id2name(m, mjOBJ_JOINT, j);
    const std::string joint = jn ? std::string("joint \"") + jn + "\"" : "joint " + std::to_string(j);
    if (m->jnt_type[j] != mjJNT_HINGE) {
      static const char* kTypes[4] = {"free", "ball", "slide", "hinge"};
      fail(path, joint + " on the chain to body \"flange\" is a " + kTypes[m->jnt_type[j]] +
                     " joint; the arm chain takes hinge joints only");
    }
    if (!jn) fail(path, joint + " on the chain to body \"flange\" has no name");
    jids.push_back(j);
  }
  std::reverse(jids.begin(), jids.end());
  if (jids.size() != 6) {
    std::string names;
    for (int j : jids) names += std::string(names.empty() ? "" : ", ") + mj_id2name(m, mjOBJ_JOINT, j);
    fail(path, "the chain from the world to body \"flange\" has " + std::to_string(jids.size()) +
                   " hinge joints (" + (names.empty() ? std::string("none") : names) + "); an arm needs 6");
  }
  int prev_body = m->body_parentid[m->jnt_bodyid[jids[0]]];
  rig->world_T_base = body_world_pose_static(m, prev_body);
  for (int i = 0; i < 6; ++i) {
    const int j = jids[i];
    const std::string name = mj_id2name(m, mjOBJ_JOINT, j);
    if (!m->jnt_limited[j]) fail(path, "joint \"" + name + "\" has no range");
    if (std::abs(m->qpos0[m->jnt_qposadr[j]]) > 1e-12) {
      fail(path, "joint \"" + name + "\" has a nonzero reference position");
    }
    rig->joint_names.push_back(name);
    rig->q_lower[i] = m->jnt_range[2 * j];
    rig->q_upper[i] = m->jnt_range[2 * j + 1];
    if (!(rig->q_lower[i] < rig->q_upper[i])) fail(path, "joint \"" + name + "\" has an empty range");
    const int b = m->jnt_bodyid[j];
    ChainJoint& c = rig->chain[i];
    c.parent_T_body = relative_static_pose(m, prev_body, b);
    c.axis = Eigen::Vector3d(m->jnt_axis[3 * j], m->jnt_axis[3 * j + 1], m->jnt_axis[3 * j + 2]).normalized();
    c.anchor = Eigen::Vector3d(m->jnt_pos[3 * j], m->jnt_pos[3 * j + 1], m->jnt_pos[3 * j + 2]);
    prev_body = b;
  }
  rig->last_T_flange = relative_static_pose(m, prev_body, flange);
  rig->spherical_wrist = match_spherical_wrist(*rig, &rig->arm);
  if (!rig->spherical_wrist) rig->arm = ArmGeometry{};
  rig->ik = rig->spherical_wrist ? IkMethod::kAnalytic : IkMethod::kGeneral;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string to_string(RigKind kind) { return std::string(name_of(kind)); }

RigKind parse_rig_kind(const std::string& s) { return parse_name<RigKind>(s); }

std::string model_file_path(const std::string& file_name) {
  return resource_dir("PBNBV_MODELS_DIR", "models", PBNBV_MODELS_DIR) + "/" + file_name;
}

std::string default_rig_path(RigKind kind) { return model_file_path("rig_" + to_string(kind) + ".xml"); }

RigModel load_rig(const std::string& path) {
  ModelPtr mp = load_mj_model(path);
  const mjModel* m = mp.get();
  RigModel rig;
  rig.model_path = path;
  try {
    rig.kind = parse_rig_kind(custom_text(m, path, "pbnbv_rig_kind"));
  } catch (const std::invalid_argument& e) {
    fail(path, std::string("pbnbv_rig_kind: ") + e.what());
  }
  {
    const int id = mj_name2id(m, mjOBJ_TEXT, "pbnbv_arm_name");
    rig.arm_name = id >= 0 ? std::string(m->text_data + m->text_adr[id])
                           : (rig.kind == RigKind::kFree ? "virtual gantry" : "");
  }

  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  const int flange = body_id(m, path, "flange");
  const int camera = body_id(m, path, "camera_optical");
  if (m->body_jntnum[flange] != 0 || m->body_jntnum[camera] != 0) {
    fail(path, "bodies \"flange\" and \"camera_optical\" must not carry joints");
  }
  if (rig.kind == RigKind::kArm) {
    load_arm_chain(m, path, flange, &rig);
  } else {
    const std::vector<ChainSpec> spec = {
        {"gantry_x", mjJNT_SLIDE, ex},     {"gantry_y", mjJNT_SLIDE, ey},
        {"gantry_z", mjJNT_SLIDE, ez},     {"gantry_yaw", mjJNT_HINGE, ez},
        {"gantry_pitch", mjJNT_HINGE, ey}, {"gantry_roll", mjJNT_HINGE, ex}};
    std::vector<int> jids, bids;
    check_chain_joints(m, path, spec, &jids, &bids);
    for (int i = 0; i < 6; ++i) {
      rig.joint_names.push_back(spec[i].name);
      rig.q_lower[i] = m->jnt_range[2 * jids[i]];
      rig.q_upper[i] = m->jnt_range[2 * jids[i] + 1];
      if (!(rig.q_lower[i] < rig.q_upper[i])) {
        fail(path, std::string("joint \"") + spec[i].name + "\" has an empty range");
      }
      if (!near(body_local_pose(m, bids[i]).translation(), Eigen::Vector3d::Zero())) {
        fail(path, "gantry body of joint " + rig.joint_names[i] + " must sit at its parent's origin");
      }
    }
    const int base_body = m->body_parentid[bids[0]];
    if (m->body_weldid[base_body] != 0) {
      fail(path, "the body carrying the first joint must be attached to a static body");
    }
    rig.world_T_base = body_world_pose_static(m, base_body);
    if (m->body_parentid[flange] != bids[5] || !near(body_local_pose(m, flange).translation(), Eigen::Vector3d::Zero()) ||
        !is_identity_rotation(body_local_pose(m, flange))) {
      fail(path, "body \"flange\" must be a child of the last joint's body, coinciding with its frame");
    }
  }

  // Camera.
  if (m->body_parentid[camera] != flange) {
    fail(path, "body \"camera_optical\" must be a child of body \"flange\"");
  }
  rig.flange_T_camera = body_local_pose(m, camera);
  if (mj_name2id(m, mjOBJ_CAMERA, "depth") < 0) fail(path, "missing camera \"depth\"");
  if (mj_name2id(m, mjOBJ_GEOM, "keepout") < 0) fail(path, "missing geom \"keepout\"");

  // Object mount and turntable.
  const int mount = body_id(m, path, "object_mount");
  const int tt = mj_name2id(m, mjOBJ_JOINT, "turntable");
  if (rig.kind == RigKind::kArm) {
    if (tt < 0) fail(path, "missing joint \"turntable\"");
    if (m->jnt_type[tt] != mjJNT_HINGE) fail(path, "joint \"turntable\" must be a hinge");
    if (std::abs(m->qpos0[m->jnt_qposadr[tt]]) > 1e-12) {
      fail(path, "joint \"turntable\" has a nonzero reference position");
    }
    // Turntable axis in the world at angle 0 must be world z through the origin.
    const int tb = m->jnt_bodyid[tt];
    if (m->body_weldid[m->body_parentid[tb]] != 0 || m->body_jntnum[tb] != 1) {
      fail(path, "the turntable platter must be a single-joint body on a static body");
    }
    const Pose w_tb = body_world_pose_static(m, tb);
    const Eigen::Vector3d axis_l(m->jnt_axis[3 * tt], m->jnt_axis[3 * tt + 1],
                                 m->jnt_axis[3 * tt + 2]);
    const Eigen::Vector3d anchor_l(m->jnt_pos[3 * tt], m->jnt_pos[3 * tt + 1],
                                   m->jnt_pos[3 * tt + 2]);
    const Eigen::Vector3d axis_w = w_tb.linear() * axis_l;
    const Eigen::Vector3d anchor_w = w_tb * anchor_l;
    if (!near(axis_w, ez) || std::hypot(anchor_w.x(), anchor_w.y()) > 1e-9) {
      fail(path, "the turntable axis must be world +z through the world origin (axis " +
                     vec_str(axis_w) + " through " + vec_str(anchor_w) + ")");
    }
    int b = mount;
    bool on_platter = false;
    while (b > 0) {
      if (b == tb) on_platter = true;
      if (b != tb && b != mount && m->body_jntnum[b] != 0) on_platter = false;
      b = m->body_parentid[b];
    }
    if (!on_platter || m->body_jntnum[mount] != 0) {
      fail(path, "body \"object_mount\" must be fixed on the turntable platter");
    }
    rig.world_T_turntable = body_world_pose_static(m, mount);
    if (!near(rig.world_T_turntable.linear().col(2), ez) ||
        std::hypot(rig.world_T_turntable.translation().x(),
                   rig.world_T_turntable.translation().y()) > 1e-9) {
      fail(path, "body \"object_mount\" must have z along the turntable axis and its origin on it");
    }
    rig.has_turntable = true;
    rig.turntable_qd_max = custom_numeric(m, path, "pbnbv_turntable_speed_limit", 1)[0];
    if (!(rig.turntable_qd_max > 0)) fail(path, "pbnbv_turntable_speed_limit must be positive");
    const Eigen::Vector3d b_rel = rig.world_T_base.translation() - rig.world_T_turntable.translation();
    rig.preferred_azimuth_rad = std::atan2(b_rel.y(), b_rel.x());
    if (mj_name2id(m, mjOBJ_NUMERIC, "pbnbv_turntable_zero") >= 0) {
      rig.turntable_zero_rad = custom_numeric(m, path, "pbnbv_turntable_zero", 1)[0];
      if (!(std::abs(rig.turntable_zero_rad) <= kPi)) fail(path, "pbnbv_turntable_zero must be within [-pi, pi]");
    }
  } else {
    if (tt >= 0) fail(path, "the free rig must not have a turntable joint");
    if (m->body_weldid[mount] != 0) fail(path, "body \"object_mount\" must be static");
    rig.world_T_turntable = body_world_pose_static(m, mount);
    if (!near(rig.world_T_turntable.translation(), Eigen::Vector3d::Zero()) ||
        !is_identity_rotation(rig.world_T_turntable)) {
      fail(path, "free rig: body \"object_mount\" must sit at the world origin, unrotated");
    }
    rig.has_turntable = false;
    rig.preferred_azimuth_rad = 0;
  }

  const std::vector<double> qd = custom_numeric(m, path, "pbnbv_joint_speed_limits", 6);
  const std::vector<double> qh = custom_numeric(m, path, "pbnbv_q_home", 6);
  for (int i = 0; i < 6; ++i) {
    rig.qd_max[i] = qd[i];
    rig.q_home[i] = qh[i];
    if (!(qd[i] > 0)) fail(path, "pbnbv_joint_speed_limits[" + std::to_string(i) + "] must be positive");
  }
  if (!within_limits(rig, rig.q_home)) fail(path, "pbnbv_q_home is outside the joint limits");
  if (const int wv = mj_name2id(m, mjOBJ_TEXT, "pbnbv_working_volume"); wv >= 0) {
    try {
      rig.working_volume = parse_working_volume(std::string(m->text_data + m->text_adr[wv]));
    } catch (const std::invalid_argument& e) {
      fail(path, std::string("pbnbv_working_volume: ") + e.what());
    }
  }
  if (const int platter = mj_name2id(m, mjOBJ_GEOM, "platter"); platter >= 0 && m->geom_type[platter] == mjGEOM_CYLINDER) {
    rig.turntable_radius_m = m->geom_size[3 * platter];
  }
  rig.camera = read_camera(m, path);
  return rig;
}

WorkingVolume working_volume_of(const RigModel& rig) {
  if (rig.working_volume) return *rig.working_volume;
  WorkingVolume w;
  w.radius_m = rig.turntable_radius_m > 0 ? 1.25 * rig.turntable_radius_m : 0.25;
  w.height_m = 2 * w.radius_m;
  return w;
}

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

std::vector<Vector6d> inverse_kinematics(const RigModel& rig, const Pose& world_T_flange,
                                         std::string* why_none, const Vector6d& q_ref) {
  return ik_with_ref(rig, world_T_flange, q_ref, why_none);
}

// ---------------------------------------------------------------------------------------------
// ReachabilityChecker

namespace {

// A keep-out box that encloses a volume (not empty, not flat): only such a box is checked.
bool has_volume(const Eigen::AlignedBox3d& box) { return !box.isEmpty() && box.sizes().minCoeff() > 0; }

}  // namespace

struct ReachabilityChecker::Impl {
  RigModel rig;
  ModelPtr model;
  DataPtr data;
  std::array<int, 6> qadr{};
  int turntable_qadr = -1;
  int keepout = -1;
  int keepout_contype = 0, keepout_conaffinity = 0;
  std::vector<char> arm_side;  // per geom: on the moving arm (or gantry) side
  std::vector<std::string> side_name;  // per geom: name used in reasons
  std::vector<char> in_object;  // per geom: part of the object mount (never an occluder)
  std::vector<char> follows_flange;  // per geom: on the last joint's body or below (its pose is
                                     // fixed by the flange pose alone)
  bool have_neighbour = false;  // solve_batch: the previous candidate's solution seeds the next
  Vector6d neighbour = Vector6d::Zero();

  void set_keepout(const Eigen::AlignedBox3d& box, double object_z_m) {
    mjModel* m = model.get();
    if (!has_volume(box)) {
      m->geom_contype[keepout] = 0;
      m->geom_conaffinity[keepout] = 0;
      return;
    }
    const Eigen::Vector3d half = 0.5 * box.sizes();
    Eigen::Vector3d c = box.center();
    if (rig.kind == RigKind::kArm) c.z() += object_z_m;
    m->geom_contype[keepout] = keepout_contype;
    m->geom_conaffinity[keepout] = keepout_conaffinity;
    for (int i = 0; i < 3; ++i) {
      m->geom_size[3 * keepout + i] = half[i];
      m->geom_pos[3 * keepout + i] = c[i];
    }
    m->geom_quat[4 * keepout] = 1;
    m->geom_quat[4 * keepout + 1] = m->geom_quat[4 * keepout + 2] = m->geom_quat[4 * keepout + 3] = 0;
    m->geom_rbound[keepout] = half.norm();
  }

  // Line of sight: rays from the optical centre to the object frame origin and to the keep-out
  // box corners pulled 20% towards its centre must not hit a rendered geom (groups 0..2) of the
  // rig, e.g. the arm's own links or the pedestal. Call after place() (uses its kinematics).
  // Returns the name of the blocking geom's body/geom, or "" when the view is clear.
  std::string occluder(const Pose& world_T_camera, const Eigen::AlignedBox3d& box, double turntable_rad,
                       double object_z_m, bool* view_fixed = nullptr) {
    const mjModel* m = model.get();
    mjData* d = data.get();
    const Pose w_o = object_in_world(rig, turntable_rad, object_z_m);
    std::vector<Eigen::Vector3d> targets{w_o.translation()};
    if (has_volume(box)) {
      const Eigen::Vector3d half = 0.5 * box.sizes();
      const Eigen::Vector3d c = box.center();
      targets[0] = w_o * c;
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d s((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
        targets.push_back(w_o * (c + 0.8 * s.cwiseProduct(half)));
      }
    }
    const Eigen::Vector3d eye = world_T_camera.translation();
    const mjtByte groups[6] = {1, 1, 1, 0, 0, 0};
    for (const Eigen::Vector3d& t : targets) {
      const Eigen::Vector3d vec = t - eye;
      int gid = -1;
      const mjtNum x = mj_ray(m, d, eye.data(), vec.data(), groups, 1, -1, &gid);
      if (gid >= 0 && x >= 0 && x < 1.0 && !in_object[gid]) {
        if (view_fixed) *view_fixed = !arm_side[gid] || follows_flange[gid];
        return side_name[gid];
      }
    }
    return "";
  }

  // Colliding arm/environment geom pairs at this state (keep-out box already set).
  // `view_fixed` (optional): every colliding pair involves a geom that follows the flange (its
  // pose is fixed by the view, whatever the configuration).
  std::vector<std::string> colliding(const Vector6d& q, double turntable_rad, bool* view_fixed = nullptr) {
    place(q, turntable_rad);
    return colliding_placed(view_fixed);
  }

  // Kinematics of the model at this state (for occluder() and colliding_placed()).
  void place(const Vector6d& q, double turntable_rad) {
    mjData* d = data.get();
    for (int i = 0; i < 6; ++i) d->qpos[qadr[i]] = q[i];
    if (turntable_qadr >= 0) d->qpos[turntable_qadr] = turntable_rad - rig.turntable_zero_rad;
    mj_kinematics(model.get(), d);
  }

  // colliding() at the state last placed.
  std::vector<std::string> colliding_placed(bool* view_fixed = nullptr) {
    mjModel* m = model.get();
    mjData* d = data.get();
    mj_collision(m, d);
    if (view_fixed) *view_fixed = true;
    std::vector<std::string> out;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const bool a1 = arm_side[c.geom1], a2 = arm_side[c.geom2];
      if (a1 == a2) continue;
      if (c.dist >= kContactMargin) continue;
      const int ga = a1 ? c.geom1 : c.geom2, ge = a1 ? c.geom2 : c.geom1;
      if (view_fixed) *view_fixed = *view_fixed && follows_flange[ga];
      const std::string s = side_name[ga] + " / " + side_name[ge];
      if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
    }
    return out;
  }
};

ReachabilityChecker::ReachabilityChecker(const RigModel& rig) : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.rig = rig;
  im.model = load_mj_model(rig.model_path);
  mjModel* m = im.model.get();
  im.data = DataPtr(mj_makeData(m));
  if (!im.data) throw std::runtime_error("rig model " + rig.model_path + ": mj_makeData failed");
  for (int i = 0; i < 6; ++i) {
    const int j = mj_name2id(m, mjOBJ_JOINT, rig.joint_names[i].c_str());
    if (j < 0) fail(rig.model_path, "missing joint \"" + rig.joint_names[i] + "\"");
    im.qadr[i] = m->jnt_qposadr[j];
  }
  const int tt = mj_name2id(m, mjOBJ_JOINT, "turntable");
  im.turntable_qadr = tt >= 0 ? m->jnt_qposadr[tt] : -1;
  im.keepout = mj_name2id(m, mjOBJ_GEOM, "keepout");
  if (im.keepout < 0) fail(rig.model_path, "missing geom \"keepout\"");

  // Arm side: geoms of bodies in the subtree of the first joint's body.
  const int first = m->jnt_bodyid[mj_name2id(m, mjOBJ_JOINT, rig.joint_names[0].c_str())];
  const int mount = mj_name2id(m, mjOBJ_BODY, "object_mount");
  im.arm_side.assign(m->ngeom, 0);
  im.in_object.assign(m->ngeom, 0);
  im.follows_flange.assign(m->ngeom, 0);
  const int last = m->jnt_bodyid[mj_name2id(m, mjOBJ_JOINT, rig.joint_names[5].c_str())];
  im.side_name.assign(m->ngeom, "");
  int arm_contype = 0, arm_conaffinity = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    int b = m->geom_bodyid[g];
    const int body = b;
    bool arm = false;
    while (b > 0) {
      if (b == first) arm = true;
      b = m->body_parentid[b];
    }
    im.arm_side[g] = arm;
    for (int bb = body; bb > 0; bb = m->body_parentid[bb]) {
      if (bb == mount) im.in_object[g] = 1;
      if (bb == last) im.follows_flange[g] = 1;
    }
    const char* bn = mj_id2name(m, mjOBJ_BODY, body);
    const char* gn = mj_id2name(m, mjOBJ_GEOM, g);
    if (arm) {
      im.side_name[g] = bn ? bn : ("body " + std::to_string(body));
      arm_contype |= m->geom_contype[g];
      arm_conaffinity |= m->geom_conaffinity[g];
    } else {
      im.side_name[g] = gn ? gn : (bn ? bn : ("geom " + std::to_string(g)));
    }
    m->geom_margin[g] = kContactMargin;
  }
  // The keep-out box collides with the arm side only.
  im.keepout_contype = arm_conaffinity;
  im.keepout_conaffinity = arm_contype;
  m->geom_contype[im.keepout] = 0;
  m->geom_conaffinity[im.keepout] = 0;
  // The box is moved around: make mj_kinematics place it from geom_pos/geom_quat rather than
  // copying the body (or inertial) frame.
  m->geom_sameframe[im.keepout] = 0;
}

ReachabilityChecker::~ReachabilityChecker() = default;

std::vector<std::string> ReachabilityChecker::collisions(const Vector6d& q, double turntable_rad,
                                                         const Eigen::AlignedBox3d& keepout,
                                                         double object_z_m) {
  impl_->set_keepout(keepout, object_z_m);
  return impl_->colliding(q, turntable_rad);
}

namespace {

// Joint-space distance weighted by the joint speed limits (~ motion time), with a small sum
// term to break ties.
double motion_cost(const RigModel& rig, const Vector6d& a, const Vector6d& b) {
  double mx = 0, sum = 0;
  for (int i = 0; i < 6; ++i) {
    const double t = std::abs(a[i] - b[i]) / rig.qd_max[i];
    mx = std::max(mx, t);
    sum += t;
  }
  return mx + 0.1 * sum;
}

std::string join_unique(const std::vector<std::string>& v, size_t max_items = 3) {
  std::string s;
  for (size_t i = 0; i < v.size() && i < max_items; ++i) s += (i ? ", " : "") + v[i];
  if (v.size() > max_items) s += ", ...";
  return s;
}

}  // namespace

ViewSolution ReachabilityChecker::solve(const Pose& object_T_camera, const Vector6d& q_current,
                                        double turntable_current, const Eigen::AlignedBox3d& keepout,
                                        double object_z_m) {
  Impl& im = *impl_;
  const RigModel& rig = im.rig;
  im.set_keepout(keepout, object_z_m);
  ViewSolution out;

  // Candidate turntable angles: the one bringing the view to the preferred azimuth, then
  // nearby azimuths (+-15 ... +-90 deg).
  std::vector<double> angles;
  std::vector<double> offsets_deg{0};
  if (rig.kind == RigKind::kArm && rig.has_turntable) {
    for (int k = 15; k <= 90; k += 15) {
      offsets_deg.push_back(k);
      offsets_deg.push_back(-k);
    }
    const Eigen::Vector3d c = object_T_camera.translation();
    const bool above = std::hypot(c.x(), c.y()) < 1e-6;
    const double psi = std::atan2(c.y(), c.x());
    for (double off : offsets_deg) {
      const double t = above ? turntable_current + off * kPi / 180.0
                             : rig.preferred_azimuth_rad + off * kPi / 180.0 - psi + rig.turntable_zero_rad;
      angles.push_back(nearest_equivalent_angle_rad(t, turntable_current));
    }
  } else {
    angles.push_back(0.0);
  }

  std::string first_reason;
  std::map<std::string, int> reason_count;
  for (size_t a = 0; a < angles.size(); ++a) {
    const double t = angles[a];
    const Pose world_T_camera = object_in_world(rig, t, object_z_m) * object_T_camera;
    const Pose world_T_flange = world_T_camera * rig.flange_T_camera.inverse();
    // Candidate solutions in order of motion cost; the first collision-free one with the
    // object in sight wins. Configurations equal up to whole joint turns share their geometry:
    // one that failed is not checked again.
    std::vector<std::string> hits, blocks;
    std::vector<Vector6d> failed;
    int checked = 0;
    // True when a solution is clear; sets `hopeless` when what failed does not depend on the
    // configuration (the view itself is blocked, or the camera collides), so that no other
    // solution at this turntable angle can be clear.
    bool hopeless = false;
    auto first_clear = [&](std::vector<Vector6d> sols) {
      std::sort(sols.begin(), sols.end(), [&](const Vector6d& x, const Vector6d& y) {
        return motion_cost(rig, x, q_current) < motion_cost(rig, y, q_current);
      });
      for (const Vector6d& q : sols) {
        ++checked;
        if (std::any_of(failed.begin(), failed.end(), [&](const Vector6d& f) { return same_modulo_turns(f, q); })) {
          continue;
        }
        // Line of sight first (rays are cheaper than the collision check, and a view blocked by
        // the environment is blocked for every solution).
        im.place(q, t);
        const Pose w_c = camera_in_world(rig, q);
        const std::string occ = im.occluder(w_c, keepout, t, object_z_m, &hopeless);
        if (!occ.empty()) {
          if (std::find(blocks.begin(), blocks.end(), occ) == blocks.end()) blocks.push_back(occ);
          if (hopeless) return false;
          failed.push_back(q);
          continue;
        }
        const std::vector<std::string> col = im.colliding_placed(&hopeless);
        if (!col.empty()) {
          for (const std::string& s : col) {
            if (std::find(hits.begin(), hits.end(), s) == hits.end()) hits.push_back(s);
          }
          if (hopeless) return false;
          failed.push_back(q);
          continue;
        }
        out.reachable = true;
        out.q = q;
        out.turntable_rad = t;
        out.world_T_camera = w_c;
        return true;
      }
      return false;
    };
    std::string reason;
    if (rig.kind == RigKind::kArm && rig.ik == IkMethod::kGeneral) {
      // General IK, seeds in stages, each stage's solutions checked before the next is tried:
      // in a batch the previous candidate's solution (a neighbouring view: a few iterations, and
      // the branch continues the current configuration's), then the current configuration and
      // home, then spread seeds (in a batch only when a near seed converged). Each solution is
      // taken in its whole-turn variant nearest the current configuration.
      reason = general_out_of_reach(rig, rig.world_T_base.inverse() * world_T_flange);
      if (reason.empty()) {
        std::vector<std::vector<Vector6d>> stages;
        if (im.have_neighbour) stages.push_back({im.neighbour});
        stages.push_back({q_current, rig.q_home});
        stages.push_back(spread_seeds(rig, kReachSpreadSeeds));
        int n_seeds = 0;
        for (const auto& st : stages) n_seeds += static_cast<int>(st.size());
        std::vector<Vector6d> found;
        for (const std::vector<Vector6d>& seeds : stages) {
          std::vector<Vector6d> fresh;
          for (const Vector6d& seed : seeds) {
            Vector6d q;
            if (!general_ik_seed(rig, world_T_flange, seed, kStallRatioFast, &q)) continue;
            if (std::any_of(found.begin(), found.end(), [&](const Vector6d& f) { return same_modulo_turns(f, q); })) {
              continue;
            }
            for (int i = 0; i < 6; ++i) q[i] = nearest_in_limits(rig, i, q[i], q_current[i]);
            found.push_back(q);
            fresh.push_back(q);
          }
          if (first_clear(fresh)) return out;
          if (hopeless) break;
          // In a batch, when not even the near seeds converge, spread seeds rarely find a
          // solution (measured: none of the 800 hemisphere views needed them) but cost most of
          // the time: skipped.
          if (im.have_neighbour && found.empty() && &seeds == &stages[stages.size() - 2]) break;
        }
        if (found.empty()) {
          reason = "no IK solution within the joint limits from " + std::to_string(n_seeds) +
                   " seeds (out of reach or beyond the limits)";
        }
      }
    } else {
      std::string why;
      std::vector<Vector6d> sols = ik_with_ref(rig, world_T_flange, q_current, &why);
      if (sols.empty()) reason = why;
      else if (first_clear(sols)) return out;
    }
    if (reason.empty()) {
      if (blocks.empty()) {
        reason = "all " + std::to_string(checked) + " IK solutions collide (" + join_unique(hits) + ")";
      } else {
        reason = "all " + std::to_string(checked) + " IK solutions collide or have the view "
                 "blocked (" + join_unique(hits) + (hits.empty() ? "" : "; ") + "view blocked by " +
                 join_unique(blocks) + ")";
      }
    }
    if (a == 0) first_reason = reason;
    ++reason_count[reason];
  }
  out.reachable = false;
  if (angles.size() == 1) {
    out.reason = first_reason;
  } else {
    out.reason = "at the preferred azimuth: " + first_reason +
                 "; also unreachable at azimuth offsets up to +-90 deg";
  }
  return out;
}

std::vector<ViewSolution> ReachabilityChecker::solve_batch(
    const std::vector<Pose>& object_T_cameras, const Vector6d& q_current,
    double turntable_current, const Eigen::AlignedBox3d& keepout, double object_z_m) {
  std::vector<ViewSolution> out;
  out.reserve(object_T_cameras.size());
  // Neighbouring candidates have nearby solutions: each seeds the next one's general IK.
  impl_->have_neighbour = false;
  for (const Pose& p : object_T_cameras) {
    out.push_back(solve(p, q_current, turntable_current, keepout, object_z_m));
    if (out.back().reachable) {
      impl_->neighbour = out.back().q;
      impl_->have_neighbour = true;
    }
  }
  impl_->have_neighbour = false;
  return out;
}

}  // namespace pbnbv
