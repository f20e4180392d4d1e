// pbnbv-motion: the motion executor.
//   in:  MOVE_REQUEST (a camera pose in the object frame), ARM_STATUS, TURNTABLE_STATUS
//   out: ARM_COMMAND, TURNTABLE_COMMAND, MOVE_RESULT, HEARTBEAT
// Splits the requested pose into a turntable angle and an arm configuration (core
// ReachabilityChecker: IK, joint limits, MuJoCo collision check), commands the rig, waits until
// its status reports the targets reached and still, and answers reached / unreachable / timed
// out with the reason. Requests are idempotent by request_id; commands are re-sent when the
// rig's status does not echo them (a lost message), and no wait is without a deadline.
#include <deque>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "bus/bus.hpp"
#include "bus/rig_options.hpp"
#include "bus/service.hpp"
#include "bus/convert.hpp"
#include "core/base/log.hpp"
#include "core/rig/rig.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"

using namespace pbnbv;

namespace {

constexpr double kResendAfterS = 0.5;        // re-send a command the status has not echoed
constexpr double kStatusStaleS = 1.0;        // status older than this: the rig is silent
constexpr double kWithinToleranceRad = 1e-3; // "arrived" (settle is judged by the rig)
constexpr std::size_t kResultsKept = 256;

struct Reading {
  Vector6d q = Vector6d::Zero();
  double turntable = 0;
  bool arm_settled = false;
  bool turntable_settled = true;
  long arm_command_seq = -1;
  long turntable_command_seq = -1;
  std::string fault;
  int64_t utime = 0;
  double arm_rx_s = -1e9;        // wall time of the last ARM_STATUS
  double turntable_rx_s = -1e9;  // wall time of the last TURNTABLE_STATUS
};

struct Job {
  move_request_t request;
  ViewSolution solution;
  long arm_seq = -1;
  long turntable_seq = -1;
  double t_start = 0, t_commanded = 0, t_within = -1, deadline = 0, last_send = 0;
  int64_t rig_utime_commanded = 0;
  double plan_s = 0;
};

class MotionExecutor {
 public:
  MotionExecutor(bus::Bus& bus, const RigModel& rig) : bus_(bus), rig_(rig), checker_(rig) {
    bus_.subscribe<arm_status_t>(channels::kArmStatus, [this](const arm_status_t& s) { on_arm(s); });
    if (rig_.has_turntable) {
      bus_.subscribe<turntable_status_t>(channels::kTurntableStatus,
                                         [this](const turntable_status_t& s) { on_turntable(s); });
    }
    bus_.subscribe<move_request_t>(channels::kMoveRequest, [this](const move_request_t& r) { on_request(r); });
  }

  void tick() {
    if (!job_) return;
    Job& job = *job_;
    const double now = bus::now_s();
    const bool arm_echoed = reading_.arm_command_seq == job.arm_seq;
    const bool tt_echoed = !rig_.has_turntable || reading_.turntable_command_seq == job.turntable_seq;
    if ((!arm_echoed || !tt_echoed) && now - job.last_send > kResendAfterS) {
      log_warn("rig has not acknowledged command seq " + std::to_string(job.arm_seq) + " after " +
               std::to_string(now - job.last_send) + " s: re-sending");
      send_commands(job);
    }
    if (!reading_.fault.empty() && reading_.fault.find("seq " + std::to_string(job.arm_seq)) != std::string::npos) {
      finish(job, move_result_t::kUnreachable, "the rig rejected the command: " + reading_.fault);
      return;
    }
    if (arm_echoed && tt_echoed && job.t_within < 0 && within_tolerance(job)) job.t_within = now;
    if (arm_echoed && tt_echoed && reading_.arm_settled && reading_.turntable_settled &&
        within_tolerance(job)) {
      finish(job, move_result_t::kReached, "");
      return;
    }
    if (now > job.deadline) {
      std::ostringstream why;
      why << "not settled after " << job.request.timeout_s << " s: ";
      if (now - reading_.arm_rx_s > kStatusStaleS) {
        why << "no ARM_STATUS for " << now - reading_.arm_rx_s << " s";
      } else if (!arm_echoed) {
        why << "ARM_STATUS never acknowledged command seq " << job.arm_seq;
      } else {
        const Vector6d err = (reading_.q - job.solution.q).cwiseAbs();
        int worst = 0;
        err.maxCoeff(&worst);
        why << "joint " << rig_.joint_names[worst] << " is " << err[worst] << " from its target"
            << ", turntable " << std::abs(reading_.turntable - job.solution.turntable_rad)
            << " rad from its target";
      }
      finish(job, move_result_t::kTimedOut, why.str());
    }
  }

 private:
  void on_arm(const arm_status_t& s) {
    reading_.q = bus::to_vector6(s.joint_position_rad, "ARM_STATUS joint_position_rad");
    reading_.arm_settled = s.mode == arm_status_t::kModeSettled || s.mode == arm_status_t::kModeIdle;
    reading_.arm_command_seq = s.command_seq;
    reading_.fault = s.mode == arm_status_t::kModeFault ? s.fault : "";
    reading_.utime = s.utime;
    reading_.arm_rx_s = bus::now_s();
  }

  void on_turntable(const turntable_status_t& s) {
    if (!std::isfinite(s.angle_rad)) throw std::invalid_argument("TURNTABLE_STATUS angle_rad is not finite");
    reading_.turntable = s.angle_rad;
    reading_.turntable_settled = s.mode == arm_status_t::kModeSettled || s.mode == arm_status_t::kModeIdle;
    reading_.turntable_command_seq = s.command_seq;
    reading_.turntable_rx_s = bus::now_s();
  }

  void on_request(const move_request_t& r) {
    bus_.set_scan(r.scan_id, r.iteration);
    if (auto it = results_.find(key(r)); it != results_.end()) {
      bus_.publish(channels::kMoveResult, it->second);  // a repeat: answer again
      return;
    }
    if (job_ && key(job_->request) == key(r)) return;  // already working on it
    move_result_t result = blank_result(r);
    if (job_) {
      result.status = move_result_t::kBusy;
      result.reason = "busy with request " + std::to_string(job_->request.request_id);
      bus_.publish(channels::kMoveResult, result);
      return;
    }
    Pose object_T_camera;
    KeepoutBox keepout;
    try {
      object_T_camera = bus::from_msg(r.object_T_camera, "MOVE_REQUEST object_T_camera");
      bus::require_range(r.object_z_m, -1.0, 2.0, "MOVE_REQUEST object_z_m");
      bus::require_range(r.speed_scale, 1e-3, 1.0, "MOVE_REQUEST speed_scale");
      bus::require_range(r.timeout_s, 0.1, 3600.0, "MOVE_REQUEST timeout_s");
      for (int i = 0; i < 3; ++i) {
        bus::require_range(r.keepout_min_m[i], -5, 5, "MOVE_REQUEST keepout_min_m");
        bus::require_range(r.keepout_max_m[i], r.keepout_min_m[i], 5, "MOVE_REQUEST keepout_max_m");
        keepout.min_m[i] = r.keepout_min_m[i];
        keepout.max_m[i] = r.keepout_max_m[i];
      }
    } catch (const std::exception& e) {
      result.status = move_result_t::kRejected;
      result.reason = e.what();
      store(result);
      throw;  // counted and logged by the bus as a rejection
    }
    if (bus::now_s() - reading_.arm_rx_s > kStatusStaleS ||
        (rig_.has_turntable && bus::now_s() - reading_.turntable_rx_s > kStatusStaleS)) {
      result.status = move_result_t::kTimedOut;
      result.reason = "no recent ARM_STATUS/TURNTABLE_STATUS from the rig: is its driver (or the twin) running?";
      bus_.publish(channels::kMoveResult, result);  // not stored: a retry may succeed
      return;
    }
    const double t0 = bus::now_s();
    Job job;
    job.request = r;
    job.solution = checker_.solve(object_T_camera, reading_.q, reading_.turntable, keepout, r.object_z_m);
    job.plan_s = bus::now_s() - t0;
    job.t_start = t0;
    if (!job.solution.reachable) {
      result.status = move_result_t::kUnreachable;
      result.reason = job.solution.reason;
      result.plan_s = job.plan_s;
      store(result);
      log_info("request " + std::to_string(r.request_id) + " unreachable: " + job.solution.reason);
      return;
    }
    if (r.plan_only) {
      result.status = move_result_t::kPlanned;
      result.joint_target_rad = bus::to_std(job.solution.q);
      result.turntable_target_rad = job.solution.turntable_rad;
      result.plan_s = job.plan_s;
      store(result);
      return;
    }
    job.arm_seq = ++command_seq_;
    job.turntable_seq = command_seq_;
    job.t_commanded = bus::now_s();
    job.deadline = job.t_commanded + r.timeout_s;
    job.rig_utime_commanded = reading_.utime;
    send_commands(job);
    job_ = job;
    bus_.set_state("moving");
  }

  void send_commands(Job& job) {
    arm_command_t a;
    a.utime = bus::now_utime();
    a.seq = job.arm_seq;
    a.num_joints = 6;
    a.joint_position_rad = bus::to_std(job.solution.q);
    a.speed_scale = job.request.speed_scale;
    a.mode = arm_command_t::kModePosition;
    bus_.publish(channels::kArmCommand, a);
    if (rig_.has_turntable) {
      turntable_command_t t;
      t.utime = a.utime;
      t.seq = job.turntable_seq;
      t.angle_rad = job.solution.turntable_rad;
      t.speed_scale = job.request.speed_scale;
      bus_.publish(channels::kTurntableCommand, t);
    }
    job.last_send = bus::now_s();
  }

  bool within_tolerance(const Job& job) const {
    if ((reading_.q - job.solution.q).cwiseAbs().maxCoeff() > kWithinToleranceRad) return false;
    return !rig_.has_turntable || std::abs(reading_.turntable - job.solution.turntable_rad) <= kWithinToleranceRad;
  }

  void finish(Job& job, int8_t status, const std::string& reason) {
    const double now = bus::now_s();
    move_result_t result = blank_result(job.request);
    result.status = status;
    result.reason = reason;
    result.joint_target_rad = bus::to_std(job.solution.q);
    result.joint_position_rad = bus::to_std(reading_.q);
    result.turntable_target_rad = job.solution.turntable_rad;
    result.turntable_angle_rad = reading_.turntable;
    const Pose reached = camera_in_object(rig_, reading_.q, reading_.turntable, job.request.object_z_m);
    const Pose requested = bus::from_msg(job.request.object_T_camera, "request");
    result.reached_object_T_camera = bus::to_msg(reached);
    result.position_error_m = (reached.translation() - requested.translation()).norm();
    result.angle_error_rad = rotation_angle_rad(reached.linear(), requested.linear());
    result.plan_s = job.plan_s;
    result.move_s = (job.t_within >= 0 ? job.t_within : now) - job.t_commanded;
    result.settle_s = job.t_within >= 0 ? now - job.t_within : 0;
    result.rig_motion_s = (reading_.utime - job.rig_utime_commanded) * 1e-6;
    result.settled_utime = reading_.utime;
    store(result);
    std::ostringstream os;
    os << "request " << job.request.request_id << ": "
       << (status == move_result_t::kReached ? "reached" : "failed: " + reason)
       << " (position error " << result.position_error_m * 1e3 << " mm, move " << result.move_s
       << " s, settle " << result.settle_s << " s)";
    log_info(os.str());
    job_.reset();
    bus_.set_state("idle");
  }

  move_result_t blank_result(const move_request_t& r) const {
    move_result_t m;
    m.utime = bus::now_utime();
    m.scan_id = r.scan_id;
    m.iteration = r.iteration;
    m.request_id = r.request_id;
    m.requested_object_T_camera = r.object_T_camera;
    m.reached_object_T_camera = r.object_T_camera;
    m.position_error_m = m.angle_error_rad = 0;
    m.num_joints = 6;
    m.joint_target_rad = m.joint_position_rad = bus::to_std(reading_.q);
    m.turntable_target_rad = m.turntable_angle_rad = reading_.turntable;
    m.plan_s = m.move_s = m.settle_s = m.rig_motion_s = 0;
    m.settled_utime = 0;
    return m;
  }

  void store(const move_result_t& result) {
    results_[{result.scan_id, result.request_id}] = result;
    order_.push_back({result.scan_id, result.request_id});
    if (order_.size() > kResultsKept) {
      results_.erase(order_.front());
      order_.pop_front();
    }
    bus_.publish(channels::kMoveResult, result);
  }

  static std::pair<std::string, int64_t> key(const move_request_t& r) { return {r.scan_id, r.request_id}; }

  bus::Bus& bus_;
  const RigModel& rig_;
  ReachabilityChecker checker_;
  Reading reading_;
  std::optional<Job> job_;
  long command_seq_ = 0;
  std::map<std::pair<std::string, int64_t>, move_result_t> results_;
  std::deque<std::pair<std::string, int64_t>> order_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbnbv-motion: moves the arm and the turntable to each MOVE_REQUEST's camera pose", "pbnbv-motion"};
  cli::init(app);
  bus::RigOptions rig_options;
  bus::add_rig_options(app, &rig_options);
  return bus::run_service("motion", app, argc, argv, 5, [&](bus::Bus& bus) -> std::function<void()> {
    auto rig = std::make_shared<RigModel>(bus::load_rig(rig_options));
    auto executor = std::make_shared<MotionExecutor>(bus, *rig);
    log_info("ready: " + rig->arm_name + " from " + rig->model_path);
    return [rig, executor] { executor->tick(); };
  });
}
