#pragma once
// scan.json as the coordinator writes it: settings, the view plan, one entry per view with what
// was planned, moved, captured, registered (and the files the registration service wrote for it:
// frames/view_NNN.ply, depth/view_NNN.png, what it added to cloud.ply) and mapped, why the scan
// stopped, the mesh, its status. The coordinator writes this file only; the keys and their
// meaning are the ones services/eval/evaluate.cpp, the tests and the README read. Everything
// written is plain data from the sequence (core/scan/messages.hpp), so a record can be checked
// without a bus.
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/mesh_summary.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/scan/messages.hpp"
#include "core/scan/rig_readings.hpp"
#include "core/scan/rig_time.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/scan/stop_rule.hpp"

namespace pbnbv {

// The plan a view came from: the scorer's answer and the map and ellipsoids it was made from.
struct PlanRecord {
  ViewPlan plan;
  int map_of_view = -1;                              // the view whose map the plan used (0-based; -1 not known)
  double map_update_s = 0;                           // that map's update time (0: not known)
  std::optional<EllipsoidSetSummary> ellipsoids;     // fitted to that map (pbnbv)
};

// The planner step as the paper times it: map update + ellipsoid fit + view selection, in ms.
double planner_step_ms(const PlanRecord& p);
// The planner step as the scan waits for it, in ms: map update + the view scorer's time from the
// request to its answer (waiting for the map and the ellipsoids, the reachability check, the
// ranking). The ellipsoid fitter and the scorer's reachability check both start from the new map
// and run at the same time, so this is less than planner_step_ms by what they overlap. NaN when
// the record does not hold the scorer's wait (or holds one shorter than its reachability check,
// which runs within it).
double planner_critical_ms(const PlanRecord& p);

// A move to an option of a view that did not reach it.
struct FailedMove {
  int option = 0;
  Pose object_T_camera = Pose::Identity();  // the option's pose (a resumed scan excludes it again)
  MoveStatus status = MoveStatus::kRejected;
  std::string reason;
  int64_t request_id = 0;  // its MOVE_REQUEST (0: a record from before rig contacts were recorded)
  int32_t contacts = 0;    // contact events the rig reported during it (-1: the rig cannot tell)
  std::string contact;     // the last one
};

// One entry of scan.json's "views": what became of view `view`. A section is written when
// it is set; the round trips (the coordinator's own clock, s) go with their section.
struct ViewRecord {
  static constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

  int view = 0;
  bool initial_view = false;                 // the scan's first view (no plan asked for)
  std::optional<PlanRecord> plan;            // next-best-view planners after the first view
  std::optional<int> option;                 // the option reached: 0 the planned view, k > 0 alternative k
  Pose requested_object_T_camera = Pose::Identity();  // that option's pose
  std::vector<FailedMove> failed_moves;
  bool move_unanswered = false;              // no MOVE_RESULT before the deadline
  std::optional<MoveResult> move;
  bool capture_unanswered = false;           // no CLOUD after every attempt
  std::optional<CaptureResult> capture;      // its points are not recorded: their count is
  std::size_t capture_points = 0;            // the capture's points
  std::optional<RegisteredCloud> registration;  // with the files written for the view (frame, depth
                                                // image) and what it added to the model
  std::optional<VoxelMapSummary> map;
  // The view's rig time (core/scan/rig_time.hpp): set once its move is answered; its compute
  // once the next move is (or the scan stops).
  std::optional<RigTime> rig_time;
  double move_round_trip_s = kUnset, capture_round_trip_s = kUnset, register_round_trip_s = kUnset,
         map_round_trip_s = kUnset, view_total_s = kUnset;
};

// A move during which the rig reported contacts: an entry of scan.json's "rig_contacts".
struct RigContactRecord {
  int view = 0;            // 0-based (written from 1, as "view")
  int64_t request_id = 0;  // the move's MOVE_REQUEST
  int32_t contacts = 0;    // contact events during it (> 0)
  std::string contact;     // the last one, as the rig told it
  bool operator==(const RigContactRecord& o) const {
    return view == o.view && request_id == o.request_id && contacts == o.contacts && contact == o.contact;
  }
};
// The moves of `views` during which the rig reported contacts, in order: each view's failed moves,
// then the move it reached (a failed move that ended its view is its "move" too: counted once).
// Moves whose rig could not tell (contacts -1) are not among them.
std::vector<RigContactRecord> rig_contacts(const std::vector<ViewRecord>& views);
// Their contact events in all.
int64_t rig_contact_events(const std::vector<RigContactRecord>& contacts);
// "view 3 (request 17): link_6 / platter, ..." ("view 3 (request 17, 2 contacts): ..." for more).
std::string to_string(const RigContactRecord& c);

// Why the scan stopped before or at its view budget.
struct ScanStop {
  std::string reason;
  int after_views = 0;
  std::string rule;  // "planner", "planner failed", "budget", "surface", "seconds", "replay"
  nlohmann::json figures;  // what the rule read (surface, seconds: its parameters and the figures)
};

// The scan's stop rule (settings.stop_rule, stop_rule.hpp) applied to its views so far, of which
// `views_done` were taken: the stop with the rule's reason and the figures it read; none when the
// scan goes on or the rule is off.
std::optional<ScanStop> rule_stop(const ScanSettings& s, const std::vector<ViewRecord>& views, int views_done);

// scan.json's "status".
struct ScanStatusRecord {
  std::string state;  // "running", "done", "stopped", "failed"
  std::string message;
  int views_done = 0, views_planned = 0;
  double elapsed_s = 0;
  std::size_t num_points = 0;    // in the model (cloud.ply) after the last view
  int64_t next_request_id = 1;   // request ids used so far end below this
  int answers_refused = 0;
};

// scan.json's "plan": how the views were chosen. The ring: its radius and elevation; a
// next-best-view planner: its name and the first view.
struct ScanPlanHeader {
  std::string planner;                     // "ring", or the planner's name
  double radius_m = 0, elevation_deg = 0;  // the ring
  Pose initial_view = Pose::Identity();    // a next-best-view planner's first view
};

// scan.json as a whole, read back into the types it is written from: what a resume, a replay,
// the view page, evaluate and the bench read (read_scan_record), and what to_json writes again.
struct RecordedScan {
  std::string pbnbv_version;        // of the pbnbv that wrote it (format_version is checked on reading)
  ScanSettings settings;
  std::optional<ScanPlanHeader> plan;  // none until the scan has started
  std::vector<ViewRecord> views;
  std::optional<ScanStop> stop;
  std::optional<PlanRecord> planning_stopped;
  std::string replay_of;            // a replay: the recording's scan.json
  std::optional<MeshSummary> mesh;
  std::string mesh_error;           // no mesh: why
  ScanStatusRecord status;
};

// scan.json's entries for a view, a plan and a stop.
nlohmann::json to_json(const ViewRecord& v);
nlohmann::json to_json(const PlanRecord& p);
nlohmann::json to_json(const ScanStop& s);
// A view's (or the scan's) "rig_time_s": motion, settle, capture, compute, total (null: not known).
nlohmann::json rig_time_json(const RigTime& t);
// scan.json's "mesh": file, also, method, vertices, triangles, watertight, boundary_loops,
// hole_boundary_length_m, area_m2, volume_m3 (null unless watertight), seconds, settings, ...
nlohmann::json to_json(const MeshSummary& m);
nlohmann::json to_json(const RecordedScan& r);

// The inverses, each field checked (type, range; a frame or depth file that is not the view's
// own is refused): std::invalid_argument naming `where` (the file and the entry) and the field.
ViewRecord view_record_from_json(const nlohmann::json& j, const std::string& where);
PlanRecord plan_record_from_json(const nlohmann::json& j, const std::string& where);
ScanStop scan_stop_from_json(const nlohmann::json& j, const std::string& where);
MeshSummary mesh_summary_from_json(const nlohmann::json& j, const std::string& where);
RecordedScan recorded_scan_from_json(const nlohmann::json& j, const std::string& where);
// A scan folder's (or the file's) scan.json through read_scan_json (its format) into its types.
RecordedScan read_scan_record(const std::filesystem::path& scan_json_or_folder);

// A merged view's frame: its file in the scan's folder and the pose its points were placed with.
struct MergedFrame {
  int view = 0;
  std::filesystem::path file;               // DIR/frames/view_NNN.ply
  Pose object_T_camera = Pose::Identity();
};
// The merged views of the scan recorded in `scan`, folder `dir`, in order. Throws naming the file
// when no view was merged.
std::vector<MergedFrame> merged_frames(const RecordedScan& scan, const std::filesystem::path& dir);
// The poses each recorded view moved to, in order: its failed moves, then the one it reached (a
// replay moves to them again).
std::vector<std::vector<Pose>> recorded_attempts(const RecordedScan& scan);
// Sets the folder's scan.json "mesh" (`pbnbv mesh`, meshing a finished scan again), read and
// written through its types.
void write_scan_mesh(const std::filesystem::path& dir, const MeshSummary& mesh);

// The rig time of a scan's views summed part by part (scan.json's top-level "rig_time_s"): each
// part the sum of the views' known figures (a view's NaN part is left out of that part's sum);
// `views` counts the views with a rig time, `views_incomplete` those of them with a part not
// known. total = the four sums added.
struct RigTimeSum {
  RigTime sum{0, 0, 0, 0};
  int views = 0, views_incomplete = 0;
};
RigTimeSum sum_rig_time(const std::vector<ViewRecord>& views);
// The scan's closing line's rig time: "; rig time 24.1 s (motion ...)" and, when some views were
// not measured in full, " (2 views not measured in full)"; "" when no view was measured.
std::string rig_time_summary(const RigTimeSum& rig);
// The rig time from the start to the end of each view with a frame (the views of
// new_surface_figures, and of coverage by view), s: every view's rig time added up to it, views
// without a frame included; NaN from a view whose rig time is not known in full on; empty when no
// view has a rig time (a record written before rig time was recorded).
std::vector<double> rig_time_at_frames(const std::vector<ViewRecord>& views);

// What each view added to the model (percent_of_model) for the views the registration answered,
// NaN where the view was not merged: the figures the surface stop rule reads, in view order.
std::vector<double> new_surface_figures(const std::vector<ViewRecord>& views);
// The stop rules' figures (stop_rule.hpp), one per view that was captured and registered: the
// new surface (NaN: not merged) and the rig time before computation (motion, settle, capture).
std::vector<ViewGain> view_gains(const std::vector<ViewRecord>& views);

// The coordinator's scan.json: a RecordedScan kept in memory and written whole (atomically) at
// every view and at the end. The only writer of scan.json.
class ScanRecord {
 public:
  // A record of the scan `settings` in folder `out` (created). Nothing is written until the first
  // view or the end.
  ScanRecord(std::filesystem::path out, const ScanSettings& settings);

  // scan.json's "plan": the ring's geometry, or the next-best-view planner and its first view.
  void set_ring_plan(double radius_m, double elevation_deg);
  void set_next_best_view_plan(const std::string& planner, const Pose& initial_view);

  // scan.json's "mesh": the registration service's mesh of the scan, or why there is none
  // (written with the next write).
  void set_mesh(const MeshSummary& mesh);
  void set_no_mesh(const std::string& why);

  // Appends a view to "views" and writes scan.json with state "running".
  void add_view(const ViewRecord& v, int views_done, double elapsed_s);
  void set_stop(const ScanStop& stop);
  void set_planning_stopped(const PlanRecord& p);  // the plan that ended the scan
  // The compute wait of the recorded view at `index` in "views" (written with the next write);
  // nothing when there is no such view or it has no rig time.
  void set_compute_wait(std::size_t index, double compute_s);
  // A replay (`pbnbv replay`) of the scan recorded in `recorded` (its scan.json), `views` views.
  void set_replay_of(const std::string& recorded, int views);
  // Writes scan.json with the status `state` ("running", "done", "stopped", "failed").
  void write(const std::string& state, const std::string& message, int views_done, double elapsed_s);

  // Points in the model (cloud.ply) after the last view: the registration service's count.
  std::size_t num_points() const { return record_.status.num_points; }
  void set_model_points(std::size_t n) { record_.status.num_points = n; }
  // Request ids used so far end below this (written in scan.json's status, so that a resumed
  // coordinator never reuses one a service still has an answer for).
  void set_next_request_id(int64_t id) { record_.status.next_request_id = id; }
  // Answers that carried an outstanding request's id but were refused (a field out of range for
  // what was asked): scan.json's status "answers_refused".
  void set_answers_refused(int n) { record_.status.answers_refused = n; }
  // Continues the record in its folder: scan.json as written so far, read into its types (a
  // resumed scan). Throws naming the file when scan.json is missing, not a scan of `scan_id`, or
  // a field of it is not what this pbnbv writes.
  void continue_from_folder(const std::string& scan_id);
  const RecordedScan& record() const { return record_; }
  std::filesystem::path scan_json_path() const { return out_ / "scan.json"; }

 private:
  std::filesystem::path out_;
  RecordedScan record_;
};

}  // namespace pbnbv
