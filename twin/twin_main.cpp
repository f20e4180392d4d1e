// pbnbv-twin: the simulated rig. Plays the physical arm, turntable and depth camera and speaks
// only the rig channels, exactly as real drivers would:
//   in:  ARM_COMMAND, TURNTABLE_COMMAND, DEPTH_TRIGGER
//   out: ARM_STATUS, TURNTABLE_STATUS (every 10 ms of rig time), DEPTH_FRAME (per trigger),
//        HEARTBEAT
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
#include "core/base/args.hpp"
#include "core/base/log.hpp"
#include "core/rig/rig.hpp"
#include "twin/depth_renderer.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "twin/rig_sim.hpp"
#include "core/base/units.hpp"

using namespace pbnbv;

namespace {

constexpr double kStatusPeriodS = 0.01;  // 100 Hz of rig time
constexpr double kDepthUnitM = 1e-4;     // 0.1 mm per count

void usage() {
  std::cerr <<
R"(usage: pbnbv-twin [options]
  --rig arm|free           rig profile (models/rig_<rig>.xml)       [arm]
  --model PATH             rig MJCF instead of the profile's file
  --mesh PATH              object mesh in the normalised object frame (binary STL or OBJ)
  --object-z M             object frame origin above the turntable top, m [0]
  --model-out PATH         where to write the composed model            [twin_model.xml]
  --width/--height PX      depth image size                             [1280 x 720]
  --fx --fy --cx --cy PX   intrinsics                                   [696 696 640 360]
  --depth-min/--depth-max M  sensor range                               [0.1 3.0]
  --noise-sigma K          depth noise std = K * depth (0: off)         [0]
  --dropout P              pixel dropout probability (0: off)           [0]
  --seed N                 noise seed                                   [1]
  --speed X                simulation speed, multiple of real time      [1]
 pose-error model (off by default): kinematic poses wrong the way a real rig's are
  --hand-eye-error-mm MM   true camera mount off the model's by MM...   [0]
  --hand-eye-error-deg DEG ...and turned by DEG (random direction/axis) [0]
  --turntable-error-deg D  turntable reports its angle D off            [0]
  --joint-error-deg D      each joint reports its angle off by N(0, D), new per move [0]
  --error-seed N           seed of the error directions and draws       [7]
  --truth-out PATH         append each frame's true camera pose (JSON lines; evaluation only)
)";
}

int64_t rig_utime(int64_t epoch_utime, double sim_s) {
  return epoch_utime + static_cast<int64_t>(std::llround(sim_s * 1e6));
}

// The mode of a joint group as Status's constants (arm_status_t or turntable_status_t).
template <class Status>
int8_t mode_of(const twin::RigSim& sim, const twin::JointGroup& g) {
  if (g.command_seq < 0 && sim.settled(g)) return Status::kModeIdle;
  return sim.settled(g) ? Status::kModeSettled : Status::kModeMoving;
}

// The last command a driver refused, until it accepts one: the twin's only fault
// (kFaultCommandRejected; it has no drive that can fail).
struct Rejection {
  std::string fault;         // empty: none
  int64_t command_seq = -1;  // the refused command
  void set(const std::string& what, int64_t seq) {
    fault = what;
    command_seq = seq;
  }
  void clear() { set("", -1); }
};

}  // namespace

int main(int argc, char** argv) {
  set_log_name("twin");
  install_stop_handlers();
  try {
    Args args(argc, argv);
    if (args.flag("help")) {
      usage();
      return 0;
    }
    const RigKind kind = parse_rig_kind(args.str("rig", "arm"));
    const std::string model_path = args.str("model", default_rig_path(kind));
    twin::ObjectPlacement object;
    object.mesh_path = args.str("mesh", "");
    object.object_z_m = args.num("object-z", 0.0, -1.0, 2.0);
    if (!object.mesh_path.empty()) {
      object.mesh_path = std::filesystem::absolute(object.mesh_path).string();
      if (!std::filesystem::exists(object.mesh_path)) {
        throw std::invalid_argument("--mesh " + object.mesh_path + " does not exist");
      }
    }
    const std::string model_out = args.str("model-out", "twin_model.xml");
    CameraIntrinsics k;
    k.width = static_cast<int>(args.integer("width", k.width, 1, 16384));
    k.height = static_cast<int>(args.integer("height", k.height, 1, 16384));
    k.fx = args.num("fx", k.fx, 1e-6, 1e6);
    k.fy = args.num("fy", k.fy, 1e-6, 1e6);
    k.cx = args.num("cx", k.width / 2.0, 0, k.width);
    k.cy = args.num("cy", k.height / 2.0, 0, k.height);
    k.validate();
    DepthRange range;
    range.min_m = args.num("depth-min", range.min_m, 1e-3, 100);
    range.max_m = args.num("depth-max", range.max_m, 1e-3, 6.5);
    range.validate();
    twin::DepthNoise noise;
    noise.sigma_per_m = args.num("noise-sigma", 0.0, 0.0, 0.1);
    noise.dropout = args.num("dropout", 0.0, 0.0, 1.0);
    std::mt19937_64 rng(static_cast<uint64_t>(args.integer("seed", 1, 0, 1L << 40)));
    const double speed = args.num("speed", 1.0, 0.01, 1000.0);
    const twin::PoseErrorModel errors = twin::make_pose_error(
        args.num("hand-eye-error-mm", 0.0, 0.0, 100.0) * 1e-3,
        args.num("hand-eye-error-deg", 0.0, 0.0, 20.0) * kPi / 180,
        args.num("turntable-error-deg", 0.0, -20.0, 20.0) * kPi / 180,
        args.num("joint-error-deg", 0.0, 0.0, 5.0) * kPi / 180,
        static_cast<uint64_t>(args.integer("error-seed", 7, 0, 1L << 40)));
    const std::string truth_path = args.str("truth-out", "");
    args.reject_unknown();

    const RigModel rig = load_rig(model_path);
    twin::RigSim sim(rig, object, model_out, errors);
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
    twin::EglContext egl;
    twin::DepthRenderer renderer(sim.model(), "depth", k, range);
    log_info("rig '" + rig.arm_name + "' from " + model_path + ", rendering " +
             std::to_string(k.width) + "x" + std::to_string(k.height) + " on " + egl.description());

    bus::Bus bus("twin");
    // Pacing reference: rig time runs at `speed` x wall time from here (reset after a render,
    // which stops the clock of the rig while it runs).
    double wall0 = 0, sim0 = 0;
    const int64_t epoch = bus::now_utime();
    long status_seq = 0;
    long frame_seq = 0;
    Rejection arm_fault, turntable_fault;

    bus.subscribe<arm_command_t>(channels::kArmCommand, [&](const arm_command_t& c) {
      try {
        if (c.mode == arm_command_t::kModeHold) {
          sim.hold_arm(c.seq);
        } else if (c.mode == arm_command_t::kModePosition) {
          if (c.num_joints != 6) {
            throw std::invalid_argument("num_joints = " + std::to_string(c.num_joints) + ", this arm has 6");
          }
          sim.command_arm(bus::to_vector6(c.joint_position_rad, "joint_position_rad"),
                          c.speed_scale, c.seq);
        } else {
          throw std::invalid_argument("unknown mode " + std::to_string(c.mode));
        }
        arm_fault.clear();
      } catch (const std::exception& e) {
        arm_fault.set("rejected ARM_COMMAND seq " + std::to_string(c.seq) + ": " + e.what(), c.seq);
        throw std::invalid_argument(arm_fault.fault);
      }
    });
    bus.subscribe<turntable_command_t>(channels::kTurntableCommand, [&](const turntable_command_t& c) {
      try {
        sim.command_turntable(c.angle_rad, c.speed_scale, c.seq);
        turntable_fault.clear();
      } catch (const std::exception& e) {
        turntable_fault.set("rejected TURNTABLE_COMMAND seq " + std::to_string(c.seq) + ": " + e.what(), c.seq);
        throw std::invalid_argument(turntable_fault.fault);
      }
    });
    bus.subscribe<depth_trigger_t>(channels::kDepthTrigger, [&](const depth_trigger_t& t) {
      bus.set_state("rendering");
      mj_forward(sim.model(), sim.data());
      twin::DepthImage image = renderer.render(sim.data());
      if (noise.enabled()) twin::apply_depth_noise(image, noise, rng);
      depth_frame_t f;
      f.utime = rig_utime(epoch, sim.time_s());
      f.seq = frame_seq++;
      f.trigger_seq = t.seq;
      f.width = image.width;
      f.height = image.height;
      f.fx = k.fx;
      f.fy = k.fy;
      f.cx = k.cx;
      f.cy = k.cy;
      f.depth_min_m = range.min_m;
      f.depth_max_m = range.max_m;
      f.depth_unit_m = kDepthUnitM;
      f.num_bytes = image.width * image.height * 2;
      f.depth.resize(f.num_bytes);
      for (std::size_t i = 0; i < image.depth_m.size(); ++i) {
        const double counts = std::round(image.depth_m[i] / kDepthUnitM);
        const uint16_t v = counts > 0 && counts < 65535 ? static_cast<uint16_t>(counts) : 0;
        f.depth[2 * i] = static_cast<uint8_t>(v & 0xff);
        f.depth[2 * i + 1] = static_cast<uint8_t>(v >> 8);
      }
      bus.publish(channels::kDepthFrame, f);
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
    });

    // Rig time runs at `speed` x wall time; the loop sleeps when it is ahead.
    wall0 = bus::now_s();
    sim0 = sim.time_s();
    double next_status = sim.time_s();
    while (!stop_requested()) {
      bus.spin_once(0);
      sim.step();
      if (sim.time_s() + 1e-12 >= next_status) {
        next_status += kStatusPeriodS;
        const int64_t utime = rig_utime(epoch, sim.time_s());
        arm_status_t s;
        s.utime = utime;
        s.seq = status_seq;
        s.num_joints = 6;
        s.joint_names = rig.joint_names;
        s.joint_position_rad = bus::to_std(sim.arm_position_reported());
        s.joint_velocity_rad_s = bus::to_std(sim.arm_velocity());
        s.joint_position_commanded_rad = bus::to_std(
            Eigen::Map<const Vector6d>(sim.arm().target.data()) + (sim.arm_position_reported() - sim.arm_position()));
        s.command_seq = sim.arm().command_seq;
        const bool arm_faulted = !arm_fault.fault.empty();
        s.mode = arm_faulted ? arm_status_t::kModeFault : mode_of<arm_status_t>(sim, sim.arm());
        s.fault_code = arm_faulted ? arm_status_t::kFaultCommandRejected : arm_status_t::kFaultNone;
        s.fault_command_seq = arm_fault.command_seq;
        s.fault = arm_fault.fault;
        bus.publish(channels::kArmStatus, s);
        if (sim.has_turntable()) {
          turntable_status_t t;
          t.utime = utime;
          t.seq = status_seq;
          t.angle_rad = sim.turntable_angle_reported();
          t.velocity_rad_s = sim.turntable_velocity();
          t.angle_commanded_rad = sim.turntable().target[0] + errors.turntable_offset_rad;
          t.command_seq = sim.turntable().command_seq;
          const bool turntable_faulted = !turntable_fault.fault.empty();
          t.mode = turntable_faulted ? turntable_status_t::kModeFault : mode_of<turntable_status_t>(sim, sim.turntable());
          t.fault_code = turntable_faulted ? turntable_status_t::kFaultCommandRejected : turntable_status_t::kFaultNone;
          t.fault_command_seq = turntable_fault.command_seq;
          t.fault = turntable_fault.fault;
          bus.publish(channels::kTurntableStatus, t);
        }
        ++status_seq;
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
    usage();
    return 2;
  }
}
