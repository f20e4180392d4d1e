// Checks before an external-rig scan (external_rig.hpp).
#include "launcher/external_rig.hpp"

#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "bus/convert_rig.hpp"
#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/planning/planner.hpp"
#include "core/scan/scan_sequencer.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/turntable_command_t.hpp"

namespace pbnbv::launcher {

namespace {

constexpr double kMinStatusHz = 50.0;  // the contract's lowest status rate (lcmtypes/*_status_t.lcm)
constexpr double kRateWindowS = 0.5;

std::string joints_text(const Vector6d& q) {
  std::string t;
  for (int i = 0; i < 6; ++i) t += (i ? ", " : "") + fixed(rad_to_deg(q[i]), 1);
  return t;
}

}  // namespace

DriversSeen wait_for_drivers(bus::Bus& bus, const RigModel& rig, const std::string& scan_id, double timeout_s) {
  DriversSeen seen;
  std::optional<arm_status_t> arm;
  std::optional<turntable_status_t> turntable;
  std::optional<depth_frame_t> frame;
  int arm_count = 0, turntable_count = 0;
  const int64_t trigger_seq = bus::now_utime();
  bus.subscribe<arm_status_t>(channels::kArmStatus, [&](const arm_status_t& m) {
    arm = m;
    ++arm_count;
  });
  bus.subscribe<turntable_status_t>(channels::kTurntableStatus, [&](const turntable_status_t& m) {
    turntable = m;
    ++turntable_count;
  });
  bus.subscribe<depth_frame_t>(channels::kDepthFrame, [&](const depth_frame_t& m) {
    if (m.trigger_seq == trigger_seq) frame = m;
  });
  const std::string hint = " (is its driver running, and on this LCM URL: " + bus::lcm_url() + "?)";
  const double t0 = bus::now_s();
  double last_trigger = -1e9;
  while (!(arm && (turntable || !rig.has_turntable) && frame)) {
    const double now = bus::now_s();
    if (now - t0 > timeout_s) {
      std::string missing;
      if (!arm) missing += ", no ARM_STATUS";
      if (!turntable && rig.has_turntable) missing += ", no TURNTABLE_STATUS";
      if (!frame) missing += ", no DEPTH_FRAME answering DEPTH_TRIGGER seq " + std::to_string(trigger_seq);
      throw std::runtime_error("the rig's drivers did not answer in " + fixed(timeout_s, 1) + " s: " + missing.substr(2) + hint);
    }
    if (now - last_trigger >= 1.0) {  // a lost trigger or frame is asked for again
      depth_trigger_t t;
      t.utime = bus::now_utime();
      t.seq = trigger_seq;
      t.scan_id = scan_id;
      bus.publish(channels::kDepthTrigger, t);
      last_trigger = now;
    }
    bus.spin_once(20);
  }
  // Rates over a short window.
  const int arm0 = arm_count, turntable0 = turntable_count;
  const double w0 = bus::now_s();
  while (bus::now_s() - w0 < kRateWindowS) bus.spin_once(10);
  const double window = bus::now_s() - w0;
  seen.arm_status_hz = (arm_count - arm0) / window;
  seen.turntable_status_hz = (turntable_count - turntable0) / window;

  const ArmReading a = bus::from_msg(*arm);  // throws naming a malformed field
  if (static_cast<int>(arm->joint_names.size()) != 6 || arm->joint_names != rig.joint_names) {
    std::string names;
    for (const auto& n : arm->joint_names) names += (names.empty() ? "" : ", ") + n;
    std::string expected;
    for (const auto& n : rig.joint_names) expected += (expected.empty() ? "" : ", ") + n;
    throw std::runtime_error("ARM_STATUS names the joints [" + names + "], the rig file " + rig.model_path + " [" + expected + "]");
  }
  for (int i = 0; i < 6; ++i) {
    const double q = a.joint_position_rad[i];
    if (q < rig.q_lower[i] - 1e-6 || q > rig.q_upper[i] + 1e-6) {
      throw std::runtime_error(fmt::format("ARM_STATUS joint {} at {:.2f} deg is outside the rig file's limits [{:.2f}, {:.2f}] deg "
                                           "({}): is this the rig the file describes?",
                                           rig.joint_names[i], rad_to_deg(q), rad_to_deg(rig.q_lower[i]),
                                           rad_to_deg(rig.q_upper[i]), rig.model_path));
    }
  }
  if (seen.arm_status_hz < kMinStatusHz) {
    throw std::runtime_error(fmt::format("ARM_STATUS arrives at {:.0f} Hz, the contract asks for at least {:.0f} Hz",
                                         seen.arm_status_hz, kMinStatusHz));
  }
  seen.q = a.joint_position_rad;
  if (rig.has_turntable) {
    const TurntableReading t = bus::from_msg(*turntable);
    if (seen.turntable_status_hz < kMinStatusHz) {
      throw std::runtime_error(fmt::format("TURNTABLE_STATUS arrives at {:.0f} Hz, the contract asks for at least {:.0f} Hz",
                                           seen.turntable_status_hz, kMinStatusHz));
    }
    seen.turntable_rad = t.angle_rad;
  }
  DepthFrame f;
  try {
    f = bus::from_msg(*frame);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("the camera's first frame: ") + e.what());
  }
  seen.camera = f.intrinsics;
  seen.range = f.range;
  seen.frame_width = f.intrinsics.width;
  seen.frame_height = f.intrinsics.height;
  return seen;
}

FirstViews plan_first_views(const ScanSettings& s, const RigModel& rig, const DriversSeen& seen) {
  FirstViews f;
  f.views = views_known_at_start(s);
  ReachabilityChecker checker(rig);
  const Eigen::AlignedBox3d keepout(s.keepout_min_m, s.keepout_max_m);
  Vector6d q = seen.q;
  double turntable = seen.turntable_rad;
  for (const Pose& v : f.views) {  // each from where the one before left the rig
    f.solutions.push_back(checker.solve(v, q, turntable, keepout, s.object_z_m));
    if (f.solutions.back().reachable) {
      q = f.solutions.back().q;
      turntable = f.solutions.back().turntable_rad;
    }
  }
  CandidateSpec spec;
  spec.num_views = s.candidates;
  spec.num_parallels = s.parallels;
  spec.area = s.area;
  spec.working_distance_m = s.working_distance_m;
  const Eigen::AlignedBox3d b(s.working_volume ? s.working_volume->bounds()
                                               : Eigen::AlignedBox3d(-s.expected_extent_m() / 2, s.expected_extent_m() / 2));
  const std::vector<Pose> candidates = candidate_views(b, spec);
  f.candidates = static_cast<int>(candidates.size());
  for (const ViewSolution& v : checker.solve_batch(candidates, seen.q, seen.turntable_rad, keepout, s.object_z_m)) {
    f.reachable_candidates += v.reachable ? 1 : 0;
  }
  return f;
}

void require_reachable(const FirstViews& f, const ScanSettings& s) {
  const std::string where = "the arm of " + s.rig_model_path + " around the working volume " +
                            (s.working_volume ? s.working_volume->to_text() : std::string("of the object"));
  if (!f.solutions.empty() && !f.solutions.front().reachable) {
    throw std::invalid_argument(where + " cannot reach the first view: " + f.solutions.front().reason +
                                " (try --working-volume, --working-distance or --ring-elevation)");
  }
  if (f.reachable_candidates == 0) {
    throw std::invalid_argument(where + ": none of the " + std::to_string(f.candidates) + " candidate views is reachable");
  }
}

std::string describe(const FirstViews& f, const RigModel& rig, const DriversSeen& seen) {
  std::ostringstream os;
  os << "rig now: joints [" << joints_text(seen.q) << "] deg";
  if (rig.has_turntable) os << ", turntable " << fixed(rad_to_deg(seen.turntable_rad), 1) << " deg";
  os << "\n";
  for (std::size_t i = 0; i < f.views.size(); ++i) {
    const ViewSolution& v = f.solutions[i];
    const Eigen::Vector3d p = f.views[i].translation();
    os << "view " << i + 1 << " at (" << fixed(p.x(), 3) << ", " << fixed(p.y(), 3) << ", " << fixed(p.z(), 3) << ") m: ";
    if (v.reachable) {
      os << "ARM_COMMAND [" << joints_text(v.q) << "] deg";
      if (rig.has_turntable) os << ", TURNTABLE_COMMAND " << fixed(rad_to_deg(v.turntable_rad), 1) << " deg";
    } else {
      os << "unreachable: " << v.reason;
    }
    os << "\n";
  }
  os << f.reachable_candidates << " of " << f.candidates << " candidate views around the working volume are reachable ("
     << fixed(100.0 * f.reachable_candidates / std::max(1, f.candidates), 1) << " %)\n";
  return os.str();
}

void hold_rig(bus::Bus& bus, const std::string& scan_id) {
  std::optional<double> angle;
  bus.subscribe<turntable_status_t>(channels::kTurntableStatus, [&](const turntable_status_t& m) {
    if (std::isfinite(m.angle_rad)) angle = m.angle_rad;
  });
  for (const double t0 = bus::now_s(); !angle && bus::now_s() - t0 < 0.5;) bus.spin_once(20);
  arm_command_t a{};
  a.seq = bus::now_utime();
  a.scan_id = scan_id;
  a.num_joints = 6;
  a.joint_position_rad.assign(6, 0.0);
  a.speed_scale = 1.0;
  a.mode = arm_command_t::kModeHold;
  turntable_command_t t{};
  t.seq = a.seq;
  t.scan_id = scan_id;
  t.speed_scale = 1.0;
  t.angle_rad = angle.value_or(0.0);
  for (int i = 0; i < 3; ++i) {
    a.utime = t.utime = bus::now_utime();
    bus.publish(channels::kArmCommand, a);
    if (angle) bus.publish(channels::kTurntableCommand, t);
    bus.spin_once(50);
  }
}

}  // namespace pbnbv::launcher
