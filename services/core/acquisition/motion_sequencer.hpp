#pragma once
// The motion executor's sequencing, without a bus: a MoveRequest (a camera pose in the object
// frame) is split into a turntable angle and an arm configuration (ReachabilityChecker: IK,
// joint limits, collisions), and a collision-free path to it is planned from where the rig
// stands (ReachabilityChecker::plan_path: the direct move, or a detour through stops, each
// reached before the next is commanded); the arm and the turntable are commanded with increasing sequence
// numbers; a command the status has not acknowledged is re-sent; the move ends when both
// readings acknowledge their command, are within tolerance of the targets and settled, when a
// driver reports a fault on the command, or at the request's deadline with a reason naming what
// is wrong. Time is the caller's: every call takes `now_s` (seconds on a monotonic clock).
//
// One move at a time: a request while moving is answered kBusy. The service keeps the answers
// (MotionStep::keep_result) to answer a repeated request id again; this class does not.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/rig/rig.hpp"
#include "core/scan/messages.hpp"
#include "core/scan/rig_readings.hpp"

namespace pbnbv {

// Re-send a command whose sequence number the status has not echoed after this long.
inline constexpr double kMotionResendAfterS = 0.5;
// A status older than this (receive time): the rig's driver is silent.
inline constexpr double kMotionStatusStaleS = 1.0;
// Every joint (and the turntable) this close to its target: arrived (settling is the rig's).
inline constexpr double kMotionWithinToleranceRad = 1e-3;

// What one call asks the service to do: publish these commands and this answer.
struct MotionStep {
  std::optional<ArmCommand> arm_command;
  std::optional<TurntableCommand> turntable_command;
  std::optional<MoveResult> result;
  // The answer is final for its request id (store it; a repeat gets it again). False for kBusy
  // and for "no status from the rig": a retry may succeed.
  bool keep_result = false;
  std::vector<std::string> warnings;  // for the service's log (e.g. a re-sent command)
};

class MotionSequencer {
 public:
  // `first_command_seq`: the sequence number of the first command; pass one that a previous
  // run cannot have used (e.g. the wall clock in microseconds), so a fault the driver still
  // reports about an old command is never taken for one about a new command.
  MotionSequencer(const RigModel& rig, int64_t first_command_seq);

  // The latest status of the arm / the turntable, received at now_s.
  void on_arm_status(const ArmReading& reading, double now_s);
  void on_turntable_status(const TurntableReading& reading, double now_s);

  // A valid request. Answers at once kBusy (another request is moving), kTimedOut (no recent
  // status), kUnreachable, or kPlanned (plan_only); otherwise commands the rig and answers later
  // from tick(). The request in progress, repeated, is ignored.
  MotionStep on_request(const MoveRequest& request, double now_s);

  // The answer to a request that failed validation (`reason` names the field): kRejected, at
  // the current readings.
  MoveResult rejected(const std::string& scan_id, int iteration, int64_t request_id,
                      const std::string& reason) const;

  // Advances the move in progress: re-sends unacknowledged commands, and answers reached, the
  // rig's fault on the command, or timed out.
  MotionStep tick(double now_s);

  // STOP: holds the arm where it is and the turntable at its last reading (new commands, sent
  // at once), and answers the move in progress kRejected with `why`. Latched: every later request
  // of the held scan (`scan_id`; "": the scan of the last request) is answered kRejected, the rig
  // not moved, until a request of another scan comes (a new scan) or the executor starts again
  // (`pbnbv scan --resume` starts every process afresh).
  MotionStep halt(const std::string& why, double now_s, const std::string& scan_id = "");
  // The scan STOP holds the rig for, or nullptr.
  const std::string* held_scan() const { return held_ ? &held_->scan_id : nullptr; }

  bool moving() const { return job_.has_value(); }

 private:
  struct Held {
    std::string scan_id;
    std::string why;
  };
  std::optional<Held> held_;  // STOP latched
  std::string last_scan_;     // of the last request
  struct Job {
    MoveRequest request;
    ViewSolution solution;
    RigPath path;              // its stops; the last is the solution's
    RigState from;             // the readings when the move was planned
    std::size_t stop = 0;      // the stop being moved to
    int64_t arm_seq = -1;
    int64_t turntable_seq = -1;
    double plan_s = 0;
    double t_commanded = 0;    // now_s when the commands were first sent
    double t_within = -1;      // first time within tolerance with both acknowledged (-1: not yet)
    double deadline = 0;
    double last_send = 0;
    int64_t rig_utime_commanded = 0;  // arm status utime when commanded
    int32_t contacts_commanded = -1;  // arm status contacts when commanded (-1: the rig cannot tell)
    int64_t rig_utime_within = 0;     // arm status utime at t_within (0: not yet)
  };

  MotionStep send_commands(Job& job, double now_s) const;
  bool within_tolerance(const Job& job) const;
  const RigState& target(const Job& job) const { return job.path.stops.at(job.stop); }
  std::string timeout_reason(const Job& job, double now_s) const;
  MoveResult blank_result(const MoveRequest& r) const;
  MotionStep finish(MoveStatus status, const std::string& reason, double now_s);

  const RigModel& rig_;
  ReachabilityChecker checker_;
  ArmReading arm_;
  TurntableReading turntable_;
  double arm_rx_s_ = -1e9;        // now_s of the last arm status
  double turntable_rx_s_ = -1e9;  // now_s of the last turntable status
  std::optional<Job> job_;
  int64_t next_seq_;
};

}  // namespace pbnbv
