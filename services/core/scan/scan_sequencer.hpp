#pragma once
// The scan coordinator's per-view sequence as a plain class: plan -> move -> capture ->
// register -> map for each view, then the mesh, driven by the answers it is handed (plain
// structs, core/scan/messages.hpp) and by ticks of a clock the caller reads (`now_s`, seconds
// on a monotonic clock). It never blocks and never touches a bus: each call consumes one event
// or tick and queues what the caller must send (requests, SCAN_STATUS) and print (progress
// lines); the scan's folder is written through ScanRecord.
//
// The sequence (the README's "For each view"):
// - wait until the rig and every service the planner needs have been heard from (startup
//   deadline; the failure lists what is missing);
// - the next view: the ring's (planner "ring"), the first view, or the view scorer's plan
//   (PLAN_REQUEST / VIEW_PLAN) with its next-best alternatives;
// - move there; a view the rig cannot reach is replaced by the plan's next alternative;
// - capture; a failed capture excludes the view and the scan goes on;
// - wait for the registration's and the mapping service's answers to the view; a view the map
//   did not take (e.g. registration rejected it) is excluded from later plans;
//   (the registration service has written its frame and merged it into cloud.ply when accepted);
//   with the map at the rig's pose (settings' map_pose rig, the default) the next view is planned
//   and moved to once the map has answered: the view's registration is awaited meanwhile (its
//   capture request re-sent, the same deadline) and the view is recorded when it comes, before the
//   next view is captured (or anything else recorded, or the scan done);
// - stop on the planner's decision, the surface rule (core/scan/stop_rule.hpp), the view
//   budget, or no view produced;
// - a scan that is done asks the registration service for the mesh of its merged views
//   (MESH_REQUEST / MESH_RESULT) and records it, or why there is none: a mesh that fails does
//   not fail the scan.
// Every request is re-sent with the same request_id while unanswered and has a deadline
// (ScanTimeouts); request ids are unique within the scan and start at a random number. An answer
// is taken only for the request outstanding and only when its fields are what was asked (its
// view, its planner, poses that are rigid transforms, counts within the request's); one that is
// not is refused, counted (scan.json status "answers_refused") and logged, never acted on.
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "core/scan/messages.hpp"
#include "core/scan/scan_record.hpp"
#include "core/scan/scan_settings.hpp"

namespace pbnbv {

// A progress line for the user: "[view 2/10] moving". `ends_view`: the view's last line.
struct ProgressLine {
  std::string text;
  bool ends_view = false;
};

// What the sequencer asks its caller to do, in order: publish a request or a status, print a
// line.
using ScanOutput = std::variant<MoveRequest, CaptureRequest, PlanRequest, MeshRequest, ScanStatus, ProgressLine>;

// A sign of life the readiness wait counts: "ARM_STATUS", "TURNTABLE_STATUS", or
// "heartbeat of <service>".
struct Heard {
  std::string what;
};

// What the sequencer reacts to besides ticks.
using ScanEvent = std::variant<MoveResult, CaptureResult, RegisteredCloud, VoxelMapSummary, EllipsoidSetSummary,
                               ViewPlan, MeshResult, Heard>;

// How long the sequence waits, s.
struct ScanTimeouts {
  double resend_s = 3.0;          // re-send a move or plan request whose answer has not come
                                  // (a move takes seconds of rig time; the executor ignores a
                                  // repeat of the move it is making)
  double rig_silent_s = 600.0;    // a view's move waits this long for silent rig drivers
  double capture_resend_s = 1.0;  // re-send the capture request while the view's CLOUD,
                                  // REGISTERED_CLOUD or VOXEL_MAP has not come (each normally
                                  // follows within 0.5 s)
  double plan_s = 90.0;           // the view scorer's answer (it waits up to 60 s for inputs)
  double move_extra_s = 15.0;     // beyond the move's own timeout
  double answer_s = 60.0;         // the registration's and the mapping service's answer to a view
  double capture_extra_s = 5.0;   // beyond twice the capture timeout (the camera service
                                  // re-triggers within one timeout and then answers)
  double status_period_s = 1.0;   // SCAN_STATUS while nothing changes
  double mesh_s = 600.0;          // the registration service's mesh of the scan (seconds for a
                                  // 10-view scan; the request is re-sent every resend_s)
};

// An answer the sequence waits for: the request that asks for it (none: the answer follows
// from another service's work), re-sent every resend_s until the deadline.
struct Awaited {
  static constexpr double kNever = std::numeric_limits<double>::infinity();
  std::optional<ScanOutput> request;
  int64_t request_id = -1;
  double since_s = 0;             // first sent (or the wait began)
  double last_sent_s = 0;
  double resend_s = kNever;
  double deadline_s = kNever;
  int sends = 0;

  bool expired(double now_s) const { return now_s >= deadline_s; }
  bool resend_due(double now_s) const { return request && now_s - last_sent_s >= resend_s; }
};

// What the scan has done so far: what the next plan request carries and the status counts.
// Everything else about a finished view is in scan.json.
struct ScanSoFar {
  std::vector<Pose> views_taken;           // registered camera poses of mapped views
  std::vector<Pose> excluded;              // views the rig could not reach, capture or map
  double first_quality = std::numeric_limits<double>::quiet_NaN();  // F of the first plan
  int last_map = -1;                       // last view integrated into the map
  int latest_map = -1;                     // last view the mapping service answered
  int64_t latest_map_request = 0;          // that view's capture request (its map answers it)
  Vector6d joints_rad = Vector6d::Zero();  // the rig where the last view was reached
  double turntable_rad = 0;
  int views_done = 0;                      // views that produced a cloud
  int64_t next_request_id = 1;             // request ids are unique within the scan; a new scan
                                           // starts them at a random number (first_request_id)
  int answers_refused = 0;                 // answers with an outstanding id but a field out of range
};

// Where a new scan's request ids start: a random number in [2^32, 2^62) from the system's entropy
// source, so that a sender who has not seen the scan's requests cannot guess an id to answer.
int64_t first_request_id();

// The views a scan knows before it has seen anything (object_T_camera): every view of the ring
// planner, or the first view of a next-best-view scan (--initial-view, else the ring's first), on
// a sphere of radius d_c plus half the diagonal of the expected extent.
std::vector<Pose> views_known_at_start(const ScanSettings& s);

// The first view of a next-best-view scan and what the rig tries when it cannot reach it, in
// order: the first view, then the same distance and elevation 45, 90, 135 and 180 deg round the
// vertical axis (each way), then each azimuth again 20 deg higher and 20 deg lower (elevations
// kept within +-80 deg), all looking at the object centre. A scan fails at view 1 only when the
// rig reaches none of them.
std::vector<Pose> first_view_options(const ScanSettings& s);

class ScanSequencer {
 public:
  // A sequencer for the scan `settings` writing to `out`. Throws std::invalid_argument for a
  // planner it does not know.
  ScanSequencer(ScanSettings settings, std::filesystem::path out, ScanTimeouts timeouts = {});

  // Replays a recorded scan (`pbnbv replay`): view i moves to the recorded view i's poses in
  // `attempts[i]` (the options it tried, in order) instead of the plan's, so the recorded frames
  // are used again; the plan is still asked for and recorded (the view this planner would
  // choose), and a plan to stop does not end the scan. The scan ends after the recorded views.
  // `recorded`: the recording's scan.json, named in the record. Call before start().
  void replay(std::vector<std::vector<Pose>> attempts, const std::string& recorded);

  // Starts the readiness wait at now_s (SCAN_STATUS "starting").
  void start(double now_s);
  // Continues the scan recorded in the folder (scan.json, cloud.ply) instead: the views taken and
  // excluded, the first plan's quality, the last map, the rig's last reading, the request ids
  // used; after the readiness wait the next view follows the last recorded one. A scan whose
  // record says it ended "done" finishes at once. Throws std::invalid_argument naming the file
  // when the folder holds no record of this scan.
  void resume(double now_s);
  // Consumes one answer or sign of life. Answers of another scan, and answers to requests
  // that are no longer waited for, are ignored.
  void handle(const ScanEvent& event, double now_s);
  // Re-sends what is due, fails what is past its deadline, publishes the periodic status.
  void tick(double now_s);
  // The scan is stopped from outside (the user; the launcher gone): it ends "stopped" with `why`
  // as its message, the view in progress is not recorded.
  void stop(double now_s, const std::string& why = "stopped by the user");
  // The scan cannot go on for a reason outside the sequence (a full disk): it ends "failed" with
  // `why` as its message, the view in progress is not recorded; the folder stays resumable.
  void abort(double now_s, const std::string& why);

  // What to send and print since the last call, in order.
  std::vector<ScanOutput> take_outputs();

  bool finished() const { return phase_ == Phase::kFinished; }
  // 0 done, 1 failed, 130 stopped (valid once finished).
  int exit_code() const;
  ScanState state() const { return state_; }
  // The closing line: "scan complete: ...: 3 of 3 views, 1234 points, 12.00 s -> DIR/scan.json".
  const std::string& summary() const { return summary_; }
  const ScanRecord& record() const { return record_; }
  const ScanSoFar& so_far() const { return done_; }

 private:
  enum class Phase { kIdle, kWaitingReady, kPlanning, kMoving, kCapturing, kRegistering, kMapping,
                     kAwaitingRegistration, kMeshing, kFinished };

  void on(const MoveResult& r, double now_s);
  void on(const CaptureResult& c, double now_s);
  void on(const RegisteredCloud& r, double now_s);
  void on(const VoxelMapSummary& m, double now_s);
  void on(const EllipsoidSetSummary& e, double now_s);
  void on(const ViewPlan& p, double now_s);
  void on(const MeshResult& m, double now_s);
  void on(const Heard& h, double now_s);

  void check_ready(double now_s);
  void begin_view(int i, double now_s);
  void begin_plan(double now_s);
  void planned(const ViewPlan& p, double now_s);
  void begin_move(double now_s);
  void send_move(double now_s);
  void moved(const MoveResult& r, double now_s);
  void begin_capture(int64_t not_before_utime, double now_s);
  void captured(const CaptureResult& c, double now_s);
  void begin_register(double now_s);
  void registered(double now_s);
  void begin_map(double now_s);  // waits for the view's map
  void mapped(double now_s);
  // The view's map taken (done_'s plan inputs), with or without its registration.
  void take_map(const VoxelMapSummary& m, double now_s);
  // Records a view with its registration and map, and says so.
  void record_registered(ViewRecord& v, const RegisteredCloud& reg, double now_s);
  // map_pose rig: the view mapped before its registration answered, kept until it does.
  void defer_registration(double now_s);
  void on_deferred(const RegisteredCloud& r, double now_s);
  // Until the deferred view is recorded, nothing later is: a move's answer and the scan's end wait
  // for it (kAwaitingRegistration); a scan that fails or stops records it as it is.
  void await_registration(double now_s);
  void flush_deferred(double now_s);
  // The stop rule (settings' stop_rule: surface or seconds) on the views so far: ends the scan "done" when it says
  // stop (not at the budget's last view, nor in a replay).
  bool stopped_by_rule(int view, double now_s);
  void next_view(double now_s);
  void fail_view(const std::string& message, double now_s);  // records the view so far, fails the scan
  // Ends the scan; one that is done asks for its mesh first (begin_mesh), then concludes.
  void finish(ScanState state, const std::string& message, double now_s);
  void begin_mesh(const std::string& message, double now_s);
  // Records the mesh, or why there is none, and concludes.
  void meshed(const std::optional<MeshSummary>& mesh, const std::string& why_not, double now_s);
  void conclude(ScanState state, const std::string& message, double now_s);
  // Rig time's compute (core/scan/rig_time.hpp): the rig's part of the view about to be recorded
  // at the end of "views" ended at since_s (coordinator's clock); the wait ends with the next
  // move's answer or the scan's end, and is recorded in that view.
  void begin_rig_wait(double since_s);
  void end_rig_wait(double compute_s);

  void send(const ScanOutput& request, int64_t request_id, double resend_s, double deadline_s, double now_s);
  void wait_for_answer(double deadline_s, double now_s);
  // What a deadline missed: "the mapping service sent no VOXEL_MAP for view 3 in 60 s (the capture
  // request sent 21 times)".
  std::string waited(const std::string& from, const std::string& what, const std::string& request) const;
  int64_t next_request_id() {
    record_.set_next_request_id(done_.next_request_id + 1);
    return done_.next_request_id++;
  }
  CaptureRequest capture_request(int iteration, int64_t request_id, int64_t not_before_utime) const;
  // Refuses an answer to the outstanding request: counted, recorded and logged (the first 20).
  void refuse(const std::string& what, const std::string& why);
  void progress(const std::string& what, bool ends_view = false);
  void set_status(ScanState state, const std::string& message, double now_s);
  void publish_status(double now_s);
  std::string view_name() const { return "view " + std::to_string(iteration_ + 1); }

  ScanSettings s_;
  ScanTimeouts t_;
  ScanRecord record_;
  std::vector<Pose> ring_;                  // planner "ring": every view
  Pose first_view_ = Pose::Identity();      // next-best-view planners: the first view

  ScanSoFar done_;
  std::optional<VoxelMapSummary> latest_map_summary_;
  std::map<int, EllipsoidSetSummary> ellipsoids_;  // by map view, from done_.latest_map on
  std::optional<ScanStop> stop_;

  // The view in progress.
  Phase phase_ = Phase::kIdle;
  int iteration_ = 0;
  ViewRecord view_;
  double t_view_s_ = 0, t_step_s_ = 0;      // the view's start, the current step's start
  std::vector<Pose> options_;               // the planned view and its alternatives
  std::size_t option_ = 0;
  MoveResult moved_;
  double t_settled_s_ = 0;                  // when its answer came (rig time's capture starts)
  int64_t capture_id_ = -1;
  CaptureRequest capture_request_;          // re-sent while the view's answers are late
  std::optional<RegisteredCloud> registered_;  // kept when it comes before it is waited for
  std::optional<VoxelMapSummary> map_;
  Awaited awaited_;
  std::string done_message_;                // the scan's closing message while its mesh is made
  struct RigWait {
    std::size_t index = 0;                  // the waiting view's entry in "views"
    double since_s = 0;                     // when the rig's part of it ended
  };
  std::optional<RigWait> rig_wait_;         // none: no view waits (the first; after a resume)
  struct Deferred {                         // map_pose rig: a view mapped, its registration awaited
    ViewRecord view;
    std::size_t taken = 0;                  // its entry in done_.views_taken (the rig's pose until
                                            // registered), when the map took it (view.map->updated)
    CaptureRequest capture_request;         // re-sent while the registration is late; its request_id
                                            // is the one the registration answers
    double since_s = 0, last_sent_s = 0;
    int sends = 0;
    double t_view_s = 0;                    // the view's start
  };
  std::optional<Deferred> deferred_;
  std::optional<MoveResult> held_move_;     // a move's answer waiting for the deferred view
  struct HeldFinish {
    ScanState state;
    std::string message;
  };
  std::optional<HeldFinish> held_finish_;   // the scan's end waiting for the deferred view
  bool held_next_view_ = false;             // the budget's end waiting for it
  double t_captured_s_ = 0;                 // when the view's CLOUD came

  std::optional<std::vector<std::vector<Pose>>> replay_;  // replaying: each recorded view's poses
  int next_view_after_ready_ = 0;           // the view after the readiness wait (resume: the next)
  bool paused_ = false;                     // the rig's drivers are silent: waiting for them
  std::set<std::string> seen_;
  double t_start_s_ = 0;
  double last_status_s_ = 0;
  ScanState state_ = ScanState::kStarting;
  std::string message_;
  std::string summary_;
  std::vector<ScanOutput> outputs_;
};

}  // namespace pbnbv
