// The rig read from its MJCF file, its kinematics and the reachability check. See rig.hpp.
//
// Arm kinematics (KUKA layout, all joint frames parallel to the base frame at q = 0, the arm
// stretched forward along the base +x):
//   base_T_flange = Rz(q1) T(a1,0,d1) Ry(q2) T(a2,0,0) Ry(q3) T(0,0,a3) Rx(q4) T(d4,0,0) Ry(q5)
//                   T(d6,0,0) Rx(q6)
// which is exactly the body tree of models/rig_arm.xml (link bodies with identity rotations,
// hinge joints at the body origins), so this code and MuJoCo's mj_kinematics agree to rounding.
//
// Free rig (virtual gantry): world_T_flange = T(x,y,z) Rz(yaw) Ry(pitch) Rx(roll).
//
// ReachabilityChecker: per candidate turntable angle (the view brought to the preferred
// azimuth, then +-15 ... +-90 deg around it) the IK solutions are ordered by a joint-space
// distance to q_current weighted by the joint speed limits (~ motion time); the first one that
// (1) collides with nothing (arm-side geoms vs table, floor, pedestal, arm base, turntable and
// the keep-out box, with 5 mm clearance) and (2) has a free line of sight from the optical
// centre to the object (rays to the keep-out box centre and its corners pulled 20% inwards
// must not hit a rendered rig geom, e.g. the arm's own links or the pedestal) wins.
#include "core/rig/rig.hpp"
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
// Arm forward kinematics on the base frame.
Pose arm_base_T_flange(const ArmGeometry& g, const Vector6d& q) {
  const double c1 = std::cos(q[0]), s1 = std::sin(q[0]);
  const double c23 = std::cos(q[1] + q[2]), s23 = std::sin(q[1] + q[2]);
  const double c2 = std::cos(q[1]), s2 = std::sin(q[1]);
  // Wrist centre in the arm plane (x forward, z up, relative to the A2 axis).
  const double r = g.a2 * c2 + g.d4 * c23 + g.a3 * s23;
  const double s = -g.a2 * s2 - g.d4 * s23 + g.a3 * c23;
  const Eigen::Matrix3d r03 = rot_z(q[0]) * rot_y(q[1] + q[2]);
  const Eigen::Matrix3d r36 = rot_x(q[3]) * rot_y(q[4]) * rot_x(q[5]);
  Pose p = Pose::Identity();
  p.linear() = r03 * r36;
  const Eigen::Vector3d wc((g.a1 + r) * c1, (g.a1 + r) * s1, g.d1 + s);
  p.translation() = wc + g.d6 * p.linear().col(0);
  return p;
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

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string to_string(RigKind kind) { return std::string(name_of(kind)); }

RigKind parse_rig_kind(const std::string& s) { return parse_name<RigKind>(s); }

std::string default_rig_path(RigKind kind) {
  const char* env = std::getenv("PBNBV_MODELS_DIR");
  const std::string dir = (env && *env) ? std::string(env) : std::string(PBNBV_MODELS_DIR);
  return dir + "/rig_" + to_string(kind) + ".xml";
}

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

  std::vector<ChainSpec> spec;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  if (rig.kind == RigKind::kArm) {
    spec = {{"a1", mjJNT_HINGE, ez}, {"a2", mjJNT_HINGE, ey}, {"a3", mjJNT_HINGE, ey},
            {"a4", mjJNT_HINGE, ex}, {"a5", mjJNT_HINGE, ey}, {"a6", mjJNT_HINGE, ex}};
  } else {
    spec = {{"gantry_x", mjJNT_SLIDE, ex},     {"gantry_y", mjJNT_SLIDE, ey},
            {"gantry_z", mjJNT_SLIDE, ez},     {"gantry_yaw", mjJNT_HINGE, ez},
            {"gantry_pitch", mjJNT_HINGE, ey}, {"gantry_roll", mjJNT_HINGE, ex}};
  }
  std::vector<int> jids, bids;
  check_chain_joints(m, path, spec, &jids, &bids);
  for (int i = 0; i < 6; ++i) {
    rig.joint_names.push_back(spec[i].name);
    rig.q_lower[i] = m->jnt_range[2 * jids[i]];
    rig.q_upper[i] = m->jnt_range[2 * jids[i] + 1];
    if (!(rig.q_lower[i] < rig.q_upper[i])) {
      fail(path, std::string("joint \"") + spec[i].name + "\" has an empty range");
    }
  }

  // Base: the parent of the first joint's body, welded to the world.
  const int base_body = m->body_parentid[bids[0]];
  if (m->body_weldid[base_body] != 0) {
    fail(path, "the body carrying the first joint must be attached to a static body");
  }
  rig.world_T_base = body_world_pose_static(m, base_body);

  // Link offsets.
  std::vector<Eigen::Vector3d> off;
  for (int i = 0; i < 6; ++i) off.push_back(body_local_pose(m, bids[i]).translation());
  if (rig.kind == RigKind::kArm) {
    // link_1 at the base origin; link_2 at (a1, 0, d1); link_3 at (a2, 0, 0);
    // link_4 at (0, 0, a3); link_5 at (d4, 0, 0); link_6 at (d6, 0, 0).
    const std::array<Eigen::Vector3d, 6> mask{
        Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(1, 0, 0),
        Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 0, 0)};
    for (int i = 0; i < 6; ++i) {
      const Eigen::Vector3d masked = off[i].cwiseProduct(mask[i]);
      if (!near(masked, off[i])) {
        fail(path, "body of joint " + rig.joint_names[i] + " has offset " + vec_str(off[i]) +
                       " from its parent; the spherical-wrist layout allows only the components " +
                       vec_str(mask[i]));
      }
    }
    rig.arm.a1 = off[1].x();
    rig.arm.d1 = off[1].z();
    rig.arm.a2 = off[2].x();
    rig.arm.a3 = off[3].z();
    rig.arm.d4 = off[4].x();
    rig.arm.d6 = off[5].x();
    if (!(rig.arm.a2 > 0 && rig.arm.d4 > 0 && rig.arm.d6 >= 0)) {
      fail(path, "arm lengths a2, d4 must be positive and d6 non-negative");
    }
  } else {
    for (int i = 0; i < 6; ++i) {
      if (!near(off[i], Eigen::Vector3d::Zero())) {
        fail(path, "gantry body of joint " + rig.joint_names[i] + " must sit at its parent's "
                       "origin (offset " + vec_str(off[i]) + ")");
      }
    }
  }

  // Flange and camera.
  const int flange = body_id(m, path, "flange");
  const int camera = body_id(m, path, "camera_optical");
  if (m->body_parentid[flange] != bids[5]) {
    fail(path, "body \"flange\" must be a child of the last joint's body");
  }
  if (!near(body_local_pose(m, flange).translation(), Eigen::Vector3d::Zero()) ||
      !is_identity_rotation(body_local_pose(m, flange))) {
    fail(path, "body \"flange\" must coincide with the last joint's body frame");
  }
  if (m->body_parentid[camera] != flange) {
    fail(path, "body \"camera_optical\" must be a child of body \"flange\"");
  }
  if (m->body_jntnum[flange] != 0 || m->body_jntnum[camera] != 0) {
    fail(path, "bodies \"flange\" and \"camera_optical\" must not carry joints");
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
  return rig.world_T_base * arm_base_T_flange(rig.arm, q);
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
                                         std::string* why_none) {
  return ik_with_ref(rig, world_T_flange, Vector6d::Zero(), why_none);
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
  // rig, e.g. the arm's own links or the pedestal. Call after colliding() (uses its kinematics).
  // Returns the name of the blocking geom's body/geom, or "" when the view is clear.
  std::string occluder(const Pose& world_T_camera, const Eigen::AlignedBox3d& box, double turntable_rad,
                       double object_z_m) {
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
      if (gid >= 0 && x >= 0 && x < 1.0 && !in_object[gid]) return side_name[gid];
    }
    return "";
  }

  // Colliding arm/environment geom pairs at this state (keep-out box already set).
  std::vector<std::string> colliding(const Vector6d& q, double turntable_rad) {
    mjModel* m = model.get();
    mjData* d = data.get();
    for (int i = 0; i < 6; ++i) d->qpos[qadr[i]] = q[i];
    if (turntable_qadr >= 0) d->qpos[turntable_qadr] = turntable_rad - rig.turntable_zero_rad;
    mj_kinematics(m, d);
    mj_collision(m, d);
    std::vector<std::string> out;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const bool a1 = arm_side[c.geom1], a2 = arm_side[c.geom2];
      if (a1 == a2) continue;
      if (c.dist >= kContactMargin) continue;
      const int ga = a1 ? c.geom1 : c.geom2, ge = a1 ? c.geom2 : c.geom1;
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
    std::string why;
    std::vector<Vector6d> sols = ik_with_ref(rig, world_T_flange, q_current, &why);
    std::string reason;
    if (sols.empty()) {
      reason = why;
    } else {
      std::sort(sols.begin(), sols.end(), [&](const Vector6d& x, const Vector6d& y) {
        return motion_cost(rig, x, q_current) < motion_cost(rig, y, q_current);
      });
      std::vector<std::string> hits, blocks;
      for (const Vector6d& q : sols) {
        const std::vector<std::string> col = im.colliding(q, t);
        if (!col.empty()) {
          for (const std::string& s : col) {
            if (std::find(hits.begin(), hits.end(), s) == hits.end()) hits.push_back(s);
          }
          continue;
        }
        const Pose w_c = camera_in_world(rig, q);
        const std::string occ = im.occluder(w_c, keepout, t, object_z_m);
        if (!occ.empty()) {
          if (std::find(blocks.begin(), blocks.end(), occ) == blocks.end()) blocks.push_back(occ);
          continue;
        }
        out.reachable = true;
        out.q = q;
        out.turntable_rad = t;
        out.world_T_camera = w_c;
        return out;
      }
      if (blocks.empty()) {
        reason = "all " + std::to_string(sols.size()) + " IK solutions collide (" +
                 join_unique(hits) + ")";
      } else {
        reason = "all " + std::to_string(sols.size()) + " IK solutions collide or have the view "
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
  for (const Pose& p : object_T_cameras) {
    out.push_back(solve(p, q_current, turntable_current, keepout, object_z_m));
  }
  return out;
}

}  // namespace pbnbv
