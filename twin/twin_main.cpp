// pbnbv-twin: the simulated rig. Plays the physical arm, turntable and depth camera and speaks
// only the rig channels, exactly as real drivers would:
//   in:  ARM_COMMAND, TURNTABLE_COMMAND, DEPTH_TRIGGER
//   out: ARM_STATUS, TURNTABLE_STATUS (every 10 ms of rig time), DEPTH_FRAME (per trigger),
//        HEARTBEAT
// The reference driver of the contract, built on the driver library (services/driver; README
// "Writing a driver"): the checks, faults, statuses and frames are the library's; --fault makes it a faulty one
// (twin/driver_faults.hpp), for `pbnbv rig-check`'s tests.
#include <unistd.h>

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
#include "bus/convert.hpp"
#include "bus/rig_options.hpp"
#include "cli/options.hpp"
#include "core/scan/scan_options.hpp"
#include "core/base/log.hpp"
#include "core/io/json.hpp"
#include "core/rig/calibration.hpp"
#include "core/rig/rig.hpp"
#include "twin/depth_renderer.hpp"
#include "twin/driver_faults.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "twin/rig_sim.hpp"
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

}  // namespace

int main(int argc, char** argv) {
  set_log_name("twin");
  CLI::App app{"pbnbv-twin: the simulated rig (arm, turntable, depth camera) on the rig channels, as real drivers "
               "would be",
               "pbnbv-twin"};
  cli::init(app);
  bus::RigOptions rig_options;
  bus::add_rig_options(app, &rig_options);
  twin::ObjectPlacement object;
  cli::add_text(app, "mesh", &object.mesh_path, "object mesh in the normalised object frame (binary STL or OBJ)", "PATH");
  cli::add(app, Setting<double>{"object-z", 0.0, -1.0, 2.0, "m", "object frame origin above the turntable top"},
           &object.object_z_m);
  cli::add(app, kSphereRadius.renamed("calibration-sphere", "put the calibration sphere of this radius on the platter "
                                      "mark (0: none; see pbnbv calibrate)").with_default(0.0),
           &object.calibration_sphere_radius_m);
  object.calibration_sphere_offset_m = kSphereOffset.value;
  cli::add(app, kSphereOffset.renamed("calibration-sphere-offset", "the calibration sphere's centre from the turntable axis, "
                                      "on the platter's +x axis"),
           &object.calibration_sphere_offset_m);
  std::string model_out = "twin_model.xml";
  cli::add_text(app, "model-out", &model_out, "where to write the composed model", "PATH");
  CameraIntrinsics k;
  std::optional<double> cx, cy;
  cli::add(app, kImageWidth, &k.width);
  cli::add(app, kImageHeight, &k.height);
  cli::add(app, kFocalX, &k.fx);
  cli::add(app, kFocalY, &k.fy);
  cli::add(app, kPrincipalX, &cx, "width / 2");
  cli::add(app, kPrincipalY, &cy, "height / 2");
  DepthRange range;
  cli::add(app, kDepthMin, &range.min_m);
  cli::add(app, kDepthMax, &range.max_m);
  twin::DepthNoise noise;
  cli::add(app, kDepthNoise, &noise.sigma_per_m);
  cli::add(app, kDropout, &noise.dropout);
  int64_t noise_seed = 0;
  cli::add(app, Setting<int64_t>{"seed", 1, 0, int64_t{1} << 40, "", "depth noise seed"}, &noise_seed);
  // Run by hand the twin keeps real time, as the rig it stands for; `pbnbv scan` asks for
  // --sim-speed (4 by default).
  double speed = 0;
  cli::add(app, kSimSpeed.renamed("speed", "simulation speed, multiple of real time").with_default(1.0), &speed);
  double hand_eye_error_mm = 0, hand_eye_error_deg = 0, turntable_error_deg = 0, joint_error_deg = 0;
  int64_t error_seed = 0;
  cli::add(app, kHandEyeErrorMm, &hand_eye_error_mm);
  cli::add(app, kHandEyeErrorDeg, &hand_eye_error_deg);
  cli::add(app, kTurntableErrorDeg, &turntable_error_deg);
  cli::add(app, kJointErrorDeg, &joint_error_deg);
  cli::add(app, kErrorSeed, &error_seed);
  std::string scope;
  cli::add_text(app, "scan", &scope,
                "play the rig of this scan only: commands and triggers of other scans are ignored and counted "
                "(default: obey every command, as a real driver does)",
                "ID");
  bool raw_depth = false;
  cli::add_flag(app, "raw-depth", &raw_depth,
                "send depth frames uncompressed (encoding raw; default zlib: 20x smaller, survives packet loss)");
  std::string truth_path;
  cli::add_text(app, "truth-out", &truth_path,
                "append each frame's true camera pose to this file (JSON lines; evaluation only)", "PATH");
  std::vector<twin::DriverFault> faults;
  cli::add_list(app, "fault", &faults,
                "play a faulty driver, for pbnbv rig-check's tests: slow-status (20 Hz), no-seq-echo, depth-unit-mm "
                "(counts in mm, unit field 0.1 mm), no-trigger-id, ignore-limits (executes out-of-limit commands), "
                "utime-backwards, late-exposure (frames stamped 1 s late)");
  std::string truth_rig_path;
  cli::add_text(app, "truth-rig-out", &truth_rig_path,
                "write the true hand-eye transform and turntable zero to this JSON file (evaluation only)", "PATH");
  if (const std::optional<int> code = cli::parse(app, argc, argv, std::cout, std::cerr)) return *code;
  install_stop_handlers();
  try {
    const std::string model_path = rig_options.model_path.empty() ? default_rig_path(rig_options.kind)
                                                                  : rig_options.model_path;
    if (!object.mesh_path.empty()) {
      object.mesh_path = std::filesystem::absolute(object.mesh_path).string();
      if (!std::filesystem::exists(object.mesh_path)) {
        throw std::invalid_argument("--mesh " + object.mesh_path + " does not exist");
      }
    }
    k.cx = cx.value_or(k.width / 2.0);
    k.cy = cy.value_or(k.height / 2.0);
    k.validate();
    range.validate();
    std::mt19937_64 rng(static_cast<uint64_t>(noise_seed));
    twin::PoseErrorModel errors = twin::make_pose_error(
        hand_eye_error_mm * 1e-3, hand_eye_error_deg * kPi / 180, turntable_error_deg * kPi / 180,
        joint_error_deg * kPi / 180, static_cast<uint64_t>(error_seed));

    const RigModel rig = load_rig(model_path);
    if (object.calibration_sphere_radius_m > 0 && object.calibration_sphere_radius_m + object.calibration_sphere_offset_m > 0.2) {
      throw std::invalid_argument("--calibration-sphere " + std::to_string(object.calibration_sphere_radius_m) +
                                  " m at --calibration-sphere-offset " + std::to_string(object.calibration_sphere_offset_m) +
                                  " m reaches beyond the platter (radius 0.2 m)");
    }
    // The turntable reports its reading: the platter's true angle plus the model's zero (a
    // calibrated file's pbnbv_turntable_zero) plus the error model's offset.
    const double turntable_error_rad = errors.turntable_offset_rad;
    errors.turntable_offset_rad += rig.turntable_zero_rad;
    twin::RigSim sim(rig, object, model_out, errors);
    using twin::DriverFault;
    const auto faulty = [&](DriverFault f) { return twin::has_fault(faults, f); };
    sim.set_ignore_limits(faulty(DriverFault::kIgnoreLimits));
    for (const DriverFault f : faults) log_warn("playing a faulty driver: " + std::string(name_of(f)));
    if (!truth_rig_path.empty()) {
      nlohmann::json j;
      j["model"] = model_path;
      j["flange_T_camera"] = to_json(rig.flange_T_camera * errors.hand_eye_error);
      j["model_flange_T_camera"] = to_json(rig.flange_T_camera);
      j["turntable_zero_rad"] = errors.turntable_offset_rad;
      j["model_turntable_zero_rad"] = rig.turntable_zero_rad;
      j["turntable_error_rad"] = turntable_error_rad;
      j["turntable_axis_direction_world"] = to_json(Eigen::Vector3d(rig.world_T_turntable.linear().col(2)));
      j["turntable_axis_point_world"] = to_json(Eigen::Vector3d(rig.world_T_turntable.translation()));
      if (object.calibration_sphere_radius_m > 0) {
        j["calibration_sphere"] = {{"radius_m", object.calibration_sphere_radius_m},
                                   {"offset_m", object.calibration_sphere_offset_m}};
      }
      write_json_atomic(j, truth_rig_path);
    }
    std::ofstream truth;
    if (!truth_path.empty()) {
      truth.open(truth_path, std::ios::app);
      if (!truth) throw std::runtime_error("cannot write --truth-out " + truth_path);
    }
    if (errors.enabled()) {
      const Eigen::AngleAxisd r(errors.hand_eye_error.linear());
      std::ostringstream os;
      os << "pose-error model on: hand-eye " << errors.hand_eye_error.translation().norm() * 1e3 << " mm / "
         << r.angle() * 180 / kPi << " deg, turntable " << errors.turntable_offset_rad * 180 / kPi
         << " deg, joints sigma " << errors.joint_sigma_rad * 180 / kPi << " deg";
      log_info(os.str());
    }
    if (object.calibration_sphere_radius_m > 0) {
      // MuJoCo draws a sphere as an inscribed polyhedron (28 x 16 facets by default: up to 0.3 mm
      // inside a 50 mm sphere, which biases the fitted centre along each view); 256 x 256 keeps
      // the drawn surface within 5 um of the sphere (twin/test/depth_renderer_test.cpp).
      sim.model()->vis.quality.numslices = 256;
      sim.model()->vis.quality.numstacks = 256;
    }
    twin::EglContext egl;
    twin::DepthRenderer renderer(sim.model(), "depth", k, range);
    log_info("rig '" + rig.arm_name + "' from " + model_path + ", rendering " +
             std::to_string(k.width) + "x" + std::to_string(k.height) + " on " + egl.description());

    bus::Bus bus("twin");
    bus.serve_scan(scope);
    // Statuses name the scan this twin plays the rig of ("" when it obeys every scan, as a real
    // driver does); frames echo the scan of their trigger.
    // Pacing reference: rig time runs at `speed` x wall time from here (reset after a render,
    // which stops the clock of the rig while it runs).
    double wall0 = 0, sim0 = 0;
    const int64_t epoch = bus::now_utime();
    // Frame numbers start at the wall clock (microseconds): a restarted twin never repeats one, so
    // twin_truth.jsonl and the frames of one scan stay unambiguous.
    int64_t frame_seq = bus::now_utime();
    const bool no_echo = faulty(DriverFault::kNoSeqEcho);
    driver::DepthCamera camera;
    camera.camera_id = kCameraId;
    camera.width = k.width;
    camera.height = k.height;
    camera.fx = k.fx;
    camera.fy = k.fy;
    camera.cx = k.cx;
    camera.cy = k.cy;
    camera.depth_min_m = range.min_m;
    camera.depth_max_m = range.max_m;
    camera.depth_unit_m = kDepthUnitM;
    camera.compress = !raw_depth;

    driver::RigDriver::Handlers handlers;
    handlers.move_arm = [&](const driver::ArmTarget& t) {
      try {
        if (t.hold) {
          sim.hold_arm(t.seq);
        } else {
          sim.command_arm(Eigen::Map<const Vector6d>(t.position_rad.data()), t.speed_scale, t.seq);
        }
      } catch (const twin::OutOfLimits& e) {
        throw driver::OutOfLimits(e.what());
      }
    };
    if (sim.has_turntable()) {
      handlers.turn_table = [&](const driver::TurntableTarget& t) {
        try {
          sim.command_turntable(t.angle_rad, t.speed_scale, t.seq);
        } catch (const twin::OutOfLimits& e) {
          throw driver::OutOfLimits(e.what());
        }
      };
    }
    handlers.capture = [&](const depth_trigger_t& t) {
      bus.set_state("rendering");
      mj_forward(sim.model(), sim.data());
      twin::DepthImage image = renderer.render(sim.data());
      if (noise.enabled()) twin::apply_depth_noise(image, noise, rng);
      // The renderer exposes instantaneously: the exposure starts and ends at this rig time.
      driver::Exposure exposure;
      exposure.start_utime = rig_utime(epoch, sim.time_s()) + (faulty(DriverFault::kLateExposure) ? 1000000 : 0);
      const double unit_m = faulty(DriverFault::kDepthUnitMm) ? 1e-3 : kDepthUnitM;
      depth_frame_t f = driver::depth_frame(camera, driver::depth_counts(image.depth_m, unit_m), exposure, frame_seq++, t);
      if (faulty(DriverFault::kNoTriggerId)) f.trigger_seq = -1;
      if (truth.is_open()) {
        double p[3], q[4];
        pose_to_arrays(sim.true_camera_in_object(object.object_z_m), p, q);
        truth << std::setprecision(12) << "{\"frame_seq\": " << f.seq << ", \"trigger_seq\": " << f.trigger_seq
              << ", \"utime\": " << f.utime << ", \"object_T_camera\": {\"position_m\": [" << p[0] << ", "
              << p[1] << ", " << p[2] << "], \"quat_wxyz\": [" << q[0] << ", " << q[1] << ", " << q[2] << ", "
              << q[3] << "]}}" << std::endl;
      }
      bus.set_state("idle");
      wall0 = bus::now_s();
      sim0 = sim.time_s();
      return f;
    };
    driver::RigDriver::Options options;
    options.any_speed_scale = true;  // RigSim refuses a speed scale outside (0, 1] (or clamps it: ignore-limits)
    driver::RigDriver rig_driver(bus, handlers, options);

    // Rig time runs at `speed` x wall time; the loop sleeps when it is ahead.
    wall0 = bus::now_s();
    sim0 = sim.time_s();
    double next_status = sim.time_s();
    const double status_period_s = faulty(DriverFault::kSlowStatus) ? kSlowStatusPeriodS : driver::kStatusPeriodS;
    while (!stop_requested()) {
      bus.spin_once(0);
      sim.step();
      if (sim.time_s() + 1e-12 >= next_status) {
        next_status += status_period_s;
        const bool backwards = faulty(DriverFault::kUtimeBackwards) && rig_driver.statuses_published() % 20 == 19;
        driver::Stamp stamp;
        stamp.utime = rig_utime(epoch, sim.time_s()) - (backwards ? 50000 : 0);
        stamp.driver_utime = std::llround(sim.time_s() * 1e6);  // the driver's own clock: the simulation's
        driver::ArmReading arm;
        arm.joint_names = rig.joint_names;
        arm.position_rad = bus::to_std(sim.arm_position_reported());
        arm.velocity_rad_s = bus::to_std(sim.arm_velocity());
        arm.commanded_rad = bus::to_std(
            Eigen::Map<const Vector6d>(sim.arm().target.data()) + (sim.arm_position_reported() - sim.arm_position()));
        arm.command_seq = no_echo ? -1 : sim.arm().command_seq;
        arm.motion = motion_of(sim, sim.arm());
        std::optional<driver::TurntableReading> turntable;
        if (sim.has_turntable()) {
          driver::TurntableReading& t = turntable.emplace();
          t.angle_rad = sim.turntable_angle_reported();
          t.velocity_rad_s = sim.turntable_velocity();
          t.commanded_rad = sim.turntable().target[0] + errors.turntable_offset_rad;
          t.command_seq = no_echo ? -1 : sim.turntable().command_seq;
          t.motion = motion_of(sim, sim.turntable());
        }
        rig_driver.publish_statuses(stamp, arm, turntable);
        // Pace: sleep while rig time is ahead of speed x wall time.
        const double ahead = (sim.time_s() - sim0) / speed - (bus::now_s() - wall0);
        if (ahead > 0) {
          bus.spin_once(static_cast<int>(ahead * 1000));  // sleeps in the LCM wait
        }
      }
    }
    log_info("stopping");
    return 0;
  } catch (const std::exception& e) {
    log_error(e.what());
    return 2;
  }
}
