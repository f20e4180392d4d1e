// Checks before an external-rig scan (external_rig.hpp).
#include "launcher/external_rig.hpp"

#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "bus/rig_commands.hpp"
#include "core/base/format.hpp"
#include "core/base/units.hpp"
#include "core/planning/planner.hpp"
#include "core/scan/scan_sequencer.hpp"

namespace pbnbv::launcher {

namespace {

std::string joints_text(const Vector6d& q) {
  std::string t;
  for (int i = 0; i < 6; ++i) t += (i ? ", " : "") + fixed(rad_to_deg(q[i]), 1);
  return t;
}

}  // namespace

rigcheck::PreflightResult check_drivers(bus::Bus& bus, const RigModel& rig, double timeout_s, std::ostream& out) {
  rigcheck::PreflightResult r = rigcheck::preflight(bus, rig, timeout_s);
  out << rigcheck::format_table(r.lines);
  if (!r.passed) {
    std::string failed;
    for (const rigcheck::CheckLine& l : r.lines) {
      if (!l.passed) failed += "\n  " + l.check + ": " + (l.detail.empty() ? l.figure : l.detail);
    }
    throw std::runtime_error("the rig's drivers failed the check (nothing was commanded to move; pbnbv rig-check "
                             "--rig-model " + rig.model_path + " tests them further):" + failed);
  }
  return r;
}

FirstViews plan_first_views(const ScanSettings& s, const RigModel& rig, const rigcheck::PreflightResult& seen) {
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
  if (s.planner != PlannerKind::kRing && !f.solutions.front().reachable) {
    // The scan falls back through first_view_options: show the view it will start from.
    const std::vector<Pose> options = first_view_options(s);
    for (std::size_t i = 1; i < options.size(); ++i) {
      const ViewSolution v = checker.solve(options[i], seen.q, seen.turntable_rad, keepout, s.object_z_m);
      if (!v.reachable) continue;
      f.first_unreachable_reason = f.solutions.front().reason;
      f.first_option = static_cast<int>(i);
      f.views.front() = options[i];
      f.solutions.front() = v;
      break;
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
    throw std::invalid_argument(where + " cannot reach the first view" +
                                (s.planner == PlannerKind::kRing ? std::string() : " nor any of its " + std::to_string(first_view_options(s).size() - 1) + " fallbacks") +
                                ": " + f.solutions.front().reason +
                                " (try --working-volume, --working-distance or --ring-elevation)");
  }
  if (f.reachable_candidates == 0) {
    throw std::invalid_argument(where + ": none of the " + std::to_string(f.candidates) + " candidate views is reachable");
  }
}

std::string describe(const FirstViews& f, const RigModel& rig, const rigcheck::PreflightResult& seen) {
  std::ostringstream os;
  os << "rig now: joints [" << joints_text(seen.q) << "] deg";
  if (rig.has_turntable) os << ", turntable " << fixed(rad_to_deg(seen.turntable_rad), 1) << " deg";
  os << "\n";
  if (f.first_option > 0) {
    os << "the first view is unreachable (" << f.first_unreachable_reason << "); the scan starts from fallback "
       << f.first_option << " of first_view_options\n";
  }
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
  ArmCommand hold;
  hold.seq = bus::now_utime();
  hold.hold = true;
  std::optional<TurntableCommand> turntable;
  if (angle) turntable = TurntableCommand{hold.seq, *angle, 1.0};
  for (int i = 0; i < 3; ++i) {
    bus::publish_rig_commands(bus, hold, turntable, scan_id);
    bus.spin_once(50);
  }
}

}  // namespace pbnbv::launcher
