// The rig read from its MJCF file (load_rig), and what the rig code does with it (kinematics.cpp,
// ik.cpp, general_ik.cpp, reachability.cpp). See rig.hpp.
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
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/base/enum_names.hpp"
#include "core/base/install_paths.hpp"
#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/rig/rig_internal.hpp"

namespace pbnbv {

using namespace rig_internal;

namespace {

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
    if (mj_name2id(m, mjOBJ_TEXT, "pbnbv_camera_model") >= 0) {
      fail(path, "pbnbv_camera_model is given without <custom><numeric name=\"pbnbv_camera\">");
    }
    if (mj_name2id(m, mjOBJ_NUMERIC, "pbnbv_camera_distortion") >= 0) {
      fail(path, "pbnbv_camera_distortion is given without <custom><numeric name=\"pbnbv_camera\">");
    }
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
  if (mj_name2id(m, mjOBJ_NUMERIC, "pbnbv_camera_distortion") >= 0) {
    const std::vector<double> d = custom_numeric(m, path, "pbnbv_camera_distortion", 5);
    c.distortion = LensDistortion{d[0], d[1], d[2], d[3], d[4]};
    try {
      c.distortion.validate(c.intrinsics, "pbnbv_camera_distortion (data=\"k1 k2 p1 p2 k3\")");
    } catch (const std::invalid_argument& e) {
      fail(path, e.what());
    }
  }
  if (id_text >= 0) c.id = std::string(m->text_data + m->text_adr[id_text]);
  const int model_text = mj_name2id(m, mjOBJ_TEXT, "pbnbv_camera_model");
  if (model_text >= 0) {
    const std::string name(m->text_data + m->text_adr[model_text]);
    c.model = find_name<CameraKind>(name);
    if (!c.model) {
      fail(path, "pbnbv_camera_model \"" + name.substr(0, 64) + "\" is not a camera pbnbv knows (" +
                     choices_of<CameraKind>() + ")");
    }
  }
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
  rig->ik = rig->spherical_wrist     ? IkMethod::kAnalytic
            : parallel_axes_layout(*rig) ? IkMethod::kParallelAxes
                                         : IkMethod::kGeneral;
}

}  // namespace

std::string model_file_path(const std::string& file_name) {
  return resource_dir("PBNBV_MODELS_DIR", "models", PBNBV_MODELS_DIR) + "/" + file_name;
}

std::string default_rig_path(RigKind kind) { return model_file_path("rig_" + to_string(kind) + ".xml"); }

namespace {

// The free rig's gantry: six joints (x, y, z, yaw, pitch, roll) ending in the flange.
void load_gantry_chain(const mjModel* m, const std::string& path, int flange, RigModel* out) {
  RigModel& rig = *out;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(), ez = Eigen::Vector3d::UnitZ();
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

// The arm rig's turntable: a hinge about world +z through the origin carrying the object mount;
// its speed limit and the calibrated zero.
void load_turntable(const mjModel* m, const std::string& path, int tt, int mount, RigModel* out) {
  RigModel& rig = *out;
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
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
  rig.turntable_qdd_max = kAccelerationPerSpeed * rig.turntable_qd_max;
  if (mj_name2id(m, mjOBJ_NUMERIC, "pbnbv_turntable_acceleration_limit") >= 0) {
    rig.turntable_qdd_max = custom_numeric(m, path, "pbnbv_turntable_acceleration_limit", 1)[0];
    if (!(rig.turntable_qdd_max > 0 && std::isfinite(rig.turntable_qdd_max))) {
      fail(path, "pbnbv_turntable_acceleration_limit must be positive");
    }
  }
  const Eigen::Vector3d b_rel = rig.world_T_base.translation() - rig.world_T_turntable.translation();
  rig.preferred_azimuth_rad = std::atan2(b_rel.y(), b_rel.x());
  if (mj_name2id(m, mjOBJ_NUMERIC, "pbnbv_turntable_zero") >= 0) {
    rig.turntable_zero_rad = custom_numeric(m, path, "pbnbv_turntable_zero", 1)[0];
    if (!(std::abs(rig.turntable_zero_rad) <= kPi)) fail(path, "pbnbv_turntable_zero must be within [-pi, pi]");
  }
}

// The free rig's object mount: static, at the world origin, unrotated; no turntable.
void load_free_mount(const mjModel* m, const std::string& path, int tt, int mount, RigModel* out) {
  RigModel& rig = *out;
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

// The speed limits, the home pose, the working volume and the platter's radius.
void load_limits(const mjModel* m, const std::string& path, RigModel* out) {
  RigModel& rig = *out;
  const std::vector<double> qd = custom_numeric(m, path, "pbnbv_joint_speed_limits", 6);
  const std::vector<double> qh = custom_numeric(m, path, "pbnbv_q_home", 6);
  for (int i = 0; i < 6; ++i) {
    rig.qd_max[i] = qd[i];
    rig.q_home[i] = qh[i];
    if (!(qd[i] > 0)) fail(path, "pbnbv_joint_speed_limits[" + std::to_string(i) + "] must be positive");
    rig.qdd_max[i] = kAccelerationPerSpeed * qd[i];
  }
  if (mj_name2id(m, mjOBJ_NUMERIC, "pbnbv_joint_acceleration_limits") >= 0) {
    const std::vector<double> qdd = custom_numeric(m, path, "pbnbv_joint_acceleration_limits", 6);
    for (int i = 0; i < 6; ++i) {
      rig.qdd_max[i] = qdd[i];
      if (!(qdd[i] > 0 && std::isfinite(qdd[i]))) {
        fail(path, "pbnbv_joint_acceleration_limits[" + std::to_string(i) + "] must be positive");
      }
    }
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
}

}  // namespace

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
  const int flange = body_id(m, path, "flange");
  const int camera = body_id(m, path, "camera_optical");
  if (m->body_jntnum[flange] != 0 || m->body_jntnum[camera] != 0) {
    fail(path, "bodies \"flange\" and \"camera_optical\" must not carry joints");
  }
  if (rig.kind == RigKind::kArm) {
    load_arm_chain(m, path, flange, &rig);
  } else {
    load_gantry_chain(m, path, flange, &rig);
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
    load_turntable(m, path, tt, mount, &rig);
  } else {
    load_free_mount(m, path, tt, mount, &rig);
  }
  load_limits(m, path, &rig);
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

}  // namespace pbnbv
