#pragma once
// What `pbnbv scan --external-rig` checks before it starts anything: the rig's drivers answer,
// and the arm can reach the first views around the working volume. Nothing here commands a move.
#include <string>
#include <vector>

#include "bus/bus.hpp"
#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/scan_settings.hpp"

namespace pbnbv::launcher {

// What the drivers showed while the launcher waited for them.
struct DriversSeen {
  Vector6d q = Vector6d::Zero();  // the arm's joints
  double turntable_rad = 0;
  CameraIntrinsics camera;        // of the frame that answered the trigger
  DepthRange range;
  int frame_width = 0, frame_height = 0;
  double arm_status_hz = 0, turntable_status_hz = 0;
};

// Waits up to `timeout_s` for each of ARM_STATUS, TURNTABLE_STATUS (when the rig has a turntable)
// and a DEPTH_FRAME answering a DEPTH_TRIGGER of `scan_id` (sent every second), then measures the
// status rates for 0.5 s. Throws std::runtime_error naming what is missing ("no ARM_STATUS in 10 s:
// ...") or wrong (joint names, a joint outside the rig file's limits, a status rate under 50 Hz, a
// frame that does not decode or whose camera disagrees with the rig file's). Sends triggers only.
DriversSeen wait_for_drivers(bus::Bus& bus, const RigModel& rig, const std::string& scan_id, double timeout_s);

// Where the scan would move first, and how much of the space around the working volume the arm
// reaches (the next-best-view candidates for B = the working volume), from the rig's state.
struct FirstViews {
  std::vector<Pose> views;                 // object_T_camera: the first view, or every ring view
  std::vector<ViewSolution> solutions;     // per view
  int candidates = 0, reachable_candidates = 0;
};
FirstViews plan_first_views(const ScanSettings& s, const RigModel& rig, const DriversSeen& seen);

// Throws std::invalid_argument naming the rig file and the working volume when the arm cannot
// reach the first view (with the reason) or any of the candidates.
void require_reachable(const FirstViews& f, const ScanSettings& s);

// The dry run's account: for each first view, the joint targets and the turntable angle that
// would be commanded, or why not; the reachable share of the candidates.
std::string describe(const FirstViews& f, const RigModel& rig, const DriversSeen& seen);

// Holds the rig where it is, for when its motion executor is gone: ARM_COMMAND kModeHold, and a
// TURNTABLE_COMMAND to the angle TURNTABLE_STATUS reports (waited for up to 0.5 s), each sent
// three times with one new sequence number (above any the motion executor used: both count from
// the wall clock in microseconds).
void hold_rig(bus::Bus& bus, const std::string& scan_id);

}  // namespace pbnbv::launcher
