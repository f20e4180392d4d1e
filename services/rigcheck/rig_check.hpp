#pragma once
// `pbnbv rig-check` on the bus: exercises whatever drivers speak the rig channels and judges them
// against the contract (README "Writing a driver") and the rig file (checks.hpp does the judging
// on what is recorded here).
//
// preflight() is PASSIVE: it commands nothing to move. It waits (up to the deadline) for
// ARM_STATUS, TURNTABLE_STATUS (when the rig has a turntable) and a DEPTH_FRAME answering a
// DEPTH_TRIGGER it sends, and checks status rates, clocks, joint names and limits, and the frame
// against the rig file's camera. `pbnbv scan --external-rig` calls it before scanning.
//
// rig_check() is preflight() and, only when that passed, the ACTIVE checks: a 3 deg move of the
// wrist joint a5 and back, an out-of-limit arm command that must be refused with a fault code
// and not move the arm, the turntable likewise (5 deg and back; a command with speed_scale 2
// refused), and the frame's depth against the turntable top forward kinematics predict.
#include <string>
#include <vector>

#include "bus/bus.hpp"
#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/rig/rig.hpp"
#include "rigcheck/checks.hpp"

namespace pbnbv::rigcheck {

struct PreflightResult {
  std::vector<CheckLine> lines;  // the table, in order
  bool passed = false;           // every line passed
  // What was seen (valid where the lines say it was heard): the frame's camera and depth range,
  // the arm's joints and the turntable angle (0 without a turntable).
  CameraIntrinsics camera;
  DepthRange range;
  Vector6d q = Vector6d::Zero();
  double turntable_rad = 0;
};

// Waits at most `deadline_s` for each driver (a missing one is a failed line naming it:
// "no ARM_STATUS in 5 s: is the arm driver running and on this LCM URL?"); then measures the
// status streams over 1 s. Never commands a move. Returns in about 1.2 s with healthy drivers,
// at most about 2 x deadline_s otherwise.
PreflightResult preflight(bus::Bus& bus, const RigModel& rig, double deadline_s);

// preflight() plus the active checks (skipped, with a failed line saying nothing was commanded,
// when preflight fails). Each wait is bounded by `deadline_s`.
PreflightResult rig_check(bus::Bus& bus, const RigModel& rig, double deadline_s);

}  // namespace pbnbv::rigcheck
