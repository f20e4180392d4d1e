#pragma once
// What the parts of the rig code share (core/rig/*.cpp), not part of the library's interface:
// tolerances, the kinematics and IK steps the reachability check reuses, and the MuJoCo model
// handles. Include rig.hpp, not this.
#include <mujoco/mujoco.h>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/rig/rig.hpp"

namespace pbnbv::rig_internal {

inline constexpr double kLimitTol = 1e-9;      // joint-limit tolerance, rad (m)
inline constexpr double kVerifyPosTol = 1e-6;  // IK verification, m
inline constexpr double kVerifyRotTol = 1e-6;  // IK verification, rad
inline constexpr double kContactMargin = 0.005;  // clearance required by the collision check, m

inline Eigen::Matrix3d rot_x(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
inline Eigen::Matrix3d rot_y(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
inline Eigen::Matrix3d rot_z(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

// ---- The MuJoCo model (mujoco_model.cpp).
Pose pose_from_mj(const mjtNum pos[3], const mjtNum quat[4]);
Pose body_local_pose(const mjModel* m, int b);
// Pose of body b in the world with all joints at zero (composition of body offsets; joints are
// checked to be absent or at their zero position by the callers).
Pose body_world_pose_static(const mjModel* m, int b);
struct MjModelDeleter {
  void operator()(mjModel* m) const { if (m) mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { if (d) mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using DataPtr = std::unique_ptr<mjData, MjDataDeleter>;
// The MJCF file loaded by MuJoCo (loads serialised: the parser keeps global state); throws
// naming the file.
ModelPtr load_mj_model(const std::string& path);
// Throws std::runtime_error "rig model <path>: <what>".
[[noreturn]] void fail(const std::string& path, const std::string& what);

// ---- Kinematics (kinematics.cpp).
using Matrix6d = Eigen::Matrix<double, 6, 6>;
// Flange in the base frame and the geometric Jacobian (rows: linear velocity of the flange
// origin, angular velocity; base frame). Rotation and translation kept apart (no 4x4 products).
Pose chain_fk_jacobian(const RigModel& rig, const Vector6d& q, Matrix6d* jac);
// True when every joint is within its limits; else false with the first joint out in *bad_joint.
bool within_limits(const RigModel& rig, const Vector6d& q, int* bad_joint = nullptr);
// Adds q (and its +-2*pi variants of revolute joints whose range allows them) to `out` when
// within limits; otherwise records the first violation.
void expand_variants(const RigModel& rig, const Vector6d& q, const std::array<bool, 6>& revolute,
                     std::vector<Vector6d>* out, std::string* first_violation);
// Pose error (position m, rotation rad).
std::pair<double, double> pose_error(const Pose& a, const Pose& b);
// The value of joint i equal to v up to whole turns, within the limits, nearest `reference`
// (v itself when no other turn fits).
double nearest_in_limits(const RigModel& rig, int i, double v, double reference);
// Same configuration up to whole turns of each joint.
bool same_modulo_turns(const Vector6d& a, const Vector6d& b);

// ---- Inverse kinematics (ik.cpp: the dispatch, the analytic and the free rig's;
// general_ik.cpp: any 6R chain).

// LM stops when its error has not fallen below this fraction of itself within kStallWindow
// iterations (general_ik.cpp): the reachability check gives up early, the full search late.
inline constexpr double kStallRatioFast = 0.25;
inline constexpr double kStallRatioFull = 0.9;
// ReachabilityChecker: spread seeds when the near seeds give no collision-free solution.
inline constexpr int kReachSpreadSeeds = 6;
// A raw IK solution wrapped into (-pi, pi], checked against the pose by forward kinematics
// (polished when a little off); nullopt when far off.
std::optional<Vector6d> verified_arm_solution(const RigModel& rig, const Pose& world_T_flange, const Vector6d& raw);
// An arm's raw IK solutions checked against the pose by forward kinematics (polished when a
// little off, dropped when far) and expanded into their whole-turn variants within the joint
// limits, without duplicates; when none is left, why_none says which limit the raw ones broke.
std::vector<Vector6d> checked_arm_solutions(const RigModel& rig, const Pose& world_T_flange,
                                            const std::vector<Vector6d>& raw, std::string* why_none);
// The closed-form IK of the parallel-axes (UR) layout, parallel_ik.cpp; throws
// std::invalid_argument naming the file when the chain does not have the layout.
std::vector<Vector6d> parallel_axes_ik(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                                       std::string* why_none);
// The same solutions, each once, in its whole-turn variant nearest q_ref (what the
// reachability check needs: whole turns share the geometry); empty with the reason when none is
// within the limits.
std::vector<Vector6d> parallel_axes_ik_nearest(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                                               std::string* why_none);
// True when the chain has the parallel-axes layout and configurations spread over its joint
// ranges come back through parallel_axes_ik (load_rig's test).
bool parallel_axes_layout(const RigModel& rig);
// The IK solutions of the rig's method; q_ref resolves free angles at singularities and seeds
// the general IK. Empty with the reason in *why_none when there is none.
std::vector<Vector6d> ik_with_ref(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                                  std::string* why_none);
std::vector<Vector6d> arm_ik(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                             std::string* why_none);
std::vector<Vector6d> free_ik(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                              std::string* why_none);
std::vector<Vector6d> general_ik(const RigModel& rig, const Pose& world_T_flange, const Vector6d& q_ref,
                                 std::string* why_none);
// One general IK solve from `seed` (LM, stalled below stall_ratio), verified and within limits.
bool general_ik_seed(const RigModel& rig, const Pose& world_T_flange, const Vector6d& seed, double stall_ratio,
                     Vector6d* q);
// Quasi-random configurations spread over the joint ranges (Halton sequence; ranges wider than
// one turn cut to +-pi, other turns being the same geometry).
std::vector<Vector6d> spread_seeds(const RigModel& rig, int n);
// "out of reach" reason when the flange pose is provably beyond the chain's reach, else "".
std::string general_out_of_reach(const RigModel& rig, const Pose& base_T_target);

}  // namespace pbnbv::rig_internal
