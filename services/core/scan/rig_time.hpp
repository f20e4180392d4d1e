#pragma once
// Rig time: how long a scan holds the rig, view by view, as a physical rig would spend it. On a
// physical rig a scan's time is the arm's. The twin's rig runs on its own clock (sim time,
// --sim-speed times faster than the wall clock, standing still while the twin renders), so the
// wall durations of the rig's moves are not rig time; everything else (the messages, the camera,
// the computation) takes real wall time on this machine at any speed, and on the twin's clock it
// would count --sim-speed times over. So rig time is the coordinator's wall time from the first
// move's command to the moment the scan stops using the rig, with each move's wall time replaced
// by its time on the rig's clock. A view's rig time has four parts, none overlapping another:
//
// - motion: the move to the view (arm and turntable together), rig clock, from the command to
//   every joint and the turntable within tolerance of their targets (MOVE_RESULT: rig_motion_s
//   less the settling). The first view's move starts where the rig stood at the scan's start.
//   Moves the executor refused (unreachable) move nothing; a move that timed out counts whole.
// - settle: rig clock, from within tolerance to settled (settled_utime - within_tolerance_utime).
// - capture: wall, from the coordinator's receipt of the settled move's answer to the used frame's
//   arrival at the camera service (the coordinator's receipt of the CLOUD less the camera service's
//   processing): the capture request, the trigger, the exposure and the frame's way back (a real
//   camera's readout and transfer; the twin's render) and the camera's wait for the rig's reading
//   after the exposure. A capture that used no frame: to the coordinator's receipt of its answer.
//   No capture (the move failed): 0.
// - compute: wall, the time the rig stands waiting after the view's capture (or failed move) for
//   the next move's command (the coordinator's receipt of the next MOVE_RESULT less the motion
//   executor's wall time from that command to settled), or after the last view for the scan to
//   stop (its registration and map, a plan that says stop): the cloud, registration, map,
//   ellipsoids, plan, the executor's inverse kinematics, the messages between them and any
//   request sent again.
//
// Not in it: the scan's start before the first command (the processes starting, the first
// view's inverse kinematics), and after it stops (the mesh).
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "core/scan/messages.hpp"

namespace pbnbv {

// A view's rig time, s. NaN: not measured (a view whose compute is not known: the scan was
// interrupted before the next command).
struct RigTime {
  static constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();
  double motion_s = kUnset, settle_s = kUnset, capture_s = kUnset, compute_s = kUnset;

  // motion + settle + capture + compute; NaN when a part is NaN.
  double total_s() const { return motion_s + settle_s + capture_s + compute_s; }
  bool complete() const { return std::isfinite(total_s()); }
};

// A move's motion and settling on the rig clock: settle = (settled_utime - within_tolerance_utime)
// / 1e6 (0 when never within tolerance), motion = rig_motion_s - settle. Both NaN when the
// figures do not fit together (rig_motion_s negative or not finite, within tolerance after
// settled or before the command).
struct MoveRigTime {
  double motion_s = RigTime::kUnset, settle_s = RigTime::kUnset;
};
MoveRigTime move_rig_time(const MoveResult& r);

// The capture's time: the coordinator received the settled move's answer at `settled_received_s`
// and the capture's answer `c` at `cloud_received_s` (its clock); the frame arrived at the camera
// service c.process_s before that. NaN when that comes out negative (figures that do not fit).
double capture_wait_s(double settled_received_s, double cloud_received_s, const CaptureResult& c);

// The compute wait from `rig_idle_since_s` (the coordinator's clock when the rig's part of the
// previous view ended) to the next command: the coordinator received that move's answer `next`
// at `next_received_s`, and the command left next.move_s + next.settle_s (the executor's wall
// time from command to settled, or to giving up) before. NaN when that comes out negative.
double compute_wait_s(double rig_idle_since_s, double next_received_s, const MoveResult& next);

// "24.1 s (motion 19.8, settle 1.2, capture 0.4, compute 2.7)", one decimal ("-": not known).
std::string rig_time_text(const RigTime& t);

}  // namespace pbnbv
