// Rig time: how long the rig's drivers take for a move (rig.hpp).
#include <algorithm>
#include <cmath>

#include "core/rig/rig.hpp"

namespace pbnbv {

double ramp_duration_s(double distance, double speed_limit, double accel_limit) {
  if (!(distance > 1e-9)) return 0.0;  // already there (up to numerical noise): no ramp
  return std::max(1.5 * distance / speed_limit, std::sqrt(6.0 * distance / accel_limit));
}

double arm_move_s(const RigModel& rig, const Vector6d& from, const Vector6d& to, double speed_scale) {
  double t = 0;
  for (int i = 0; i < 6; ++i) {
    t = std::max(t, ramp_duration_s(std::abs(to[i] - from[i]), rig.qd_max[i] * speed_scale, rig.qdd_max[i] * speed_scale));
  }
  return t;
}

double turntable_move_s(const RigModel& rig, double from_rad, double to_rad, double speed_scale) {
  if (!rig.has_turntable) return 0;
  return ramp_duration_s(std::abs(to_rad - from_rad), rig.turntable_qd_max * speed_scale,
                         rig.turntable_qdd_max * speed_scale);
}

double move_s(const RigModel& rig, const RigState& from, const RigState& to, double speed_scale) {
  return std::max(arm_move_s(rig, from.q, to.q, speed_scale),
                  turntable_move_s(rig, from.turntable_rad, to.turntable_rad, speed_scale));
}

double path_s(const RigModel& rig, const RigState& from, const std::vector<RigState>& stops, double speed_scale) {
  double t = 0;
  const RigState* at = &from;
  for (const RigState& s : stops) {
    t += move_s(rig, *at, s, speed_scale);
    at = &s;
  }
  return t;
}

}  // namespace pbnbv
