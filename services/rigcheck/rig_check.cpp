#include "rigcheck/rig_check.hpp"

#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "bus/convert_rig.hpp"
#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/acquisition/motion_sequencer.hpp"
#include "pbnbv/depth_trigger_t.hpp"

namespace pbnbv::rigcheck {

namespace {

constexpr double kRateWindowS = 1.0;     // statuses measured over this long
constexpr double kTriggerRepeatS = 1.0;  // a trigger not answered is sent again after this long
constexpr double kWristStepRad = deg_to_rad(3.0);
constexpr double kTurntableStepRad = deg_to_rad(5.0);
constexpr double kBeyondLimitRad = deg_to_rad(5.0);  // the refused arm target, outside the limit
constexpr double kRefusalWatchS = 1.0;   // how long a refused command must leave the rig still
constexpr double kSpeedScale = 0.25;
constexpr int kWristJoint = 4;           // a5

// What the drivers publish, recorded from the bus while a check runs; unsubscribes when it ends
// (the caller's Bus lives on).
class Recorder {
 public:
  explicit Recorder(bus::Bus& bus) : bus_(bus) {
    // Raw subscriptions (removed when the check ends), each message passed through the message
    // guard before it is decoded, as Bus::subscribe does.
    subs_.push_back(bus.raw().subscribe(channels::kArmStatus, &Recorder::on_raw<arm_status_t, &Recorder::on_arm>, this));
    subs_.push_back(bus.raw().subscribe(channels::kTurntableStatus,
                                        &Recorder::on_raw<turntable_status_t, &Recorder::on_turntable>, this));
    // Statuses queued while the checker is busy (LCM keeps 30 by default: 15 ms of a twin's at
    // 20x), so that a hole in the rates is the driver's, not the checker's.
    for (lcm::Subscription* s : subs_) s->setQueueCapacity(bus::Bus::kStatusQueue);
    subs_.push_back(bus.raw().subscribe(channels::kDepthFrame, &Recorder::on_raw<depth_frame_t, &Recorder::on_frame>, this));
  }
  ~Recorder() {
    for (lcm::Subscription* s : subs_) bus_.raw().unsubscribe(s);
  }
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Handles messages for up to `ms` milliseconds.
  void spin(int ms) { bus_.spin_once(ms); }

  std::vector<StatusSample> arm_clock, turntable_clock;
  std::vector<DriverSample> arm_samples, turntable_samples;
  std::optional<ArmReading> arm;
  std::vector<std::string> arm_names;
  std::optional<TurntableReading> turntable;
  std::string arm_error, turntable_error, frame_error;  // the first malformed message of each

  int64_t wanted_trigger = -1;
  int frames_seen = 0;
  int64_t last_trigger_seen = -1;
  // The frame answering wanted_trigger as received, and decoded (decode_answer) once the status
  // window is over: decoding it (inflating the depth, undistorting it, decoding its colour JPEG)
  // takes tens of milliseconds, in which a twin at 20x real time sends hundreds of statuses that
  // the socket buffer cannot hold, and the rates would show a hole the checker made.
  std::optional<depth_frame_t> answer;
  std::optional<DepthFrame> frame;
  double frame_received_s = 0;
  int64_t status_after_utime = 0;  // newest ARM_STATUS utime heard within 0.1 s of the frame

  // The answer decoded into `frame`, or its error into frame_error.
  void decode_answer() {
    if (!answer || frame || !frame_error.empty()) return;
    try {
      frame = bus::from_msg(*answer);
    } catch (const std::exception& e) {
      frame_error = e.what();
    }
  }

 private:
  // A message that fails the guard or does not decode is dropped, as LCM's typed subscriptions
  // drop one that does not decode: it may be another program's on the same channel.
  template <class T, void (Recorder::*handle)(const lcm::ReceiveBuffer*, const std::string&, const T*)>
  void on_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    T m;
    if (bus::decode_checked(channel, rbuf->data, rbuf->data_size, &m)) (this->*handle)(rbuf, channel, &m);
  }
  void on_arm(const lcm::ReceiveBuffer*, const std::string&, const arm_status_t* m) {
    const double now = bus::now_s();
    arm_clock.push_back(StatusSample{now, m->utime, m->driver_utime});
    try {
      const ArmReading r = bus::from_msg(*m);
      arm = r;
      arm_names = m->joint_names;
      arm_samples.push_back(sample_of(r, now));
      if (answer && now <= frame_received_s + 0.1) status_after_utime = std::max(status_after_utime, m->utime);
    } catch (const std::exception& e) {
      if (arm_error.empty()) arm_error = e.what();
    }
  }
  void on_turntable(const lcm::ReceiveBuffer*, const std::string&, const turntable_status_t* m) {
    const double now = bus::now_s();
    turntable_clock.push_back(StatusSample{now, m->utime, m->driver_utime});
    try {
      const TurntableReading r = bus::from_msg(*m);
      turntable = r;
      turntable_samples.push_back(sample_of(r, now));
    } catch (const std::exception& e) {
      if (turntable_error.empty()) turntable_error = e.what();
    }
  }
  void on_frame(const lcm::ReceiveBuffer*, const std::string&, const depth_frame_t* m) {
    if (wanted_trigger < 0 || answer) return;
    ++frames_seen;
    last_trigger_seen = m->trigger_seq;
    if (m->trigger_seq != wanted_trigger) return;
    answer = *m;
    frame_received_s = bus::now_s();
    status_after_utime = arm ? arm->utime : 0;
  }

  bus::Bus& bus_;
  std::vector<lcm::Subscription*> subs_;
};

std::vector<StatusSample> window(const std::vector<StatusSample>& all, double from_s, double to_s) {
  std::vector<StatusSample> out;
  for (const StatusSample& s : all) {
    if (s.received_s >= from_s && s.received_s <= to_s) out.push_back(s);
  }
  return out;
}

CheckLine heard(const std::string& channel, const std::string& driver, bool got, double after_s, double deadline_s,
                const std::string& malformed) {
  if (!malformed.empty()) {
    return CheckLine{channel + " heard", false, "malformed", channel + " is malformed: " + malformed};
  }
  if (!got) {
    return CheckLine{channel + " heard", false, "none",
                     fmt::format("no {} in {} s: is the {} driver running and on this LCM URL ({})?", channel,
                                 fixed(deadline_s, 1), driver, bus::lcm_url())};
  }
  return CheckLine{channel + " heard", true, fmt::format("after {} s", fixed(after_s, 2)), ""};
}

PreflightResult run_preflight(Recorder& r, bus::Bus& bus, const RigModel& rig, double deadline_s) {
  PreflightResult out;
  const double t0 = bus::now_s();
  const auto have_statuses = [&] { return r.arm && (r.turntable || !rig.has_turntable); };
  while (!have_statuses() && bus::now_s() - t0 < deadline_s) r.spin(20);
  const double statuses_after = bus::now_s() - t0;

  // The status window and one frame, together.
  depth_trigger_t trigger;
  trigger.seq = bus::now_utime();
  trigger.scan_id = "";
  const int64_t status_before_utime = r.arm ? r.arm->utime : 0;
  r.wanted_trigger = trigger.seq;
  const double tw = bus::now_s();
  double last_send = -1e9;
  const bool any_status = r.arm || r.turntable;
  while (true) {
    const double now = bus::now_s();
    const bool window_done = !any_status || now - tw >= kRateWindowS;
    if ((window_done && r.answer && now - r.frame_received_s >= 0.1) || now - tw >= deadline_s) break;
    if (!r.answer && now - last_send >= kTriggerRepeatS) {
      trigger.utime = bus::now_utime();
      bus.publish(channels::kDepthTrigger, trigger);
      last_send = now;
    }
    r.spin(5);
  }
  r.decode_answer();

  out.lines.push_back(heard("ARM_STATUS", "arm", r.arm.has_value(), statuses_after, deadline_s, r.arm_error));
  if (r.arm) {
    out.lines.push_back(check_status_rate("ARM_STATUS", window(r.arm_clock, tw, tw + kRateWindowS)));
    out.lines.push_back(check_clocks_increase("ARM_STATUS", r.arm_clock));
    out.lines.push_back(check_joint_names(r.arm_names, rig));
    out.lines.push_back(check_joints_within_limits(r.arm->joint_position_rad, rig));
    out.q = r.arm->joint_position_rad;
  }
  if (rig.has_turntable) {
    out.lines.push_back(heard("TURNTABLE_STATUS", "turntable", r.turntable.has_value(), statuses_after, deadline_s,
                              r.turntable_error));
    if (r.turntable) {
      out.lines.push_back(check_status_rate("TURNTABLE_STATUS", window(r.turntable_clock, tw, tw + kRateWindowS)));
      out.lines.push_back(check_clocks_increase("TURNTABLE_STATUS", r.turntable_clock));
      out.turntable_rad = r.turntable->angle_rad;
    }
  }
  if (!r.frame && !r.frame_error.empty()) {
    out.lines.push_back(CheckLine{"DEPTH_FRAME answers DEPTH_TRIGGER", false, "malformed",
                                  "the DEPTH_FRAME answering the trigger is malformed: " + r.frame_error});
  } else {
    out.lines.push_back(check_trigger_answered(r.frame, trigger.seq, r.frames_seen, r.last_trigger_seen,
                                               r.frame_received_s - tw, deadline_s));
  }
  if (r.frame) {
    for (CheckLine& l : check_frame_against_camera(*r.frame, rig.camera)) out.lines.push_back(std::move(l));
    out.lines.push_back(check_depth_within_range(*r.frame));
    if (r.arm) out.lines.push_back(check_exposure(*r.frame, status_before_utime, r.status_after_utime));
    out.camera = r.frame->intrinsics;
    out.range = r.frame->range;
  }
  out.passed = all_passed(out.lines);
  return out;
}

// Handles messages until `done()` or `timeout_s`, calling `send()` first and again every second
// while `resend()` says the command is not yet acknowledged.
void drive(Recorder& r, const std::function<void()>& send, const std::function<bool()>& resend,
           const std::function<bool()>& done, double timeout_s) {
  const double t0 = bus::now_s();
  double last_send = -1e9;
  while (bus::now_s() - t0 < timeout_s) {
    if (done()) return;
    if (bus::now_s() - last_send >= 1.0 && (last_send < 0 || resend())) {
      send();
      last_send = bus::now_s();
    }
    r.spin(10);
  }
}

std::vector<double> to_vec(const Vector6d& q) { return std::vector<double>(q.data(), q.data() + 6); }

// The active checks of one driver: a small move, a command it must refuse, back to the start.
struct Trial {
  std::string who;                     // "arm", "turntable"
  std::vector<DriverSample>* samples;  // the recorder's, for this driver
  double speed_limit_rad_s;            // the slowest joint's
  std::function<void(int64_t seq, const std::vector<double>& target, double speed_scale)> send;
};

void run_trial(Recorder& r, const Trial& t, const std::vector<double>& start, const std::vector<double>& moved,
               const std::string& move_what, const std::vector<double>& refused, double refused_speed_scale,
               const std::string& refused_what, int64_t seq, double deadline_s, std::vector<CheckLine>* lines) {
  const auto echoed = [&](int64_t s) { return !t.samples->empty() && t.samples->back().command_seq == s; };
  const auto move = [&](const std::string& check, int64_t s, const std::vector<double>& target) {
    const double sent = bus::now_s();
    // The deadline, plus twice the travel at the commanded speed (a driver that ignored a limit
    // may have gone far).
    const std::vector<double> from = t.samples->empty() ? target : t.samples->back().position;
    double travel = 0;
    for (std::size_t i = 0; i < std::min(from.size(), target.size()); ++i) {
      travel = std::max(travel, std::abs(target[i] - from[i]));
    }
    const double timeout = deadline_s + 2 * travel / (kSpeedScale * t.speed_limit_rad_s);
    drive(r, [&] { t.send(s, target, kSpeedScale); }, [&] { return !echoed(s); },
          [&] { return check_move(check, *t.samples, s, target, kMotionWithinToleranceRad, sent).passed; }, timeout);
    lines->push_back(check_move(check, *t.samples, s, target, kMotionWithinToleranceRad, sent));
  };
  move(t.who + " small move (" + move_what + ")", seq, moved);

  // The refused command: sent once (again after a second if no fault names it), watched for
  // kRefusalWatchS whatever happens, since the rig must also stay still.
  const std::vector<double> here = t.samples->empty() ? moved : t.samples->back().position;
  const std::size_t first = t.samples->size();
  const auto faulted = [&] {
    for (std::size_t i = first; i < t.samples->size(); ++i) {
      if ((*t.samples)[i].fault_command_seq == seq + 1) return true;
    }
    return false;
  };
  drive(r, [&] { t.send(seq + 1, refused, refused_speed_scale); }, [&] { return !faulted(); }, [] { return false; },
        kRefusalWatchS);
  const std::vector<DriverSample> after(t.samples->begin() + static_cast<std::ptrdiff_t>(first), t.samples->end());
  lines->push_back(check_refused(t.who + " refuses " + refused_what, after, seq + 1, here));

  move(t.who + " back to its start", seq + 2, start);
}

}  // namespace

PreflightResult preflight(bus::Bus& bus, const RigModel& rig, double deadline_s) {
  Recorder r(bus);
  return run_preflight(r, bus, rig, deadline_s);
}

PreflightResult rig_check(bus::Bus& bus, const RigModel& rig, double deadline_s) {
  Recorder r(bus);
  PreflightResult out = run_preflight(r, bus, rig, deadline_s);
  // The preflight's frame, taken with the arm still at out.q (rig-check wants the platter empty).
  if (r.frame && r.arm) out.lines.push_back(check_depth_against_geometry(*r.frame, rig, out.q));
  if (!out.passed) {
    out.lines.push_back(CheckLine{"active checks", false, "skipped",
                                  "the passive checks failed: nothing was commanded to move"});
    out.passed = false;
    return out;
  }

  // The arm: a5 by 3 deg (away from its nearer limit) and back; a5 5 deg beyond its upper limit
  // must be refused.
  const Vector6d q0 = out.q;
  const double sign = q0[kWristJoint] + kWristStepRad < rig.q_upper[kWristJoint] - 1e-3 ? 1.0 : -1.0;
  Vector6d q1 = q0;
  q1[kWristJoint] += sign * kWristStepRad;
  Vector6d beyond = q1;
  beyond[kWristJoint] = rig.q_upper[kWristJoint] + kBeyondLimitRad;
  int64_t seq = bus::now_utime();
  const Trial arm{"arm", &r.arm_samples, rig.qd_max.minCoeff(), [&](int64_t s, const std::vector<double>& target, double speed_scale) {
                    ArmCommand c;
                    c.seq = s;
                    c.joint_position_rad = Eigen::Map<const Vector6d>(target.data());
                    c.speed_scale = speed_scale;
                    arm_command_t m = bus::to_msg(c);
                    m.utime = bus::now_utime();
                    bus.publish(channels::kArmCommand, m);
                  }};
  run_trial(r, arm, to_vec(q0), to_vec(q1),
            fmt::format("{} {}{} deg", rig.joint_names[kWristJoint], sign > 0 ? "+" : "-", fixed(rad_to_deg(kWristStepRad), 0)),
            to_vec(beyond), kSpeedScale,
            fmt::format("{} {} deg beyond its limit", rig.joint_names[kWristJoint], fixed(rad_to_deg(kBeyondLimitRad), 0)),
            seq, deadline_s, &out.lines);

  if (rig.has_turntable && r.turntable) {
    // The turntable: 5 deg and back; a quarter turn at speed_scale 2 (outside (0, 1]) refused.
    const double a0 = r.turntable->angle_rad;
    const Trial turntable{"turntable", &r.turntable_samples, rig.turntable_qd_max,
                          [&](int64_t s, const std::vector<double>& target, double speed_scale) {
                            TurntableCommand c;
                            c.seq = s;
                            c.angle_rad = target[0];
                            c.speed_scale = speed_scale;
                            turntable_command_t m = bus::to_msg(c);
                            m.utime = bus::now_utime();
                            bus.publish(channels::kTurntableCommand, m);
                          }};
    seq += 3;
    run_trial(r, turntable, {a0}, {a0 + kTurntableStepRad}, "+5 deg", {a0 + kTurntableStepRad + kPi / 2}, 2.0,
              "speed_scale 2", seq, deadline_s, &out.lines);
  }
  out.passed = all_passed(out.lines);
  return out;
}

}  // namespace pbnbv::rigcheck
