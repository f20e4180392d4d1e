#pragma once
// The scan's output folder as the coordinator writes it: scan.json (settings, the view plan, one
// entry per view with what was planned, moved, captured, registered and mapped, why the scan
// stopped, its status), frames/view_NNN.ply (each view's cloud, registered when accepted) and
// cloud.ply (the accepted views merged and downsampled). The keys and their meaning are the ones
// services/eval/evaluate.cpp, the tests and the README read; everything written is plain data
// from the sequence (core/scan/messages.hpp), so a record can be checked without a bus.
#include <deque>
#include <filesystem>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/point_cloud.hpp"
#include "core/scan/messages.hpp"
#include "core/scan/rig_readings.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/scan/stop_rule.hpp"
#include "core/surface/surface.hpp"

namespace pbnbv {

// The plan a view came from: the scorer's answer and the map and ellipsoids it was made from.
struct PlanRecord {
  ViewPlan plan;
  int map_of_view = -1;                              // the view whose map the plan used
  double map_update_s = 0;                           // that map's update time (0: not known)
  std::optional<EllipsoidSetSummary> ellipsoids;     // fitted to that map (pbnbv)
};

// The planner step as the paper times it: map update + ellipsoid fit + view selection, in ms.
double planner_step_ms(const PlanRecord& p);

// A move to an option of a view that did not reach it.
struct FailedMove {
  int option = 0;
  Pose object_T_camera = Pose::Identity();  // the option's pose (a resumed scan excludes it again)
  MoveStatus status = MoveStatus::kRejected;
  std::string reason;
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
  std::optional<CaptureResult> capture;
  std::optional<RegisteredCloud> registration;
  std::optional<VoxelMapSummary> map;
  std::string frame_file;                    // "frames/view_NNN.ply" once written
  std::string normals;                       // how the frame's normals were found: "depth image", "neighbours"
  std::string depth_file;                    // "depth/view_NNN.png" once written (its intrinsics: view_NNN.json)
  bool merged = false;                       // merged into cloud.ply
  std::optional<NewSurface> new_surface;     // what it added to the model (merged views)
  double move_round_trip_s = kUnset, capture_round_trip_s = kUnset, register_round_trip_s = kUnset,
         map_round_trip_s = kUnset, accumulate_s = kUnset, view_total_s = kUnset;
};

// Why the scan stopped before or at its view budget.
struct ScanStop {
  std::string reason;
  int after_views = 0;
  std::string rule;  // "planner", "planner failed", "budget", "surface"
  nlohmann::json figures;  // what the rule read (surface: its parameters and the window's figures)
};

// scan.json's entries for a view, a plan and a stop.
nlohmann::json to_json(const ViewRecord& v);
nlohmann::json to_json(const PlanRecord& p);
nlohmann::json to_json(const ScanStop& s);

class ScanRecord {
 public:
  // A record of the scan `settings` in folder `out` (created, with out/frames). Nothing is
  // written until the first view or the end.
  ScanRecord(std::filesystem::path out, const ScanSettings& settings);

  // scan.json's "plan": the ring's geometry, or the next-best-view planner and its first view.
  void set_ring_plan(double radius_m, double elevation_deg);
  void set_next_best_view_plan(const std::string& planner, const Pose& initial_view);

  // A depth frame the camera sent: accumulate finds a view's frame among the last few by its
  // depth_frame_seq (normals from its neighbourhood; depth/view_NNN.png with the writer below).
  void keep_depth_frame(DepthFrame frame);
  // Writes a depth image (m, row-major, 0 = no reading) as a 16-bit PNG of millimetres; set by
  // the coordinator (OpenCV lives in report/). Unset: no depth/ folder.
  using DepthImageWriter = std::function<void(const std::vector<float>& depth_m, int width, int height, const std::string& path)>;
  void set_depth_image_writer(DepthImageWriter writer) { depth_writer_ = std::move(writer); }

  // Writes the view's cloud (registered when accepted) to frames/view_NNN.ply and, when the
  // registration accepted it, merges it into cloud.ply (voxel-downsampled at the settings'
  // voxel_m), both with normals facing the camera (from the view's depth frame when it was kept,
  // else from each point's nearest neighbours) and the camera poses in the header; writes the
  // depth frame to depth/ when it was kept and a writer is set.
  // Sets v.frame_file, v.normals, v.depth_file, v.merged and, when merged, v.new_surface (the view's points
  // farther than the settings' stop_radius_m from the model before it); returns the wall time
  // this took, s.
  double accumulate(const RegisteredCloud& r, ViewRecord& v);

  // Meshes the accepted frames (core/surface/scan_mesh.hpp: mesh.ply and mesh.obj in
  // the folder) and sets scan.json's "mesh" (written with the next write); when meshing fails,
  // "mesh" is {"error": why} and the scan stands. Returns the "mesh" object.
  nlohmann::json add_mesh(const SurfaceSettings& settings);

  // Appends a view to "views" and writes scan.json with state "running".
  void add_view(const ViewRecord& v, int views_done, double elapsed_s);
  void set_stop(const ScanStop& stop);
  void set_planning_stopped(const PlanRecord& p);  // the plan that ended the scan
  // A replay (`pbnbv replay`) of the scan recorded in `recorded` (its scan.json), `views` views.
  void set_replay_of(const std::string& recorded, int views);
  // Writes scan.json with the status `state` ("running", "done", "stopped", "failed").
  void write(const std::string& state, const std::string& message, int views_done, double elapsed_s);

  std::size_t num_points() const { return accumulated_.size(); }
  // Request ids used so far end below this (written in scan.json's status, so that a resumed
  // coordinator never reuses one a service still has an answer for).
  void set_next_request_id(int64_t id) { next_request_id_ = id; }
  // Answers that carried an outstanding request's id but were refused (a field out of range for
  // what was asked): scan.json's status "answers_refused".
  void set_answers_refused(int n) { answers_refused_ = n; }
  // Continues the record in its folder: scan.json as written so far and the merged cloud (a
  // resumed scan). Throws naming the file when scan.json is missing or not a scan of `scan_id`.
  void continue_from_folder(const std::string& scan_id);
  const nlohmann::json& report() const { return report_; }
  std::filesystem::path scan_json_path() const { return out_ / "scan.json"; }

 private:
  std::filesystem::path out_;
  int views_planned_;
  double voxel_m_;
  double stop_radius_m_;
  nlohmann::json report_;
  PointCloud accumulated_;
  std::vector<Eigen::Vector3f> accumulated_normals_;  // one per accumulated point (zero: none)
  std::vector<Pose> merged_poses_;                    // the merged views' camera poses, in order
  std::deque<DepthFrame> depth_frames_;
  DepthImageWriter depth_writer_;
  int64_t next_request_id_ = 1;
  int answers_refused_ = 0;
};

}  // namespace pbnbv
