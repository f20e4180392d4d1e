#pragma once
// A recorded scan's rig played back, without a bus (pbnbv-replay-rig wires it to the rig
// channels): the recording's arm and turntable statuses and depth frames, in the order they were
// logged, are split into the views the rig was commanded to; a position command is matched to the
// recorded view commanded to the same targets, and the rig then reports that view's recorded
// readings from the moment it was still (the commands' seq echoed) up to the frame's exposure; a
// trigger is answered with the view's recorded frame, after which the readings just after the
// exposure are reported and the last one held. A command no recorded view was given is refused
// (the rig's fault, as a driver refuses a target it cannot reach). The caller publishes the
// statuses this class names, one per tick (the driver's status period), with their recorded
// values and times.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/base/pose.hpp"

namespace pbnbv {

// A command's targets equal a recorded command's within this (rad): the replayed motion executor
// solves the same inverse kinematics from the same readings.
inline constexpr double kReplayTargetToleranceRad = 1e-4;
// Still readings played before a view's frame, and readings played after its exposure (rig time).
inline constexpr int64_t kReplayBeforeFrameUs = 300000;
inline constexpr int64_t kReplayAfterFrameUs = 200000;

// What the player needs of one recorded status: its rig time, where it was in the log, whether
// the device was still (mode settled or idle), the command it was following.
struct RecordedStatus {
  int64_t utime = 0;
  int64_t order = 0;  // event number in the log (over every file, in order)
  bool still = false;
  int64_t command_seq = -1;                    // the command acknowledged (-1: none yet)
  Vector6d commanded_rad = Vector6d::Zero();   // its target as the status reports it (turntable: [0])
};

// A recorded position command (the arm's joints, or the turntable's angle in joint 0).
struct RecordedCommand {
  int64_t order = 0;
  int64_t seq = 0;
  Vector6d target_rad = Vector6d::Zero();
};

// A recorded depth frame answering one of the scan's triggers.
struct RecordedFrame {
  int64_t utime = 0;  // exposure, rig time
  int64_t order = 0;
};

// The rig channels of one recorded scan, each list in log order.
struct RigTimeline {
  std::vector<RecordedStatus> arm, turntable;
  std::vector<RecordedCommand> arm_commands, turntable_commands;
  std::vector<RecordedFrame> frames;
  bool has_turntable() const { return !turntable.empty(); }
};

// The statuses played for one view: [begin, end) of a device's list; at_frame is the last one
// logged before the frame (the rig holds there until the trigger). When the log lost the still
// readings before the exposure (lcm-logger drops messages under load), at_frame is the first still
// one after it, played before the trigger with the exposure's time (`restamp_utime`): the rig was
// still then, the frame was taken after it settled.
struct StatusSpan {
  std::size_t begin = 0, at_frame = 0, end = 1;
  std::optional<int64_t> restamp_utime;
  // The log's reading nearest the exposure is further from it than half the recording's status
  // period: the reading the scan's camera used is not in the log, and the replayed camera pose
  // differs from the recorded one by what the rig moved in between.
  bool nearest_reading_lost = false;
};

// A stop of a detour the motion executor took on its way to a view (a retreat, a turn, home): the
// command's targets and the statuses the rig reported while it followed it, from the first still
// one to the last (at_frame = end - 1: held until the next command).
struct RecordedStop {
  int64_t arm_command_seq = -1;
  Vector6d arm_target_rad = Vector6d::Zero();
  std::optional<double> turntable_target_rad;
  StatusSpan arm, turntable;
};

// One recorded view: the frame the scan used (the last frame the rig took while following the
// view's command), the targets it was commanded to, and the statuses played for it. The command is
// the one the arm's status acknowledged at the frame (the log may have lost the command itself:
// the target is then the one the status reports).
struct RecordedView {
  std::size_t frame = 0;
  int64_t arm_command_seq = -1;
  Vector6d arm_target_rad = Vector6d::Zero();
  std::optional<double> turntable_target_rad;
  StatusSpan arm, turntable;
  // The detour's stops commanded after the previous view's frame and before this view's command,
  // in order (empty: the move went straight).
  std::vector<RecordedStop> stops;
};

// The views of a recording, in order. Throws std::invalid_argument when it has no arm status, no
// frame, or a frame taken before the arm acknowledged any command.
std::vector<RecordedView> recorded_views(const RigTimeline& t);

class ReplayRig {
 public:
  // Statuses to publish on a tick: indices into the timeline's arm and turntable lists.
  // `*_utime`: publish the status with this time instead of its own (StatusSpan::restamp_utime).
  struct Statuses {
    std::size_t arm = 0;
    std::optional<std::size_t> turntable;
    std::optional<int64_t> arm_utime, turntable_utime;
  };

  // Throws std::invalid_argument as recorded_views does.
  explicit ReplayRig(const RigTimeline& timeline);

  // The statuses of this tick; playback advances by one status per tick.
  Statuses tick();

  // A position command. A stop of the next recorded view's detour commanded to these joints is
  // played (no frame is shown there); else the recorded view commanded to them becomes the current
  // one (a repeated seq is ignored); none: the command is refused, the rig keeps holding and reports the
  // fault (arm_fault()) until it accepts a command.
  void on_arm_command(int64_t seq, const Vector6d& target_rad);
  // Hold where you are (STOP): the seq is echoed, nothing moves.
  void on_arm_hold(int64_t seq);
  // A turntable command: accepted when it is the current view's (checked once the arm command of
  // the same seq is in), otherwise refused (turntable_fault()).
  void on_turntable_command(int64_t seq, double angle_rad);
  // A trigger: the current view's frame (an index into the timeline's frames); none before the
  // first command. The readings after the exposure follow.
  std::optional<std::size_t> on_trigger();

  int64_t arm_command_seq() const { return arm_seq_; }
  int64_t turntable_command_seq() const { return turntable_seq_; }
  // The refused command and why ("" : none).
  const std::string& arm_fault() const { return arm_fault_; }
  int64_t arm_fault_seq() const { return arm_fault_seq_; }
  const std::string& turntable_fault() const { return turntable_fault_; }
  int64_t turntable_fault_seq() const { return turntable_fault_seq_; }
  // The current recorded view (-1: before the first command).
  int view() const { return view_; }
  // The stop of the next view's detour being played (-1: none).
  int detour_stop() const { return stop_; }
  const std::vector<RecordedView>& views() const { return views_; }

 private:
  void check_turntable();
  void enter(int view);
  void play(const StatusSpan& arm, const StatusSpan& turntable, std::optional<double> turntable_target);

  std::vector<RecordedView> views_;
  bool has_turntable_;
  StatusSpan arm_span_, turntable_span_;  // playing
  std::size_t arm_at_ = 0, turntable_at_ = 0;
  bool triggered_ = false;
  int view_ = -1;
  int stop_ = -1;                                   // of views_[view_ + 1].stops
  std::optional<double> expected_turntable_rad_;    // the recorded turntable target of what is played
  int64_t arm_seq_ = -1, turntable_seq_ = -1;
  std::optional<double> turntable_target_;  // of turntable_seq_
  std::string arm_fault_, turntable_fault_;
  int64_t arm_fault_seq_ = -1, turntable_fault_seq_ = -1;
};

}  // namespace pbnbv
