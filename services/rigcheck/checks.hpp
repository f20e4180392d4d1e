#pragma once
// The checks of `pbnbv rig-check` on what was recorded from the drivers, as plain functions (no
// bus): each returns one line of the table, passed or not, with the measured figure and, when it
// fails, a sentence naming the fault. rig_check.hpp records the samples on the bus and calls
// these.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/rig/rig.hpp"
#include "core/scan/rig_readings.hpp"

namespace pbnbv::rigcheck {

// The contract's figures the checks hold a driver to (README "Writing a driver").
inline constexpr double kMinStatusRateHz = 50.0;  // ARM_STATUS / TURNTABLE_STATUS
inline constexpr double kMaxStatusGapS = 1.0;     // the longest a status stream may go quiet
inline constexpr double kNamedStatusGapS = 0.1;   // a shorter hole is said in the line, not failed
// Exposure times may lead the newest status, or trail the status before the trigger, by this
// much (a few status periods at 50 Hz).
inline constexpr double kExposureSlackS = 0.06;
// A measured depth within this fraction of what the rig file's geometry predicts.
inline constexpr double kDepthRatioTolerance = 0.05;
// Pixels whose rays meet the turntable top within this radius of its axis are compared (every
// platter is at least this big; beyond it the table may show).
inline constexpr double kTurntableProbeRadiusM = 0.05;
// A commanded joint may drift this much while it holds (a refused command): rad.
inline constexpr double kHoldToleranceRad = 3e-3;

// One line of the table.
struct CheckLine {
  std::string check;   // what is checked, e.g. "ARM_STATUS rate"
  bool passed = false;
  std::string figure;  // what was measured, e.g. "100.0 Hz"
  std::string detail;  // why it failed (naming the fault), or what it means; may be empty
};

// A status as received: when (host monotonic clock) and its two clocks.
struct StatusSample {
  double received_s = 0;     // monotonic host clock at reception, s
  int64_t utime = 0;         // the status's utime
  int64_t driver_utime = 0;  // the driver's own clock
};

// One status of a driver under command, reduced to what the active checks read (the arm's six
// joints or the turntable's one angle).
struct DriverSample {
  double received_s = 0;
  std::vector<double> position;  // rad (m for gantry slides)
  int64_t command_seq = -1;
  RigMode mode = RigMode::kIdle;
  RigFault fault_code = RigFault::kNone;
  int64_t fault_command_seq = -1;
  std::string fault;
};
DriverSample sample_of(const ArmReading& r, double received_s);
DriverSample sample_of(const TurntableReading& r, double received_s);

// `channel` is published at kMinStatusRateHz or faster, measured on the driver's own clock
// (driver_utime) over the window: the host's reception times say when the network and the
// scheduler delivered the statuses, not when the device produced them (a twin at --speed 20, or
// statuses queued and delivered together, read thousands of Hz on the host's clock). Fails also
// when the driver's clock shows a hole of more than kMaxStatusGapS between two statuses, or when
// the host received nothing for longer than that (a stalled stream). Statuses that arrive in
// bursts (received in less than two thirds of the time they span on the driver's clock) are named
// in the detail with what that means: readings up to the burst's length old.
CheckLine check_status_rate(const std::string& channel, const std::vector<StatusSample>& samples);
// utime and driver_utime both strictly increase from one status to the next.
CheckLine check_clocks_increase(const std::string& channel, const std::vector<StatusSample>& samples);
// The status names the rig file's joints, in order.
CheckLine check_joint_names(const std::vector<std::string>& names, const RigModel& rig);
// Every reading within the rig file's joint limits.
CheckLine check_joints_within_limits(const Vector6d& q, const RigModel& rig);

// A frame that answers trigger `trigger_seq`; `frames_seen` counts every DEPTH_FRAME heard since
// the trigger (a driver that answers without echoing the seq is named as such).
CheckLine check_trigger_answered(const std::optional<DepthFrame>& frame, int64_t trigger_seq, int frames_seen,
                                 int64_t last_trigger_seq_seen, double answer_s, double deadline_s);
// Size, intrinsics, depth range and camera id against the rig file's camera (each line passes
// with "not stated" when the rig file has no camera).
std::vector<CheckLine> check_frame_against_camera(const DepthFrame& frame, const std::optional<RigCamera>& camera);
// Nonzero depths lie inside the frame's own range (the contract reports the rest as 0): a frame
// whose values are in another unit than depth_unit_m says mostly fails this. A frame without a
// valid pixel (an empty scene) passes with nothing compared.
CheckLine check_depth_within_range(const DepthFrame& frame);
// The exposure [start, start + duration] holds utime and lies on the status clock: not before the
// status preceding the trigger (`status_before_utime`) nor after the newest status received with
// the frame (`status_after_utime`), kExposureSlackS either way.
CheckLine check_exposure(const DepthFrame& frame, int64_t status_before_utime, int64_t status_after_utime);
// Depth units against geometry: the frame's depth where forward kinematics (q, the rig's
// hand-eye) puts the turntable top near its axis, against the predicted planar depth; the median
// ratio within kDepthRatioTolerance of 1. Passes as not applicable when the rig has no turntable
// or its top is out of view (a real rig: run rig-check with the platter empty).
CheckLine check_depth_against_geometry(const DepthFrame& frame, const RigModel& rig, const Vector6d& q);

// A commanded move: some sample after `sent_s` echoes `seq`, is within `tolerance_rad` of
// `target` on every joint and reports settled (or idle). Figure: time to settled, largest error.
CheckLine check_move(const std::string& check, const std::vector<DriverSample>& samples, int64_t seq,
                     const std::vector<double>& target, double tolerance_rad, double sent_s);
// A command the driver must refuse: some sample reports kFault with fault_command_seq = `seq`
// and a fault code, and no joint leaves `start` by more than kHoldToleranceRad.
CheckLine check_refused(const std::string& check, const std::vector<DriverSample>& samples, int64_t seq,
                        const std::vector<double>& start);

// The table: check | pass/FAIL | measured figure | detail, columns aligned.
std::string format_table(const std::vector<CheckLine>& lines);
bool all_passed(const std::vector<CheckLine>& lines);

}  // namespace pbnbv::rigcheck
