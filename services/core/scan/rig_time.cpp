#include "core/scan/rig_time.hpp"

#include <algorithm>

#include "core/base/format.hpp"

namespace pbnbv {

MoveRigTime move_rig_time(const MoveResult& r) {
  if (!std::isfinite(r.rig_motion_s) || r.rig_motion_s < 0) return {};
  double settle_s = 0;
  if (r.within_tolerance_utime != 0) {
    settle_s = static_cast<double>(r.settled_utime - r.within_tolerance_utime) * 1e-6;
    if (settle_s < 0 || settle_s > r.rig_motion_s + 1e-6) return {};
  }
  return {std::max(0.0, r.rig_motion_s - settle_s), settle_s};
}

double capture_wait_s(double settled_received_s, double cloud_received_s, const CaptureResult& c) {
  const double s = cloud_received_s - c.process_s - settled_received_s;
  return s >= 0 ? s : RigTime::kUnset;
}

double compute_wait_s(double rig_idle_since_s, double next_received_s, const MoveResult& next) {
  const double s = next_received_s - (next.move_s + next.settle_s) - rig_idle_since_s;
  return s >= 0 ? s : RigTime::kUnset;
}

std::string rig_time_text(const RigTime& t) {
  const auto one = [](double x) { return std::isfinite(x) ? fixed(x, 1) : std::string("-"); };
  return one(t.total_s()) + " s (motion " + one(t.motion_s) + ", settle " + one(t.settle_s) + ", capture " +
         one(t.capture_s) + ", compute " + one(t.compute_s) + ")";
}

}  // namespace pbnbv
