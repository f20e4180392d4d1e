#pragma once
// The simulated rig without the bus: the rig's MJCF with the object inserted, stepped by
// MuJoCo physics. Joints follow speed-limited smooth ramps to their targets (all joints of a
// command arriving together); the model's position actuators track the ramp, helped, as an
// industrial controller is, by gravity compensation and velocity/acceleration feed-forward
// (joint damping and inertia times the ramp's velocity and acceleration); a joint group is
// "settled" when it is at its target and still. Every state is checked for contacts between the
// arm and the rest of the rig (twin/contact_monitor.hpp): on a contact the rig stops, as a real
// arm's collision detection stops it.
#include <mujoco/mujoco.h>

#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <array>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/colour_image.hpp"
#include "core/geometry/mesh.hpp"
#include "core/rig/rig.hpp"
#include "twin/contact_monitor.hpp"

namespace pbnbv::twin {

// The object as the twin places it: a mesh already in the normalised object frame, whose
// frame sits object_z_m above the turntable top (free rig: at the world origin).
// A part of the object drawn in its own colour (MuJoCo 2.2.2 draws a mesh in one colour).
struct ObjectColourPart {
  std::string mesh_path;              // binary STL, in the composed model's folder
  std::array<double, 3> rgb{};        // 0..1
  std::size_t triangles = 0;
};

struct ObjectPlacement {
  std::string mesh_path;  // binary STL or OBJ in the object frame; "" = empty rig
  double object_z_m = 0;
  // The calibration sphere (pbnbv calibrate): radius (0 = none), resting on the platter top with
  // its centre above the platter's +x axis, this far from the turntable axis (the mark).
  double calibration_sphere_radius_m = 0;
  double calibration_sphere_offset_m = 0;
  // Drawn instead of the mesh, which then only collides (group 3): its faces in their colours
  // (split_by_colour). Empty: the mesh is drawn in one colour.
  std::vector<ObjectColourPart> colour_parts;
};

// A mesh with a colour per vertex as parts of one colour each: its faces grouped by their
// vertices' mean colour quantised to `levels` steps per channel, each group written as binary STL
// `<stem>_colour_N.stl` in `dir`, its colour the mean of its faces'. Largest group first.
// Throws std::invalid_argument when the colours are not one per vertex.
std::vector<ObjectColourPart> split_by_colour(const TriangleMesh& mesh, const std::vector<Rgb>& vertex_colours,
                                              const std::string& dir, const std::string& stem, int levels = 4);

// Reads the rig's MJCF text and returns it with the object's asset and geom (and the calibration
// sphere's geom, a native MuJoCo sphere) inserted at the PBNBV_OBJECT_ASSET / PBNBV_OBJECT_GEOM
// markers. Throws std::runtime_error naming the file
// when a marker is missing.
std::string compose_model_xml(const std::string& rig_xml_path, const ObjectPlacement& object);

// How the twin's kinematics differ from the rig model the services use, so that kinematic
// camera poses are wrong the way a real rig's are (off by default):
//  - the true hand-eye transform is the model's times a fixed error (in the camera frame);
//  - the turntable reports its angle with a fixed offset;
//  - each joint reports its angle with an offset drawn anew (Gaussian) at every arm command.
// Reported = true + offset, and the rig servos so that the reported angle reaches the command.
struct PoseErrorModel {
  Pose hand_eye_error = Pose::Identity();  // true flange_T_camera = model's * hand_eye_error
  double turntable_offset_rad = 0;          // reported - true
  double joint_sigma_rad = 0;               // per-command reported - true, standard deviation
  // The platter stops half of this short of the encoder's angle, against the direction it turned
  // (reported - true = offset + or - backlash / 2, after the first turn).
  double turntable_backlash_rad = 0;
  uint64_t seed = 1;
  bool enabled() const;
};

// A hand-eye error of the given size in a random direction (translation) and about a random
// axis (rotation), deterministic for the seed, plus the turntable and joint errors.
PoseErrorModel make_pose_error(double hand_eye_m, double hand_eye_rad, double turntable_rad,
                               double joint_sigma_rad, uint64_t seed);

// The most one TURNTABLE_COMMAND may turn the turntable from its setpoint, rad (one full turn).
inline constexpr double kMaxTurntableTurnRad = 2 * 3.14159265358979323846;

// A command target outside its joint's limits (the twin reports kFaultOutOfLimits; other
// std::invalid_argument from a command: kFaultCommandRejected).
struct OutOfLimits : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// A group of joints moving together under one command (the arm's 6, or the turntable).
struct JointGroup {
  std::vector<int> qpos_adr;   // addresses in qpos
  std::vector<int> dof_adr;    // addresses in qvel
  std::vector<int> actuator;   // position actuator per joint
  std::vector<double> speed_limit;  // per joint, rad/s (m/s)
  std::vector<double> accel_limit;  // per joint, rad/s^2 (m/s^2)
  std::vector<double> lower, upper; // joint limits
  std::vector<std::string> names;
  // Ramp state: the setpoint follows a cubic (smoothstep) profile from start to target over
  // [t0, t1]: zero velocity at both ends, peak velocity 1.5 x the mean, kept within the limits.
  std::vector<double> start, target, setpoint, setpoint_velocity, setpoint_acceleration;
  double t0 = 0, t1 = 0;
  long command_seq = -1;
  bool ramping = false;
};

class RigSim {
 public:
  // Loads the composed model (written to `model_out_path`, kept for users to open in MuJoCo's
  // viewer). Throws std::runtime_error with MuJoCo's error text.
  RigSim(const RigModel& rig, const ObjectPlacement& object, const std::string& model_out_path,
         const PoseErrorModel& errors = PoseErrorModel{});
  ~RigSim();
  RigSim(const RigSim&) = delete;
  RigSim& operator=(const RigSim&) = delete;

  // Starts a synchronised ramp to `target` at `speed_scale` of the limits. Throws OutOfLimits
  // naming the joint when a target is outside its limits, std::invalid_argument when it is not
  // finite or speed_scale is outside (0, 1] (the command is then ignored: the rig keeps holding;
  // the twin reports it in the status as kFaultOutOfLimits / kFaultCommandRejected with the
  // command's seq).
  void command_arm(const Vector6d& target, double speed_scale, long seq);
  void command_turntable(double target_rad, double speed_scale, long seq);
  void hold_arm(long seq);  // stop where it is
  // A faulty driver (pbnbv-twin --fault ignore-limits): targets outside the joint limits are
  // executed (the joints stop at their mechanical limits) and speed_scale is clamped into (0, 1].
  void set_ignore_limits(bool on) { ignore_limits_ = on; }

  // Advances physics by one timestep, and checks the states it went through for contacts
  // (ContactMonitor, swept unless the rig teleports). On a contact's onset the rig makes a
  // protective stop: the arm holds where it is (its command_seq kept: the command it was
  // executing), and so does the turntable (one safety circuit for the cell: a turntable turning
  // the object into the camera stops too); the next command moves it again.
  // A rig at rest (no ramp running, every joint still: under 1e-6 rad/s or m/s) is held without a
  // physics step: the clock advances alone until a command wakes it (rest_steps counts them).
  void step();
  double time_s() const;
  bool at_rest() const;
  int64_t rest_steps() const { return rest_steps_; }

  Vector6d arm_position() const;  // true joint angles
  Vector6d arm_velocity() const;
  // What the rig's encoders report (true + the pose-error model's offsets).
  Vector6d arm_position_reported() const { return arm_position() + joint_offset_; }
  double turntable_angle_reported() const { return turntable_angle() + errors_.turntable_offset_rad + turntable_lag_rad_; }
  // What the backlash leaves between the encoder and the platter now (reported - true - offset).
  double turntable_lag_rad() const { return turntable_lag_rad_; }
  // True optical-frame camera pose in the true object frame (for evaluation only: the
  // pipeline never sees it).
  Pose true_camera_in_object(double object_z_m) const;
  const JointGroup& arm() const { return arm_; }
  bool has_turntable() const { return turntable_.has_value(); }
  const JointGroup& turntable() const { return *turntable_; }
  double turntable_angle() const;
  double turntable_velocity() const;
  bool settled(const JointGroup& g) const;  // ramp done, |q - target| and |qd| small
  bool moving(const JointGroup& g) const { return g.ramping || !settled(g); }

  mjModel* model() { return m_; }
  mjData* data() { return d_; }

  // Contact events since the rig was made (a start in contact included), the last one, and the
  // ones the driver has not taken yet (each taken once, in order).
  int64_t contact_events() const { return contacts_->events(); }
  const std::optional<RigContact>& last_contact() const { return last_contact_; }
  std::vector<RigContact> take_contacts();
  const ContactMonitor& contact_monitor() const { return *contacts_; }

 private:
  void start_ramp(JointGroup& g, const std::vector<double>& target, double speed_scale, long seq);
  void advance_ramp(JointGroup& g);
  void protective_stop();
  JointGroup make_group(const std::vector<std::string>& joints, const std::vector<double>& speeds,
                        const std::vector<double>& accelerations);

  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  PoseErrorModel errors_;
  Vector6d joint_offset_ = Vector6d::Zero();
  double turntable_lag_rad_ = 0;
  std::mt19937_64 rng_;
  JointGroup arm_;
  std::optional<JointGroup> turntable_;
  // The free rig teleports (the paper's comparison setup): a command's ramp takes no time and
  // the gantry's joints sit exactly at their setpoints, so a view's camera pose is the commanded
  // one to the bit and a benchmark scan's plans do not depend on the machine's timing.
  bool teleport_ = false;
  bool ignore_limits_ = false;
  std::unique_ptr<ContactMonitor> contacts_;
  std::optional<RigContact> last_contact_;
  std::vector<RigContact> untaken_contacts_;
  int64_t rest_steps_ = 0;
};

}  // namespace pbnbv::twin
