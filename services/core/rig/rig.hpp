#pragma once
// The rig as plain data read from its MJCF file (models/rig_arm.xml, rig_ur5e.xml, rig_free.xml), and
// its kinematics: forward kinematics along the arm's joint chain, inverse kinematics (closed form
// for the spherical-wrist layout, damped least squares for any other 6R chain), the split of a requested
// camera pose into a turntable angle and an arm configuration, and the reachability check
// (IK + joint limits + MuJoCo collision check against table, turntable, pedestal and the object
// keep-out box). The same file describes the twin and a calibrated real rig; services read the
// kinematics from here, never from the twin's state.
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/base/setting.hpp"
#include "core/geometry/rig_kind.hpp"
#include "core/geometry/working_volume.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/lens_distortion.hpp"
#include "core/geometry/depth_sensor.hpp"

namespace pbnbv {

// A joint's acceleration limit when the rig file states none, as a multiple of its speed limit
// per second: full speed within a quarter of a second, about what industrial arms and turntables
// reach at their default acceleration.
inline constexpr double kAccelerationPerSpeed = 4.0;

// Lengths of a spherical-wrist 6R arm with the KUKA joint layout (axes z, y, y, x, y, x at
// zero), metres: base->A2 (a1 forward, d1 up), A2->A3 (a2), A3->wrist (a3 up, d4 forward),
// wrist centre -> flange (d6). Set only when the chain has this layout (the analytic IK).
struct ArmGeometry {
  double a1 = 0, d1 = 0, a2 = 0, a3 = 0, d4 = 0, d6 = 0;
};

// The depth camera the rig carries, as its rig file states it (optional): what a driver's
// DEPTH_FRAME must match (pbnbv rig-check). MJCF:
//   <custom><numeric name="pbnbv_camera" data="width height fx fy cx cy depth_min depth_max"/>
//           <text name="pbnbv_camera_id" data="SERIAL"/>            (the id is optional)
//           <text name="pbnbv_camera_model" data="d435"/></custom>   (optional: the twin plays
//                                                  this camera, core/geometry/depth_sensor.hpp)
struct RigCamera {
  CameraIntrinsics intrinsics;  // pixels
  DepthRange range;             // metres, planar depth
  std::string id;               // the camera's serial / id; "" = any
  std::optional<CameraKind> model;  // the named camera (its image and depth errors in the twin)
  LensDistortion distortion;        // <custom><numeric name="pbnbv_camera_distortion" data="k1 k2
                                    // p1 p2 k3"> (OpenCV's order): the lens its frames come through
};

// One joint of the arm's serial chain, as the MJCF body tree gives it (all joints at zero).
struct ChainJoint {
  Pose parent_T_body = Pose::Identity();  // this joint's body in the previous joint's body (the
                                          // base for the first), fixed bodies between folded in
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();     // unit hinge axis, body frame
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();    // a point on the axis, body frame, m
};

// How inverse_kinematics solves an arm: closed form for the spherical-wrist layout above
// (kAnalytic); closed form for the parallel-axes layout of the Universal Robots arms (kParallelAxes:
// joints 2-4 parallel, axes 4-5 and 5-6 meeting, any offsets and joint directions; up to 8
// solutions); or damped least squares on the chain's geometric Jacobian (kGeneral: any 6R chain).
// load_rig picks the first whose layout the chain has; a rig whose calibration moved an axis off
// the layout falls back to kGeneral.
enum class IkMethod { kAnalytic, kParallelAxes, kGeneral };

struct RigModel {
  RigKind kind = RigKind::kArm;
  std::string model_path;
  std::string arm_name;                   // e.g. "KUKA KR 10 R1100 sixx"
  std::vector<std::string> joint_names;   // 6 arm (or gantry) joints, base to flange
  Vector6d q_lower, q_upper;              // joint limits, rad (m for gantry slides)
  Vector6d qd_max;                        // joint speed limits, rad/s (m/s)
  Vector6d qdd_max;                       // joint acceleration limits, rad/s^2 (m/s^2):
                                          // <custom><numeric name="pbnbv_joint_acceleration_limits">
                                          // (optional; default kAccelerationPerSpeed x qd_max)
  Vector6d q_home;                        // a safe start configuration
  std::array<ChainJoint, 6> chain{};      // kArm: base -> joint bodies (forward kinematics)
  Pose last_T_flange = Pose::Identity();  // kArm: flange in the last joint's body
  bool spherical_wrist = false;           // kArm: the chain has the ArmGeometry layout
  IkMethod ik = IkMethod::kGeneral;       // kArm: kAnalytic when spherical_wrist, kParallelAxes
                                          // for that layout (set on load); a caller may set
                                          // kGeneral to force the general IK
  ArmGeometry arm;                        // kArm with spherical_wrist only
  Pose world_T_base = Pose::Identity();   // arm base (A1 axis at the floor of link 1)
  Pose flange_T_camera = Pose::Identity(); // hand-eye: optical frame in the flange frame
  bool has_turntable = false;
  double turntable_qd_max = 0;            // rad/s
  double turntable_qdd_max = 0;           // rad/s^2: "pbnbv_turntable_acceleration_limit"
                                          // (optional; default kAccelerationPerSpeed x turntable_qd_max)
  Pose world_T_turntable = Pose::Identity();  // turntable top centre at angle 0, z = axis
  double preferred_azimuth_rad = 0;       // world azimuth about the turntable axis where the
                                          // arm sees best (towards the arm base)
  double turntable_zero_rad = 0;          // the turntable's reading when the platter is at its
                                          // zero (the calibration mark on its +x axis), rad:
                                          // <custom><numeric name="pbnbv_turntable_zero">
                                          // (optional, 0; written by `pbnbv calibrate`)
  // Where an unknown object may be (<custom><text name="pbnbv_working_volume"
  // data="cylinder:R,H"/> or "box:X,Y,Z"); without it, working_volume_of() derives one from the
  // turntable.
  std::optional<WorkingVolume> working_volume;
  double turntable_radius_m = 0;          // the platter's radius (geom "platter"); 0: no platter
  std::optional<RigCamera> camera;        // none: the rig file states no camera
};

// The rig file's working volume, or one derived from the turntable: a cylinder 1.25 times the
// platter's radius (objects may overhang it a little) and twice as tall as that radius is long
// (without a platter: radius 0.25 m, height 0.5 m).
WorkingVolume working_volume_of(const RigModel& rig);

// Reads the rig from its MJCF file. An arm is any serial chain of 6 hinge joints from a static
// body to body "flange" (named in order base to flange); the spherical-wrist layout is detected.
// Throws std::runtime_error naming the file and what is wrong (missing file, MuJoCo parse
// error, missing body, a chain of the wrong length or with a slide joint, no joint range).
RigModel load_rig(const std::string& mjcf_path);

// models/rig_<kind>.xml under the installed models directory.
std::string default_rig_path(RigKind kind);
// A file under the installed models directory (e.g. "rig_ur5e.xml").
std::string model_file_path(const std::string& file_name);

// Forward kinematics.
Pose flange_in_world(const RigModel& rig, const Vector6d& q);
Pose camera_in_world(const RigModel& rig, const Vector6d& q);
// Object frame in the world: turntable top frame turned by `turntable_rad` (a reading: minus
// turntable_zero_rad) about its axis and lifted by `object_z_m` along it. Free rig: identity (the object floats at the world origin).
Pose object_in_world(const RigModel& rig, double turntable_rad, double object_z_m);
// Camera (optical frame) in the object frame, from joint and turntable readings.
Pose camera_in_object(const RigModel& rig, const Vector6d& q, double turntable_rad,
                      double object_z_m);

// All inverse kinematics solutions of the flange pose within joint limits (including the
// +-2*pi variants of joints whose range allows them), each verified by forward kinematics to
// 1e-6 m / 1e-6 rad. Empty when none exists. `why_none` (optional) receives the reason.
// The general IK (rig.ik == kGeneral) finds the solutions it converges to from `q_ref` first,
// home, and spread seeds: all of them for common arms, but not provably all.
std::vector<Vector6d> inverse_kinematics(const RigModel& rig, const Pose& world_T_flange,
                                         std::string* why_none = nullptr,
                                         const Vector6d& q_ref = Vector6d::Zero());

// General IK from one seed: damped least squares on the chain's Jacobian, joint limits
// respected. True (and *q set, verified by FK to 1e-6 m / 1e-6 rad) when it converged.
bool general_ik_from_seed(const RigModel& rig, const Pose& world_T_flange, const Vector6d& seed,
                          Vector6d* q);

// Where the rig stands: the arm's joints and the turntable's reading.
struct RigState {
  Vector6d q = Vector6d::Zero();
  double turntable_rad = 0;
};

// Rig time: a move as the rig's drivers execute it (the twin does exactly this; an arm's movej
// and a turntable's positioning move are close): each joint group (the arm's 6 joints together,
// the turntable on its own) follows a smoothstep ramp from rest to rest, whose peak speed (1.5 x
// the mean) stays within every joint's speed limit and whose peak acceleration (6 distance / T^2)
// within its acceleration limit, both scaled by `speed_scale`; the arm's joints arrive together
// (the slowest sets the time); the arm and the turntable move at once (the slower decides).
// Seconds of real time. 0 for no distance.
double ramp_duration_s(double distance, double speed_limit, double accel_limit);
double arm_move_s(const RigModel& rig, const Vector6d& from, const Vector6d& to, double speed_scale = 1.0);
double turntable_move_s(const RigModel& rig, double from_rad, double to_rad, double speed_scale = 1.0);
double move_s(const RigModel& rig, const RigState& from, const RigState& to, double speed_scale = 1.0);
// The moves through `stops` in turn, from `from`.
double path_s(const RigModel& rig, const RigState& from, const std::vector<RigState>& stops, double speed_scale = 1.0);

// The path check's step: no point of the arm moves farther between two checked states, m (below
// the check's 5 mm clearance, so that between samples at least 3 mm remain).
inline constexpr double kPathStepM = 0.004;
// How far a detour backs the camera off along its view axis (and twice that), m.
inline constexpr double kPathRetreatM = 0.2;

// A path the rig can take to a view: the states it stops at in order (the last one the view's),
// each reached from the one before by one move of both joint groups (see move_s).
struct RigPath {
  bool clear = false;
  std::vector<RigState> stops;  // excludes where the rig starts
  double time_s = 0;            // the moves' time at full speed, s
  std::string route;            // "direct", "retreat 0.20 m, turn, approach", "via home", ...
  std::string reason;           // !clear: why every route collides (each route's first contact)
};

// A requested view split into a turntable angle and an arm configuration.
struct ViewSolution {
  bool reachable = false;
  std::string reason;                      // why not, when !reachable (e.g. which joint limit,
                                           // which bodies collide, how far out of reach)
  Vector6d q = Vector6d::Zero();
  double turntable_rad = 0;
  Pose world_T_camera = Pose::Identity();  // by forward kinematics of the solution
};

// Owns a MuJoCo model/data of the rig for collision checks; not thread-safe (one per thread).
// `keepout`: the object's keep-out volume, an axis-aligned box in the object frame that the rig
// must not enter and whose corners must be in sight; an empty or flat box: none.
class ReachabilityChecker {
 public:
  explicit ReachabilityChecker(const RigModel& rig, TurntableChoice choice = TurntableChoice::kPreferred);
  ~ReachabilityChecker();
  void set_turntable_choice(TurntableChoice choice);
  TurntableChoice turntable_choice() const;
  ReachabilityChecker(const ReachabilityChecker&) = delete;
  ReachabilityChecker& operator=(const ReachabilityChecker&) = delete;

  // Splits object_T_camera into a turntable angle (see TurntableChoice; each angle taken in its
  // equivalent nearest `turntable_current`) and the IK solution nearest `q_current` within joint
  // limits that collides with nothing. Free rig: the gantry configuration, turntable 0.
  ViewSolution solve(const Pose& object_T_camera, const Vector6d& q_current,
                     double turntable_current, const Eigen::AlignedBox3d& keepout, double object_z_m);

  // solve() for each pose (a planner's candidate views), same current state, but with kLeastTurn
  // and kQuickest each on the grid of azimuth offsets alone (solve narrows the least turn further:
  // TurntableChoice).
  std::vector<ViewSolution> solve_batch(const std::vector<Pose>& object_T_cameras,
                                        const Vector6d& q_current, double turntable_current,
                                        const Eigen::AlignedBox3d& keepout, double object_z_m);

  // The first collision on the straight joint-space move from `from` to `to` ("link_6 / platter
  // at 40 % of the move"), "" when the whole move is clear. The move is sampled so that no point
  // of the arm moves more than kPathStepM between samples (bounded by each joint's turn times the
  // farthest any part it carries reaches from its axis), and each sample is checked with the
  // clearance kContactMargin: between samples nothing comes nearer than the margin minus half the
  // step. When the turntable turns during the move the keep-out box is checked as the cylinder
  // about the turntable axis that it sweeps turning through any angle, so the turntable's timing
  // against the arm's does not matter.
  std::string path_collision(const RigState& from, const RigState& to, const Eigen::AlignedBox3d& keepout,
                             double object_z_m);

  // A collision-free path from `from` to the view's state `to`: the direct move when it is clear,
  // else the quickest clear one of: retreat along the camera's view axis (0.2 m, then 0.4 m),
  // turn the turntable, approach along the view's axis; via the home configuration; retreat,
  // home, approach. Free rig: direct (the gantry flies). !clear when every route collides.
  RigPath plan_path(const RigState& from, const RigState& to, const Eigen::AlignedBox3d& keepout,
                    double object_z_m);

  // The rig's fixed parts (its solid geoms welded to the world: the table, the pedestal, the arm's
  // base) that an object turning on the turntable would strike: the cylinder about the turntable
  // axis of radius `radius_m` from `bottom_z_m` + kTurningLiftM to `top_z_m` (object frame, whose
  // origin is object_z_m above the platter top: the object stands on the platter, and what lies
  // under the platter's top cannot be struck), each part within kContactMargin of it, by name.
  // Empty: clear; the free rig and a rig without a turntable: always.
  static constexpr double kTurningLiftM = 0.01;
  std::vector<std::string> turning_collisions(double radius_m, double bottom_z_m, double top_z_m, double object_z_m);

  // Names of colliding geom pairs ("link_4 / table") at this configuration; empty = free.
  std::vector<std::string> collisions(const Vector6d& q, double turntable_rad,
                                      const Eigen::AlignedBox3d& keepout, double object_z_m);

 private:
  struct Impl;
  struct AngleSearch;  // solve()'s search at one turntable angle
  // solve(), narrowing a least turn (TurntableChoice::kLeastTurn, kQuickest) when `narrow_turn`; solve_batch
  // keeps the grid's angles.
  ViewSolution solve_view(const Pose& object_T_camera, const Vector6d& q_current, double turntable_current,
                          const Eigen::AlignedBox3d& keepout, double object_z_m, bool narrow_turn);
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbnbv
