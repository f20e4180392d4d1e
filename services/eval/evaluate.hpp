#pragma once
// What a finished twin scan achieved, measured against the ground truth the twin rendered
// (object.stl in the output folder, the normalised mesh): coverage after every view, as the
// paper measures it, the planner time per iteration, and the surface metrics of the final cloud
// (and of mesh.ply when the folder has one: accuracy, completeness, F-score;
// core/metrics/surface_metrics.hpp). Reads only the output folder.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/geometry/point_cloud.hpp"
#include "core/metrics/surface_metrics.hpp"
#include "core/scan/scan_record.hpp"
#include "eval/coverage.hpp"

namespace pbnbv::eval {

// The registration's estimate of the camera mount (hand_eye.json) against the twin's true mount
// (twin_rig.json): both as errors from the rig file's flange_T_camera.
struct HandEyeCheck {
  int views = 0;
  double estimate_mm = 0, estimate_deg = 0;  // the estimated error's size
  double true_mm = 0, true_deg = 0;          // the twin's
  double error_mm = 0, error_deg = 0;        // estimate against truth
  double sigma_mm = 0, sigma_deg = 0;        // what the estimate says of itself
};

struct ScanEvaluation {
  std::vector<double> coverage_by_view;  // percent after views 1..n (a view that added nothing
                                         // to the model repeats the previous figure)
  std::vector<double> observable_by_view;  // the same over the observable samples (when a mask
                                           // is given; empty otherwise)
  std::vector<double> planner_ms;        // per planning iteration: map update + ellipsoid fit +
                                         // view selection (views 2..n; empty for a ring scan)
  std::vector<double> planner_critical_ms;  // the same iterations as the scan waited for them
                                            // (core/scan planner_critical_ms; those recorded)
  std::vector<int> points_by_view;       // points in the model after each view
  std::vector<double> new_surface_by_view;  // what each view added, % of the model before it
  std::vector<ViewGain> view_gains;         // the same with each view's rig time (the seconds rule)
                                            // (the stop rule's figure; NaN: not merged or not recorded)
  // Rig time (core/scan/rig_time.hpp) from the start to the end of each view of coverage_by_view
  // (the sum of every recorded view's rig time up to it, views that captured nothing included),
  // s; NaN from a view whose rig time is not known in full; empty when the record has none
  // (written before rig time was recorded).
  std::vector<double> rig_time_s_by_view;
  RigTimeSum rig_time;                   // scan.json's rig_time_s: the views' sums
  std::string state;                     // scan.json status.state
  std::string stop_reason;               // why the scan stopped
  int views_done = 0;
  // After the last view, against object.stl: the cloud (cloud.ply, else the merged frames) and,
  // when the folder has mesh.ply, the mesh. None when there was no point to evaluate.
  std::optional<SurfaceMetrics> cloud_metrics, mesh_metrics;
  std::string mesh_error;  // why mesh.ply could not be evaluated (unreadable, no faces); the rest stands
  std::optional<HandEyeCheck> hand_eye;  // a twin scan whose registration estimated the mount
};

// Evaluates the scan in `out` (scan.json, frames/, object.stl, cloud.ply, mesh.ply when
// present). `observable` (optional): one flag per coverage sample
// (CoverageEvaluator(object.stl, params).samples()), 1 = some reachable candidate view can see
// it. Throws std::runtime_error naming the file that is missing or malformed,
// std::invalid_argument when the mask's size is not the number of samples.
ScanEvaluation evaluate_scan(const std::filesystem::path& out, const CoverageParams& params = {},
                             const std::vector<uint8_t>* observable = nullptr, const MetricParams& metrics = {});
// evaluate_scan without the surface metrics (cloud_metrics and mesh_metrics stay empty; every
// other figure is the same), for a caller that reads only the coverage: the metrics' distance
// queries against the true mesh are most of an evaluation's time.
ScanEvaluation evaluate_coverage(const std::filesystem::path& out, const CoverageParams& params = {},
                                 const std::vector<uint8_t>* observable = nullptr);

nlohmann::json to_json(const ScanEvaluation& e, const CoverageParams& params);

// The surface metrics as coverage.json, summary.json and `pbnbv evaluate --json` write them
// (distances in mm, fractions in [0, 1]).
nlohmann::json to_json(const SurfaceMetrics& m);
nlohmann::json to_json(const MetricParams& p);

// A model file for `pbnbv evaluate`: a cloud (.pcd, or .ply without faces) or a triangle mesh
// (.ply with faces, .obj, .stl, .off); exactly one of the two is set.
struct ModelFile {
  std::optional<PointCloud> cloud;
  std::optional<TriangleMesh> mesh;
};
// Throws std::runtime_error naming the file and what is wrong: missing, an extension it does not
// read, unreadable, a cloud with no points, a mesh with no faces (load_mesh's errors).
ModelFile load_model(const std::filesystem::path& path);

}  // namespace pbnbv::eval
