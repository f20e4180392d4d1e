#pragma once
// What `pbnbv scan --external-rig` checks before it starts anything: the rig's drivers answer,
// and the arm can reach the first views around the working volume. Nothing here commands a move.
#include <ostream>
#include <string>
#include <vector>

#include "bus/bus.hpp"
#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/scan_settings.hpp"
#include "rigcheck/rig_check.hpp"

namespace pbnbv::launcher {

// The rig's drivers checked without moving anything (rigcheck::preflight: ARM_STATUS,
// TURNTABLE_STATUS and a DEPTH_FRAME answering a trigger within `timeout_s` each, status rates and
// clocks, joint names and limits, the frame against the rig file's camera); the table is printed
// to `out`. Throws std::runtime_error listing the failed lines when any failed.
rigcheck::PreflightResult check_drivers(bus::Bus& bus, const RigModel& rig, double timeout_s, std::ostream& out);

// Where the scan would move first, and how much of the space around the working volume the arm
// reaches (the next-best-view candidates for B = the working volume), from the rig's state.
struct FirstViews {
  std::vector<Pose> views;                 // object_T_camera: the first view, or every ring view
  std::vector<ViewSolution> solutions;     // per view
  // A next-best-view scan whose first view is unreachable starts from the first reachable of
  // first_view_options (as the scan itself does): that option's index, and why the first failed.
  int first_option = 0;
  std::string first_unreachable_reason;
  int candidates = 0, reachable_candidates = 0;
};
FirstViews plan_first_views(const ScanSettings& s, const RigModel& rig, const rigcheck::PreflightResult& seen);

// Throws std::invalid_argument naming the rig file and the working volume when the arm cannot
// reach the first view nor any of its fallbacks (with the reason), or any of the candidates.
void require_reachable(const FirstViews& f, const ScanSettings& s);

// The dry run's account: for each first view, the joint targets and the turntable angle that
// would be commanded, or why not; the reachable share of the candidates.
std::string describe(const FirstViews& f, const RigModel& rig, const rigcheck::PreflightResult& seen);

// Holds the rig where it is, for when its motion executor is gone: ARM_COMMAND kModeHold, and a
// TURNTABLE_COMMAND to the angle TURNTABLE_STATUS reports (waited for up to 0.5 s), each sent
// three times with one new sequence number (above any the motion executor used: both count from
// the wall clock in microseconds).
void hold_rig(bus::Bus& bus, const std::string& scan_id);

}  // namespace pbnbv::launcher
