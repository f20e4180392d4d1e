// pbnbv-twin: the simulated rig. Plays the physical arm, turntable and depth camera and speaks
// only the rig channels, exactly as real drivers would:
//   in:  ARM_COMMAND, TURNTABLE_COMMAND, DEPTH_TRIGGER
//   out: ARM_STATUS, TURNTABLE_STATUS (every 10 ms of rig time), DEPTH_FRAME (per trigger),
//        HEARTBEAT
// With --rtde-port it plays a Universal Robots controller for the arm instead (pbnbv-ur-driver
// speaks for the arm on the bus; twin/ur_controller.hpp): RTDE and the driver's program in, the
// controller's state out; the turntable and the camera stay on the bus.
// The reference driver of the contract, built on the driver library (services/driver; README
// "Writing a driver"): the checks, faults, statuses and frames are the library's; --fault makes it a faulty one
// (twin/driver_faults.hpp), for `pbnbv rig-check`'s tests.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <iostream>
#include <random>
#include <thread>

#include "bus/bus.hpp"
#include "bus/colour_codec.hpp"
#include "bus/convert.hpp"
#include "bus/rig_options.hpp"
#include "cli/options.hpp"
#include "core/scan/scan_options.hpp"
#include "core/base/log.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "core/rig/calibration.hpp"
#include "core/rig/rig.hpp"
#include "twin/depth_renderer.hpp"
#include "twin/sensor_sim.hpp"
#include "core/geometry/depth_sensor.hpp"
#include "twin/driver_faults.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "twin/rig_sim.hpp"
#include "twin/ur_controller.hpp"
#include "driver/ur_arm.hpp"
#include "driver/rig_driver.hpp"
#include "core/base/units.hpp"

using namespace pbnbv;

namespace {

constexpr double kSlowStatusPeriodS = 0.05;  // --fault slow-status: 20 Hz
constexpr double kDepthUnitM = 1e-4;     // 0.1 mm per count
constexpr const char* kCameraId = "pbnbv-twin";  // depth_frame_t camera_id

int64_t rig_utime(int64_t epoch_utime, double sim_s) {
  return epoch_utime + static_cast<int64_t>(std::llround(sim_s * 1e6));
}

// A joint group's motion as the contract reports it: idle before its first command, settled at
// its target, else moving.
driver::Motion motion_of(const twin::RigSim& sim, const twin::JointGroup& g) {
  if (g.command_seq < 0 && sim.settled(g)) return driver::Motion::kIdle;
  return sim.settled(g) ? driver::Motion::kSettled : driver::Motion::kMoving;
}

// What the command line sets.
struct TwinOptions {
  bus::RigOptions rig;
  twin::ObjectPlacement object;
  std::string model_out = "twin_model.xml";
  CameraIntrinsics k;
  std::optional<double> cx, cy;
  DepthRange range;
  CameraKind camera = kCamera.value;
  twin::DepthNoise noise;
  int64_t noise_seed = 0;
  double speed = 0;
  double hand_eye_error_mm = 0, hand_eye_error_deg = 0, turntable_error_deg = 0, joint_error_deg = 0;
  double turntable_backlash_deg = 0;
  int64_t error_seed = 0;
  std::string scope;
  bool raw_depth = false;
  std::string truth_path;
  std::vector<twin::DriverFault> faults;
  int64_t rtde_port = 0;         // 0: the arm on the bus; else a UR controller's RTDE port
  int64_t ur_script_port = driver::ur::kScriptPort;
  std::string truth_rig_path;
  std::string distortion_text;  // --distortion k1,k2,p1,p2,k3 ("": the rig file's camera's, else none)
  LensDistortion distortion;    // the lens frames are taken through (main fills it in)
  CameraIntrinsics render_k;    // what the renderer draws: k, or the pinhole image covering the lens's
  bool no_colour = false;       // frames without their colour image
  double colour_scale = 0.5;    // the colour image's size against the depth image's
  CameraIntrinsics colour_k;    // the colour sensor's (main fills it in)
  std::string colour_offset_text;  // --colour-offset x,y,z mm
  Pose depth_T_colour = Pose::Identity();  // the colour sensor in the depth sensor's optical frame

  bool faulty(twin::DriverFault f) const { return twin::has_fault(faults, f); }
};

void add_options(CLI::App& app, TwinOptions& o) {
  bus::add_rig_options(app, &o.rig);
  cli::add_text(app, "mesh", &o.object.mesh_path, "object mesh in the normalised object frame (binary STL or OBJ)", "PATH");
  cli::add(app, Setting<double>{"object-z", 0.0, -1.0, 2.0, "m", "object frame origin above the turntable top"},
           &o.object.object_z_m);
  cli::add(app, kSphereRadius.renamed("calibration-sphere", "put the calibration sphere of this radius on the platter "
                                      "mark (0: none; see pbnbv calibrate)").with_default(0.0),
           &o.object.calibration_sphere_radius_m);
  o.object.calibration_sphere_offset_m = kSphereOffset.value;
  cli::add(app, kSphereOffset.renamed("calibration-sphere-offset", "the calibration sphere's centre from the turntable axis, "
                                      "on the platter's +x axis"),
           &o.object.calibration_sphere_offset_m);
  cli::add_text(app, "model-out", &o.model_out, "where to write the composed model", "PATH");
  cli::add(app, kCamera, &o.camera);
  cli::add(app, kImageWidth, &o.k.width);
  cli::add(app, kImageHeight, &o.k.height);
  cli::add(app, kFocalX, &o.k.fx);
  cli::add(app, kFocalY, &o.k.fy);
  cli::add(app, kPrincipalX, &o.cx, "width / 2");
  cli::add(app, kPrincipalY, &o.cy, "height / 2");
  cli::add(app, kDepthMin, &o.range.min_m);
  cli::add(app, kDepthMax, &o.range.max_m);
  cli::add(app, kDepthNoise, &o.noise.sigma_per_m);
  cli::add(app, kDropout, &o.noise.dropout);
  cli::add(app, Setting<int64_t>{"seed", 1, 0, int64_t{1} << 40, "", "depth noise seed"}, &o.noise_seed);
  // Run by hand the twin keeps real time, as the rig it stands for; `pbnbv scan` asks for
  // --sim-speed (4 by default).
  cli::add(app, kSimSpeed.renamed("speed", "simulation speed, multiple of real time").with_default(1.0), &o.speed);
  cli::add(app, kHandEyeErrorMm, &o.hand_eye_error_mm);
  cli::add(app, kHandEyeErrorDeg, &o.hand_eye_error_deg);
  cli::add(app, kTurntableErrorDeg, &o.turntable_error_deg);
  cli::add(app, kJointErrorDeg, &o.joint_error_deg);
  cli::add(app, kTurntableBacklashDeg, &o.turntable_backlash_deg);
  cli::add(app, kErrorSeed, &o.error_seed);
  cli::add_text(app, "scan", &o.scope,
                "play the rig of this scan only: commands and triggers of other scans are ignored and counted "
                "(default: obey every command, as a real driver does)",
                "ID");
  cli::add_flag(app, "raw-depth", &o.raw_depth,
                "send depth frames uncompressed (encoding raw; default zlib: 20x smaller, survives packet loss)");
  cli::add_text(app, "truth-out", &o.truth_path,
                "append each frame's true camera pose to this file (JSON lines; evaluation only)", "PATH");
  cli::add_list(app, "fault", &o.faults,
                "play a faulty driver, for pbnbv rig-check's tests: slow-status (20 Hz), no-seq-echo, depth-unit-mm "
                "(counts in mm, unit field 0.1 mm), no-trigger-id, ignore-limits (executes out-of-limit commands), "
                "utime-backwards, late-exposure (frames stamped 1 s late); with --rtde-port: rtde-drop (the RTDE "
                "connection closed once, 2 s after the first move starts), protective-stop (the second move stops "
                "halfway in a protective stop, safety mode 3, and stays there)");
  cli::add(app, Setting<int64_t>{"rtde-port", 0, 0, 65535, "",
                                 "play a Universal Robots controller for the arm: RTDE on 127.0.0.1 at this port for "
                                 "pbnbv-ur-driver (no ARM_COMMAND / ARM_STATUS on the bus; 0: the arm on the bus)"},
           &o.rtde_port);
  cli::add(app, Setting<int64_t>{"ur-script-port", driver::ur::kScriptPort, 1, 65535, "",
                                 "with --rtde-port: take the driver's URScript program on 127.0.0.1 at this port"},
           &o.ur_script_port);
  cli::add_text(app, "distortion", &o.distortion_text,
                "render through this lens: Brown-Conrady k1,k2,p1,p2,k3 (OpenCV's order); the frames say so "
                "(default: the rig file's pbnbv_camera_distortion, else none)",
                "K1,K2,P1,P2,K3");
  cli::add_flag(app, "no-colour", &o.no_colour,
                "send depth frames without their colour image (default: each frame carries the colour image the "
                "camera took with it, JPEG, or raw R G B with --raw-depth)");
  cli::add(app, Setting<double>{"colour-scale", 0.5, 0.25, 1.0, "",
                                "the colour image's size against the depth image's (its own intrinsics: the depth "
                                "camera's scaled; 0.5 renders a quarter of the pixels)"},
           &o.colour_scale);
  cli::add_text(app, "colour-offset", &o.colour_offset_text,
                "where the colour sensor sits in the depth sensor's optical frame (x right, y down, z forward), mm: "
                "a camera with two sensors, e.g. 15,0,0 (default 0,0,0: colour registered to depth)",
                "X,Y,Z");
  cli::add_text(app, "truth-rig-out", &o.truth_rig_path,
                "write the true hand-eye transform and turntable zero to this JSON file (evaluation only)", "PATH");
}

// Checks what the options say together, and fills in what they leave to defaults.
void complete(TwinOptions& o) {
  if (!o.object.mesh_path.empty()) {
    o.object.mesh_path = std::filesystem::absolute(o.object.mesh_path).string();
    if (!std::filesystem::exists(o.object.mesh_path)) {
      throw std::invalid_argument("--mesh " + o.object.mesh_path + " does not exist");
    }
  }
  if (!o.colour_offset_text.empty()) {
    const std::optional<std::vector<double>> c = cli::detail::parse_numbers(o.colour_offset_text, 3);
    if (!c || std::abs((*c)[0]) > 200 || std::abs((*c)[1]) > 200 || std::abs((*c)[2]) > 200) {
      throw std::invalid_argument("--colour-offset '" + o.colour_offset_text +
                                  "' is not three numbers x,y,z in mm, each within 200 mm");
    }
    o.depth_T_colour = Pose::Identity();
    o.depth_T_colour.translation() = Eigen::Vector3d((*c)[0], (*c)[1], (*c)[2]) * 1e-3;
  }
  o.k.cx = o.cx.value_or(o.k.width / 2.0);
  o.k.cy = o.cy.value_or(o.k.height / 2.0);
  // The colour sensor: the depth camera's view at colour_scale (pixel centres at integers, so the
  // principal point scales about -0.5).
  const double s = o.colour_scale;
  o.colour_k = CameraIntrinsics{std::max(1, static_cast<int>(std::lround(o.k.width * s))),
                                std::max(1, static_cast<int>(std::lround(o.k.height * s))), o.k.fx * s, o.k.fy * s,
                                (o.k.cx + 0.5) * s - 0.5, (o.k.cy + 0.5) * s - 0.5};
  o.k.validate();
  o.colour_k.validate();
  o.range.validate();
  if (o.rtde_port > 0 && o.speed != 1.0) {
    throw std::invalid_argument("--rtde-port with --speed " + std::to_string(o.speed) +
                                ": a UR controller's clock runs at real time (pbnbv-ur-driver puts its timestamps on "
                                "the host's clock, where the camera's frames are), so the twin playing one runs at "
                                "--speed 1");
  }
  if (o.rtde_port > 0 && o.rtde_port == o.ur_script_port) {
    throw std::invalid_argument("--rtde-port and --ur-script-port are both " + std::to_string(o.rtde_port));
  }
  for (const twin::DriverFault f : {twin::DriverFault::kRtdeDrop, twin::DriverFault::kProtectiveStop}) {
    if (o.faulty(f) && o.rtde_port == 0) {
      throw std::invalid_argument("--fault " + std::string(name_of(f)) + " is a UR controller's: it needs --rtde-port");
    }
  }
  if (o.object.calibration_sphere_radius_m > 0 &&
      o.object.calibration_sphere_radius_m + o.object.calibration_sphere_offset_m > 0.2) {
    throw std::invalid_argument("--calibration-sphere " + std::to_string(o.object.calibration_sphere_radius_m) +
                                " m at --calibration-sphere-offset " + std::to_string(o.object.calibration_sphere_offset_m) +
                                " m reaches beyond the platter (radius 0.2 m)");
  }
}

// A PLY object (MuJoCo 2.2.2 reads STL and OBJ only) as binary STL beside the composed model,
// and, when its vertices have colours, its faces split into parts of one colour each, drawn in
// them (twin/rig_sim.hpp). Other meshes are given to MuJoCo as they are.
void prepare_object_mesh(TwinOptions& o) {
  namespace fs = std::filesystem;
  std::string ext = fs::path(o.object.mesh_path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (o.object.mesh_path.empty() || ext != ".ply") return;
  const std::string source = fs::path(o.object.mesh_path).filename().string();
  const TriangleMesh mesh = load_mesh(o.object.mesh_path);
  const std::vector<Rgb> colours = read_ply_colours(o.object.mesh_path, mesh.vertices.size());
  const fs::path dir = fs::absolute(o.model_out).parent_path();
  const std::string stem = fs::path(o.model_out).stem().string() + "_object";
  write_stl_binary(mesh, (dir / (stem + ".stl")).string());
  o.object.mesh_path = (dir / (stem + ".stl")).string();
  if (colours.empty()) return;
  o.object.colour_parts = twin::split_by_colour(mesh, colours, dir.string(), stem);
  log_info(fmt::format("object in {} colours (from the vertex colours of {})", o.object.colour_parts.size(),
                       source));
}

// --truth-rig-out: the true hand-eye transform and turntable zero, for the calibration's tests.
void write_truth_rig(const TwinOptions& o, const std::string& model_path, const RigModel& rig,
                     const twin::PoseErrorModel& errors, double turntable_error_rad) {
  nlohmann::json j;
  j["model"] = model_path;
  j["flange_T_camera"] = to_json(rig.flange_T_camera * errors.hand_eye_error);
  j["model_flange_T_camera"] = to_json(rig.flange_T_camera);
  j["turntable_zero_rad"] = errors.turntable_offset_rad;
  j["model_turntable_zero_rad"] = rig.turntable_zero_rad;
  j["turntable_error_rad"] = turntable_error_rad;
  j["turntable_axis_direction_world"] = to_json(Eigen::Vector3d(rig.world_T_turntable.linear().col(2)));
  j["turntable_axis_point_world"] = to_json(Eigen::Vector3d(rig.world_T_turntable.translation()));
  if (o.object.calibration_sphere_radius_m > 0) {
    j["calibration_sphere"] = {{"radius_m", o.object.calibration_sphere_radius_m},
                               {"offset_m", o.object.calibration_sphere_offset_m}};
  }
  write_json_atomic(j, o.truth_rig_path);
}

driver::DepthCamera camera_of(const TwinOptions& o) {
  driver::DepthCamera camera;
  camera.camera_id = kCameraId;
  camera.width = o.k.width;
  camera.height = o.k.height;
  camera.fx = o.k.fx;
  camera.fy = o.k.fy;
  camera.cx = o.k.cx;
  camera.cy = o.k.cy;
  camera.depth_min_m = o.range.min_m;
  camera.depth_max_m = o.range.max_m;
  camera.distortion = o.distortion.coefficients();
  // The camera's own unit, as its driver would send it, where its range fits 16 bits in it; else 0.1 mm.
  const DepthSensorModel& m = depth_sensor_model(o.camera);
  camera.depth_unit_m = m.depth_unit_m > 0 && o.range.max_m / m.depth_unit_m < 65535 ? m.depth_unit_m : kDepthUnitM;
  camera.compress = !o.raw_depth;
  return camera;
}

// --truth-out: a frame's true camera pose, one JSON line.
void append_truth(std::ofstream& truth, const depth_frame_t& f, const Pose& object_T_camera) {
  double p[3], q[4];
  pose_to_arrays(object_T_camera, p, q);
  truth << std::setprecision(12) << "{\"frame_seq\": " << f.seq << ", \"trigger_seq\": " << f.trigger_seq
        << ", \"utime\": " << f.utime << ", \"object_T_camera\": {\"position_m\": [" << p[0] << ", " << p[1] << ", "
        << p[2] << "], \"quat_wxyz\": [" << q[0] << ", " << q[1] << ", " << q[2] << ", " << q[3] << "]}}" << std::endl;
}

// The simulated rig on the bus: the driver library's contract over RigSim and the renderer, rig
// time paced at --speed x wall time.
class Twin {
 public:
  Twin(const TwinOptions& o, const RigModel& rig, twin::RigSim& sim, twin::DepthRenderer& renderer,
       const twin::PoseErrorModel& errors, bus::Bus& bus)
      : o_(o), rig_(rig), sim_(sim), renderer_(renderer), errors_(errors), bus_(bus), camera_(camera_of(o)),
        rng_(static_cast<uint64_t>(o.noise_seed)), epoch_(bus::now_utime()), frame_seq_(bus::now_utime()) {
    if (!o.truth_path.empty()) {
      truth_.open(o.truth_path, std::ios::app);
      if (!truth_) throw std::runtime_error("cannot write --truth-out " + o.truth_path);
    }
  }

  // Until SIGINT or SIGTERM. Rig time runs at `speed` x wall time; the loop sleeps when it is ahead.
  void run() {
    driver::RigDriver::Options options;
    options.any_speed_scale = true;  // RigSim refuses a speed scale outside (0, 1] (or clamps it: ignore-limits)
    options.no_turntable = !sim_.has_turntable();
    if (o_.rtde_port > 0) ur_ = std::make_unique<twin::UrController>(o_.rtde_port, o_.ur_script_port);
    driver::RigDriver rig_driver(bus_, handlers(), options);
    wall0_ = bus::now_s();
    sim0_ = sim_.time_s();
    double next_status = sim_.time_s();
    const double status_period_s = o_.faulty(twin::DriverFault::kSlowStatus) ? kSlowStatusPeriodS : driver::kStatusPeriodS;
    while (!stop_requested()) {
      bus_.spin_once(0);
      sim_.step();
      for (const twin::RigContact& c : sim_.take_contacts()) on_contact(c, rig_driver);
      if (ur_) serve_ur();
      if (sim_.time_s() + 1e-12 < next_status) continue;
      next_status += status_period_s;
      publish_statuses(rig_driver);
      // Pace: sleep while rig time is ahead of speed x wall time.
      const double ahead = (sim_.time_s() - sim0_) / o_.speed - (bus::now_s() - wall0_);
      if (ahead > 0) bus_.spin_once(static_cast<int>(ahead * 1000));  // sleeps in the LCM wait
    }
    const twin::ContactCheckCost& cost = sim_.contact_monitor().cost();
    log_info(fmt::format("contact check: {} contact events; {} states checked in {} steps, {:.1f} us each, {:.2f} s in all; "
                         "{} steps at rest (held without physics)",
                         sim_.contact_events(), cost.states, cost.calls,
                         cost.states > 0 ? 1e6 * cost.seconds / static_cast<double>(cost.states) : 0.0, cost.seconds,
                         sim_.rest_steps()));
  }

 private:
  // A contact's onset (the rig has already stopped, twin/rig_sim.hpp): reported at once in the
  // log, and in every ARM_STATUS as kFaultContact on the command it was executing until the next
  // command is accepted; playing a UR controller, as the protective stop a UR arm's collision
  // detection makes (safety mode 3, which pbnbv-ur-driver reports as a drive fault; it stays, as a
  // UR arm's stays until someone releases it at the pendant, which the twin does not play).
  void on_contact(const twin::RigContact& c, driver::RigDriver& rig_driver) {
    const std::string text = "contact: " + c.text();
    log_warn(text + ": the arm stops and holds");
    if (ur_) {
      safety_mode_ = driver::ur::kSafetyModeProtectiveStop;
    } else {
      rig_driver.set_arm_contact(c.command_seq, text);
    }
  }

  // As a UR controller: the RTDE client's requests answered, the program's part played (a new
  // command number in the registers starts the move or the hold and is echoed), the faults
  // played, and the controller's state streamed.
  void serve_ur() {
    ur_->poll();
    if (ur_->take_program()) start_program();
    const driver::ur::Registers& r = ur_->registers();
    if (program_running_ && safety_mode_ == driver::ur::kSafetyModeNormal && r.number != done_) follow(r);
    if (stop_at_s_ >= 0 && sim_.time_s() >= stop_at_s_) {
      stop_at_s_ = -1;
      sim_.hold_arm(sim_.arm().command_seq);
      safety_mode_ = driver::ur::kSafetyModeProtectiveStop;
      log_warn("playing a protective stop (safety mode 3) halfway through move " + std::to_string(done_));
    }
    if (drop_at_s_ >= 0 && sim_.time_s() >= drop_at_s_) {
      drop_at_s_ = -1;
      ur_->drop("playing a dropped connection (--fault rtde-drop)");
    }
    ur_->stream(sim_.time_s(), ur_state());
    ur_->poll();  // sends it now
  }

  // A program (re)started: the number standing in the registers counts as done, and a move in
  // progress stops, as when a controller replaces its running program.
  void start_program() {
    program_running_ = true;
    done_ = echo_ = ur_->registers().number;
    if (sim_.moving(sim_.arm())) sim_.hold_arm(sim_.arm().command_seq);
  }

  // The program's part for a new command number: echo it, then hold or move (as movej would).
  void follow(const driver::ur::Registers& r) {
    done_ = echo_ = r.number;
    if (r.stop) return sim_.hold_arm(r.number);
    try {
      sim_.command_arm(Eigen::Map<const Vector6d>(r.target.data()), r.speed_scale, r.number);
    } catch (const std::exception& e) {
      log_warn("the program's move " + std::to_string(r.number) + " failed: " + e.what() + ": program stopped");
      program_running_ = false;
      return;
    }
    ++moves_;
    if (moves_ == 1 && o_.faulty(twin::DriverFault::kRtdeDrop)) drop_at_s_ = sim_.time_s() + 2.0;
    if (moves_ == 2 && o_.faulty(twin::DriverFault::kProtectiveStop)) {
      stop_at_s_ = sim_.arm().t0 + 0.5 * (sim_.arm().t1 - sim_.arm().t0);
    }
  }

  // The controller's state as RTDE reports it (timestamp: rig time).
  driver::ur::State ur_state() const {
    driver::ur::State s;
    s.timestamp_s = sim_.time_s();
    const Vector6d q = sim_.arm_position_reported(), qd = sim_.arm_velocity();
    const Vector6d offset = q - sim_.arm_position();
    for (int i = 0; i < 6; ++i) {
      s.q[i] = q[i];
      s.qd[i] = qd[i];
      s.target_q[i] = sim_.arm().setpoint[i] + offset[i];
    }
    s.robot_mode = driver::ur::kRobotModeRunning;
    s.safety_mode = safety_mode_;
    s.runtime_state = program_running_ ? driver::ur::kRuntimePlaying : 1;  // 1: stopped
    s.echo = echo_;
    return s;
  }

  driver::RigDriver::Handlers handlers() {
    driver::RigDriver::Handlers h;
    if (!ur_) {  // with --rtde-port pbnbv-ur-driver owns the arm
      h.move_arm = [this](const driver::ArmTarget& t) {
        try {
          if (t.hold) {
            sim_.hold_arm(t.seq);
          } else {
            sim_.command_arm(Eigen::Map<const Vector6d>(t.position_rad.data()), t.speed_scale, t.seq);
          }
        } catch (const twin::OutOfLimits& e) {
          throw driver::OutOfLimits(e.what());
        }
      };
    }
    if (sim_.has_turntable()) {
      h.turn_table = [this](const driver::TurntableTarget& t) {
        try {
          sim_.command_turntable(t.angle_rad, t.speed_scale, t.seq);
        } catch (const twin::OutOfLimits& e) {
          throw driver::OutOfLimits(e.what());
        }
      };
    }
    h.capture = [this](const depth_trigger_t& t) { return capture(t); };
    return h;
  }

  // A trigger's frame: rendered at this rig time (the renderer exposes instantaneously), with the
  // noise model and the faults that break the frame.
  depth_frame_t capture(const depth_trigger_t& t) {
    using twin::DriverFault;
    bus_.set_state("rendering");
    mj_forward(sim_.model(), sim_.data());
    twin::DepthImage image = renderer_.render(sim_.data());
    const twin::SensorSimStats sensor = twin::simulate_sensor(image, o_.render_k, depth_sensor_model(o_.camera), rng_);
    // Through the lens: the pinhole image that covers it resampled into the camera's own image.
    if (!o_.distortion.none()) image = twin::through_lens(image, o_.render_k, o_.k, o_.distortion);
    if (!depth_sensor_model(o_.camera).exact()) {
      log_info(fmt::format("frame {}: {} of {} readings: {} shadowed, {} flying, {} lost at grazing angles, {} pushed "
                           "back by multipath, {} dropped",
                           frame_seq_, name_of(o_.camera), sensor.valid_in, sensor.shadowed, sensor.flying,
                           sensor.grazing, sensor.multipath, sensor.dropped));
    }
    if (o_.noise.enabled()) twin::apply_depth_noise(image, o_.noise, rng_);
    driver::Exposure exposure;
    exposure.start_utime = rig_utime(epoch_, sim_.time_s()) + (o_.faulty(DriverFault::kLateExposure) ? 1000000 : 0);
    const double unit_m = o_.faulty(DriverFault::kDepthUnitMm) ? 1e-3 : camera_.depth_unit_m;
    depth_frame_t f = driver::depth_frame(camera_, driver::depth_counts(image.depth_m, unit_m), exposure, frame_seq_++, t);
    if (!o_.no_colour) {
      // The colour sensor exposes with the depth sensor; its image is a pinhole one.
      ColourImage colour;
      colour.intrinsics = o_.colour_k;
      colour.depth_T_colour = o_.depth_T_colour;
      colour.rgb = renderer_.render_colour(sim_.data(), o_.colour_k, o_.depth_T_colour);
      bus::set_colour(f, colour, f.utime, o_.raw_depth ? depth_frame_t::kColourRgb8 : depth_frame_t::kColourJpeg);
    }
    if (o_.faulty(DriverFault::kNoTriggerId)) f.trigger_seq = -1;
    if (truth_.is_open()) append_truth(truth_, f, sim_.true_camera_in_object(o_.object.object_z_m));
    bus_.set_state("idle");
    // The render stopped the rig's clock while it ran: pacing starts again from here.
    wall0_ = bus::now_s();
    sim0_ = sim_.time_s();
    return f;
  }

  void publish_statuses(driver::RigDriver& rig_driver) {
    using twin::DriverFault;
    const bool no_echo = o_.faulty(DriverFault::kNoSeqEcho);
    const bool backwards = o_.faulty(DriverFault::kUtimeBackwards) && rig_driver.statuses_published() % 20 == 19;
    driver::Stamp stamp;
    stamp.utime = rig_utime(epoch_, sim_.time_s()) - (backwards ? 50000 : 0);
    stamp.driver_utime = std::llround(sim_.time_s() * 1e6);  // the driver's own clock: the simulation's
    driver::ArmReading arm;
    arm.joint_names = rig_.joint_names;
    arm.position_rad = bus::to_std(sim_.arm_position_reported());
    arm.velocity_rad_s = bus::to_std(sim_.arm_velocity());
    arm.commanded_rad = bus::to_std(Eigen::Map<const Vector6d>(sim_.arm().target.data()) +
                                    (sim_.arm_position_reported() - sim_.arm_position()));
    arm.command_seq = no_echo ? -1 : sim_.arm().command_seq;
    arm.motion = motion_of(sim_, sim_.arm());
    arm.contacts = static_cast<int32_t>(std::min<int64_t>(sim_.contact_events(), INT32_MAX));
    if (sim_.last_contact()) arm.last_contact = sim_.last_contact()->text();
    std::optional<driver::TurntableReading> turntable;
    if (sim_.has_turntable()) {
      driver::TurntableReading& t = turntable.emplace();
      t.angle_rad = sim_.turntable_angle_reported();
      t.velocity_rad_s = sim_.turntable_velocity();
      t.commanded_rad = sim_.turntable().target[0] + errors_.turntable_offset_rad + sim_.turntable_lag_rad();
      t.command_seq = no_echo ? -1 : sim_.turntable().command_seq;
      t.motion = motion_of(sim_, sim_.turntable());
    }
    if (ur_) {
      if (turntable) rig_driver.publish_statuses(stamp, std::nullopt, turntable);
      return;
    }
    rig_driver.publish_statuses(stamp, arm, turntable);
  }

  const TwinOptions& o_;
  const RigModel& rig_;
  twin::RigSim& sim_;
  twin::DepthRenderer& renderer_;
  twin::PoseErrorModel errors_;
  bus::Bus& bus_;
  driver::DepthCamera camera_;
  std::mt19937_64 rng_;
  int64_t epoch_;      // rig time 0, wall clock
  // Frame numbers start at the wall clock (microseconds): a restarted twin never repeats one, so
  // twin_truth.jsonl and the frames of one scan stay unambiguous.
  int64_t frame_seq_;
  std::ofstream truth_;
  // Pacing reference: rig time runs at `speed` x wall time from here (reset after a render,
  // which stops the clock of the rig while it runs).
  double wall0_ = 0, sim0_ = 0;
  // --rtde-port: the controller, and the program's part the twin plays.
  std::unique_ptr<twin::UrController> ur_;
  bool program_running_ = false;
  int32_t done_ = 0;   // the command number last acted on
  int32_t echo_ = 0;   // output_int_register_0
  int32_t safety_mode_ = driver::ur::kSafetyModeNormal;
  int moves_ = 0;
  double stop_at_s_ = -1, drop_at_s_ = -1;  // rig time of a fault to play (-1: none)
};

}  // namespace

int main(int argc, char** argv) {
  set_log_name("twin");
  CLI::App app{"pbnbv-twin: the simulated rig (arm, turntable, depth camera) on the rig channels, as real drivers "
               "would be",
               "pbnbv-twin"};
  cli::init(app);
  TwinOptions o;
  add_options(app, o);
  if (const std::optional<int> code = cli::parse(app, argc, argv, std::cout, std::cerr)) return *code;
  install_stop_handlers();
  try {
    take_model_defaults(
        depth_sensor_model(o.camera),
        [&app](std::string_view name) { return app.get_option("--" + std::string(name))->count() > 0; }, o.k, o.range);
    complete(o);
    prepare_object_mesh(o);
    const std::string model_path = o.rig.model_path.empty() ? default_rig_path(o.rig.kind) : o.rig.model_path;
    twin::PoseErrorModel errors = twin::make_pose_error(
        o.hand_eye_error_mm * 1e-3, o.hand_eye_error_deg * kPi / 180, o.turntable_error_deg * kPi / 180,
        o.joint_error_deg * kPi / 180, static_cast<uint64_t>(o.error_seed));
    errors.turntable_backlash_rad = o.turntable_backlash_deg * kPi / 180;
    const RigModel rig = load_rig(model_path);
    if (o.distortion_text.empty()) {
      o.distortion = rig.camera ? rig.camera->distortion : LensDistortion{};
    } else {
      const std::optional<std::vector<double>> c = cli::detail::parse_numbers(o.distortion_text, 5);
      if (!c) throw std::invalid_argument("--distortion '" + o.distortion_text + "' is not five numbers k1,k2,p1,p2,k3");
      o.distortion = LensDistortion{(*c)[0], (*c)[1], (*c)[2], (*c)[3], (*c)[4]};
    }
    o.distortion.validate(o.k, "--distortion");
    o.render_k = o.distortion.none() ? o.k : pinhole_cover(o.k, o.distortion);
    // The turntable reports its reading: the platter's true angle plus the model's zero (a
    // calibrated file's pbnbv_turntable_zero) plus the error model's offset.
    const double turntable_error_rad = errors.turntable_offset_rad;
    errors.turntable_offset_rad += rig.turntable_zero_rad;
    twin::RigSim sim(rig, o.object, o.model_out, errors);
    sim.set_ignore_limits(o.faulty(twin::DriverFault::kIgnoreLimits));
    for (const twin::DriverFault f : o.faults) log_warn("playing a faulty driver: " + std::string(name_of(f)));
    if (!o.truth_rig_path.empty()) write_truth_rig(o, model_path, rig, errors, turntable_error_rad);
    if (errors.enabled()) {
      const Eigen::AngleAxisd r(errors.hand_eye_error.linear());
      std::ostringstream os;
      os << "pose-error model on: hand-eye " << errors.hand_eye_error.translation().norm() * 1e3 << " mm / "
         << r.angle() * 180 / kPi << " deg, turntable " << errors.turntable_offset_rad * 180 / kPi
         << " deg, joints sigma " << errors.joint_sigma_rad * 180 / kPi << " deg, turntable backlash "
         << errors.turntable_backlash_rad * 180 / kPi << " deg";
      log_info(os.str());
    }
    if (o.object.calibration_sphere_radius_m > 0) {
      // MuJoCo draws a sphere as an inscribed polyhedron (28 x 16 facets by default: up to 0.3 mm
      // inside a 50 mm sphere, which biases the fitted centre along each view); 256 x 256 keeps
      // the drawn surface within 5 um of the sphere (twin/test/depth_renderer_test.cpp).
      sim.model()->vis.quality.numslices = 256;
      sim.model()->vis.quality.numstacks = 256;
    }
    twin::EglContext egl;
    twin::DepthRenderer renderer(sim.model(), "depth", o.render_k, o.range);
    const std::string lens =
        o.distortion.none() ? std::string()
                            : fmt::format(" through a lens (k1 {} k2 {} p1 {} p2 {} k3 {}: {}x{} rendered, resampled)",
                                          o.distortion.k1, o.distortion.k2, o.distortion.p1, o.distortion.p2,
                                          o.distortion.k3, o.render_k.width, o.render_k.height);
    log_info("rig '" + rig.arm_name + "' from " + model_path + ", rendering " + std::to_string(o.k.width) + "x" +
             std::to_string(o.k.height) + lens + " on " + egl.description() + "; camera: " +
             std::string(depth_sensor_model(o.camera).label));
    // Statuses name the scan this twin plays the rig of ("" when it obeys every scan, as a real
    // driver does); frames echo the scan of their trigger.
    bus::Bus bus("twin");
    bus.serve_scan(o.scope);
    Twin(o, rig, sim, renderer, errors, bus).run();
    log_info("stopping");
    return 0;
  } catch (const std::exception& e) {
    log_error(e.what());
    return 2;
  }
}
