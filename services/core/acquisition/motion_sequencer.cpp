#include "core/acquisition/motion_sequencer.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "core/base/format.hpp"

namespace pbnbv {

MotionSequencer::MotionSequencer(const RigModel& rig, int64_t first_command_seq)
    : rig_(rig), checker_(rig), next_seq_(first_command_seq) {}

void MotionSequencer::on_arm_status(const ArmReading& reading, double now_s) {
  arm_ = reading;
  arm_rx_s_ = now_s;
}

void MotionSequencer::on_turntable_status(const TurntableReading& reading, double now_s) {
  turntable_ = reading;
  turntable_rx_s_ = now_s;
}

// The answer's frame before the move: the request echoed, the current readings as targets and
// positions, no errors, no times.
MoveResult MotionSequencer::blank_result(const MoveRequest& r) const {
  MoveResult m;
  m.scan_id = r.scan_id;
  m.iteration = r.iteration;
  m.request_id = r.request_id;
  m.requested_object_T_camera = r.object_T_camera;
  m.reached_object_T_camera = r.object_T_camera;
  m.joint_target_rad = m.joint_position_rad = arm_.joint_position_rad;
  m.turntable_target_rad = m.turntable_angle_rad = turntable_.angle_rad;
  return m;
}

MoveResult MotionSequencer::rejected(const std::string& scan_id, int iteration, int64_t request_id,
                                     const std::string& reason) const {
  MoveRequest r;
  r.scan_id = scan_id;
  r.iteration = iteration;
  r.request_id = request_id;
  MoveResult m = blank_result(r);
  m.status = MoveStatus::kRejected;
  m.reason = reason;
  return m;
}

MotionStep MotionSequencer::on_request(const MoveRequest& r, double now_s) {
  MotionStep step;
  if (job_ && job_->request.scan_id == r.scan_id && job_->request.request_id == r.request_id) {
    return step;  // already moving for it
  }
  MoveResult result = blank_result(r);
  last_scan_ = r.scan_id;
  if (held_ && held_->scan_id == r.scan_id) {
    result.status = MoveStatus::kRejected;
    result.reason = "the rig is held: " + held_->why + " (a new scan or pbnbv scan --resume releases it)";
    step.result = result;
    return step;
  }
  held_.reset();  // another scan: a new one
  if (job_) {
    result.status = MoveStatus::kBusy;
    result.reason = fmt::format("busy with request {}", job_->request.request_id);
    step.result = result;
    return step;
  }
  if (now_s - arm_rx_s_ > kMotionStatusStaleS ||
      (rig_.has_turntable && now_s - turntable_rx_s_ > kMotionStatusStaleS)) {
    result.status = MoveStatus::kRigSilent;
    result.reason = "no recent ARM_STATUS/TURNTABLE_STATUS from the rig: is its driver (or the twin) running?";
    step.result = result;
    return step;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const RigState from{arm_.joint_position_rad, turntable_.angle_rad};
  checker_.set_turntable_choice(r.turntable_choice);
  const ViewSolution solution = checker_.solve(r.object_T_camera, from.q, from.turntable_rad, r.keepout, r.object_z_m);
  RigPath path;
  if (solution.reachable) {
    path = checker_.plan_path(from, {solution.q, solution.turntable_rad}, r.keepout, r.object_z_m);
  }
  const double plan_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!solution.reachable || !path.clear) {
    result.status = MoveStatus::kUnreachable;
    result.reason = solution.reachable ? path.reason : solution.reason;
    result.plan_s = plan_s;
    step.result = result;
    step.keep_result = true;
    return step;
  }
  if (r.plan_only) {
    result.status = MoveStatus::kPlanned;
    result.joint_target_rad = solution.q;
    result.turntable_target_rad = solution.turntable_rad;
    result.plan_s = plan_s;
    result.route = path.route;
    result.path_s = path_s(rig_, from, path.stops, r.speed_scale);
    step.result = result;
    step.keep_result = true;
    return step;
  }
  Job job;
  job.request = r;
  job.solution = solution;
  job.path = path;
  job.from = from;
  job.plan_s = plan_s;
  job.arm_seq = job.turntable_seq = next_seq_++;
  job.t_commanded = now_s + plan_s;  // the commands leave once the plan is made
  job.deadline = job.t_commanded + r.timeout_s;
  job.rig_utime_commanded = arm_.utime;
  job.contacts_commanded = arm_.contacts;
  step = send_commands(job, job.t_commanded);
  job_ = job;
  return step;
}

// The commands of the job (a first send or a re-send, same sequence numbers).
MotionStep MotionSequencer::send_commands(Job& job, double now_s) const {
  MotionStep step;
  ArmCommand a;
  a.seq = job.arm_seq;
  a.joint_position_rad = target(job).q;
  a.speed_scale = job.request.speed_scale;
  step.arm_command = a;
  if (rig_.has_turntable) {
    TurntableCommand t;
    t.seq = job.turntable_seq;
    t.angle_rad = target(job).turntable_rad;
    t.speed_scale = job.request.speed_scale;
    step.turntable_command = t;
  }
  job.last_send = now_s;
  return step;
}

// Every joint, and the turntable, within kMotionWithinToleranceRad of the current stop's targets.
bool MotionSequencer::within_tolerance(const Job& job) const {
  if ((arm_.joint_position_rad - target(job).q).cwiseAbs().maxCoeff() > kMotionWithinToleranceRad) return false;
  return !rig_.has_turntable || std::abs(turntable_.angle_rad - target(job).turntable_rad) <= kMotionWithinToleranceRad;
}

// Why the job is not done at its deadline: a silent status, an unacknowledged command, or how
// far the joint furthest from its target (and the turntable) still are.
std::string MotionSequencer::timeout_reason(const Job& job, double now_s) const {
  std::string why = fmt::format("not settled after {} s: ", exact(job.request.timeout_s));
  const bool turntable = rig_.has_turntable;
  if (now_s - arm_rx_s_ > kMotionStatusStaleS) {
    return why + fmt::format("no ARM_STATUS for {} s", fixed(now_s - arm_rx_s_, 2));
  }
  if (turntable && now_s - turntable_rx_s_ > kMotionStatusStaleS) {
    return why + fmt::format("no TURNTABLE_STATUS for {} s", fixed(now_s - turntable_rx_s_, 2));
  }
  if (arm_.command_seq != job.arm_seq) {
    return why + fmt::format("ARM_STATUS never acknowledged command seq {}", job.arm_seq);
  }
  if (turntable && turntable_.command_seq != job.turntable_seq) {
    return why + fmt::format("TURNTABLE_STATUS never acknowledged command seq {}", job.turntable_seq);
  }
  if (job.stop + 1 < job.path.stops.size()) {
    why += fmt::format("at stop {} of {} of the detour ({}): ", job.stop + 1, job.path.stops.size(), job.path.route);
  }
  const Vector6d err = (arm_.joint_position_rad - target(job).q).cwiseAbs();
  int worst = 0;
  err.maxCoeff(&worst);
  why += fmt::format("joint {} is {} rad from its target", rig_.joint_names.at(worst), fmt::format("{:.4g}", err[worst]));
  if (turntable) {
    why += fmt::format(", turntable {} rad from its target",
                       fmt::format("{:.4g}", std::abs(turntable_.angle_rad - target(job).turntable_rad)));
  }
  if (arm_.mode != RigMode::kSettled && arm_.mode != RigMode::kIdle) why += ", arm not settled";
  if (turntable && turntable_.mode != RigMode::kSettled && turntable_.mode != RigMode::kIdle) {
    why += ", turntable not settled";
  }
  if (arm_.fault_code != RigFault::kNone) why += "; arm fault: " + arm_.fault;
  if (turntable && turntable_.fault_code != RigFault::kNone) why += "; turntable fault: " + turntable_.fault;
  return why;
}

MotionStep MotionSequencer::tick(double now_s) {
  if (!job_) return {};
  Job& job = *job_;
  // A fault tied to this job's command, by its sequence number.
  const bool arm_fault = arm_.fault_code != RigFault::kNone && arm_.fault_command_seq == job.arm_seq;
  const bool turntable_fault = rig_.has_turntable && turntable_.fault_code != RigFault::kNone &&
                               turntable_.fault_command_seq == job.turntable_seq;
  if (arm_fault || turntable_fault) {
    const RigFault code = arm_fault ? arm_.fault_code : turntable_.fault_code;
    const std::string& text = arm_fault ? arm_.fault : turntable_.fault;
    const char* who = arm_fault ? "arm" : "turntable";
    if (code == RigFault::kCommandRejected || code == RigFault::kOutOfLimits) {
      return finish(MoveStatus::kUnreachable, fmt::format("the rig rejected the command: {}", text), now_s);
    }
    return finish(MoveStatus::kTimedOut,
                  fmt::format("the {} driver reported a {} fault on command seq {}: {}", who, to_string(code),
                              arm_fault ? job.arm_seq : job.turntable_seq, text),
                  now_s);
  }
  MotionStep step;
  const bool arm_acknowledged = arm_.command_seq == job.arm_seq;
  const bool turntable_acknowledged = !rig_.has_turntable || turntable_.command_seq == job.turntable_seq;
  if ((!arm_acknowledged || !turntable_acknowledged) && now_s - job.last_send > kMotionResendAfterS) {
    const std::string warning = fmt::format("rig has not acknowledged command seq {} after {} s: re-sending",
                                            job.arm_seq, fixed(now_s - job.last_send, 2));
    step = send_commands(job, now_s);
    step.warnings.push_back(warning);
  }
  const bool acknowledged = arm_acknowledged && turntable_acknowledged;
  if (acknowledged && within_tolerance(job) && job.stop + 1 < job.path.stops.size()) {
    // A detour's stop reached: on to the next (new sequence numbers: a new command).
    ++job.stop;
    job.arm_seq = job.turntable_seq = next_seq_++;
    MotionStep next = send_commands(job, now_s);
    next.warnings = step.warnings;
    return next;
  }
  const bool within = acknowledged && within_tolerance(job);
  if (within && job.t_within < 0) {
    job.t_within = now_s;
    job.rig_utime_within = arm_.utime;
  }
  const bool settled = (arm_.mode == RigMode::kSettled || arm_.mode == RigMode::kIdle) &&
                       (!rig_.has_turntable || turntable_.mode == RigMode::kSettled ||
                        turntable_.mode == RigMode::kIdle);
  if (within && settled) {
    MotionStep done = finish(MoveStatus::kReached, "", now_s);
    done.arm_command = step.arm_command;
    done.turntable_command = step.turntable_command;
    done.warnings = step.warnings;
    return done;
  }
  if (now_s > job.deadline) {
    MotionStep done = finish(MoveStatus::kTimedOut, timeout_reason(job, now_s), now_s);
    done.arm_command = step.arm_command;
    done.turntable_command = step.turntable_command;
    done.warnings = step.warnings;
    return done;
  }
  return step;
}

// Ends the job: the answer at the current readings, the reached pose by forward kinematics,
// its errors and the move's times.
MotionStep MotionSequencer::finish(MoveStatus status, const std::string& reason, double now_s) {
  const Job& job = *job_;
  MoveResult result = blank_result(job.request);
  result.status = status;
  result.reason = reason;
  result.joint_target_rad = job.solution.q;
  result.turntable_target_rad = job.solution.turntable_rad;
  const Pose reached = camera_in_object(rig_, arm_.joint_position_rad, turntable_.angle_rad, job.request.object_z_m);
  const Pose& requested = job.request.object_T_camera;
  result.reached_object_T_camera = reached;
  result.position_error_m = (reached.translation() - requested.translation()).norm();
  result.angle_error_rad = rotation_angle_rad(reached.linear(), requested.linear());
  result.plan_s = job.plan_s;
  result.move_s = (job.t_within >= 0 ? job.t_within : now_s) - job.t_commanded;
  result.settle_s = job.t_within >= 0 ? now_s - job.t_within : 0;
  result.rig_motion_s = (arm_.utime - job.rig_utime_commanded) * 1e-6;
  result.settled_utime = arm_.utime;
  result.route = job.path.route;
  result.path_s = path_s(rig_, job.from, job.path.stops, job.request.speed_scale);
  // The contacts the rig counted since the command (a driver restarted meanwhile counts from 0:
  // all of its count), and the last one's text.
  if (job.contacts_commanded < 0 || arm_.contacts < 0) {
    result.contacts = -1;
  } else {
    result.contacts = arm_.contacts >= job.contacts_commanded ? arm_.contacts - job.contacts_commanded : arm_.contacts;
    if (result.contacts > 0) result.contact = arm_.last_contact;
  }
  result.within_tolerance_utime = job.rig_utime_within;
  job_.reset();
  MotionStep step;
  step.result = result;
  step.keep_result = true;
  return step;
}

MotionStep MotionSequencer::halt(const std::string& why, double now_s, const std::string& scan_id) {
  MotionStep step;
  held_ = Held{scan_id.empty() ? last_scan_ : scan_id, why};
  if (job_) step = finish(MoveStatus::kRejected, "halted: " + why, now_s);
  ArmCommand hold;
  hold.seq = next_seq_++;
  hold.joint_position_rad = arm_.joint_position_rad;
  hold.hold = true;
  step.arm_command = hold;
  if (rig_.has_turntable) {
    TurntableCommand t;
    t.seq = next_seq_++;
    t.angle_rad = turntable_.angle_rad;
    step.turntable_command = t;
  }
  return step;
}

}  // namespace pbnbv
