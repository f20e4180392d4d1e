#include "eval/evaluate.hpp"
#include "core/base/version.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <fstream>
#include <stdexcept>

#include "core/geometry/point_cloud.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/file_checks.hpp"
#include "core/io/pcd_file.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "core/scan/scan_record.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/scan/stop_rule.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {

namespace {

json stats_mm(const DistanceStats& s) {
  return {{"count", s.count},         {"mean_mm", s.mean_m * 1e3}, {"median_mm", s.median_m * 1e3},
          {"rmse_mm", s.rmse_m * 1e3}, {"p95_mm", s.p95_m * 1e3},  {"max_mm", s.max_m * 1e3}};
}

// evaluate_scan, and evaluate_coverage when `metrics` is null.
// hand_eye.json against twin_rig.json, when the folder has both.
std::optional<HandEyeCheck> check_hand_eye(const fs::path& out) {
  if (!fs::exists(out / "hand_eye.json") || !fs::exists(out / "twin_rig.json")) return std::nullopt;
  const std::string estimate_file = (out / "hand_eye.json").string(), truth_file = (out / "twin_rig.json").string();
  const json h = read_json(estimate_file), t = read_json(truth_file);
  const Pose estimate = pose_from_json(h.at("error"), estimate_file + " error");
  const Pose truth = pose_from_json(t.at("model_flange_T_camera"), truth_file).inverse() *
                     pose_from_json(t.at("flange_T_camera"), truth_file);
  const auto deg = [](const Pose& p) { return Eigen::AngleAxisd(p.linear()).angle() * 180.0 / 3.14159265358979323846; };
  HandEyeCheck c;
  c.views = h.at("views").get<int>();
  c.estimate_mm = estimate.translation().norm() * 1e3;
  c.estimate_deg = deg(estimate);
  c.true_mm = truth.translation().norm() * 1e3;
  c.true_deg = deg(truth);
  c.error_mm = (estimate.translation() - truth.translation()).norm() * 1e3;
  c.error_deg = deg(truth.inverse() * estimate);
  c.sigma_mm = h.at("sigma_mm").get<double>();
  c.sigma_deg = h.at("sigma_deg").get<double>();
  return c;
}

ScanEvaluation evaluate(const fs::path& out, const CoverageParams& params, const std::vector<uint8_t>* observable,
                        const MetricParams* metrics) {
  const RecordedScan scan = read_scan_record(out);  // every field checked, frame files the views' own
  const fs::path mesh_path = out / "object.stl";
  if (!fs::exists(mesh_path)) throw std::runtime_error(mesh_path.string() + " is missing: not a twin scan's output folder");
  const TriangleMesh truth = load_mesh(mesh_path.string());
  CoverageEvaluator coverage(truth, params);
  PointCloud merged;  // the model's points when there is no cloud.ply
  if (observable && observable->size() != coverage.samples().size()) {
    throw std::invalid_argument("observable mask has " + std::to_string(observable->size()) + " flags for " +
                                std::to_string(coverage.samples().size()) + " coverage samples of " + mesh_path.string());
  }
  ScanEvaluation e;
  e.state = scan.status.state;
  e.views_done = scan.status.views_done;
  e.stop_reason = scan.stop ? scan.stop->reason : scan.status.message;
  int points = 0;
  for (const ViewRecord& v : scan.views) {
    if (v.plan) {
      e.planner_ms.push_back(planner_step_ms(*v.plan));
      if (const double c = planner_critical_ms(*v.plan); std::isfinite(c)) e.planner_critical_ms.push_back(c);
    }
    const std::string frame_file = v.registration ? v.registration->frame_file : std::string();
    if (frame_file.empty()) continue;  // the rig never captured this view
    if (v.registration->accepted) {
      const PointCloud frame = read_ply((out / frame_file).string());
      coverage.add_cloud(frame);
      points += static_cast<int>(frame.size());
      merged.insert(merged.end(), frame.begin(), frame.end());
    }
    e.coverage_by_view.push_back(coverage.coverage_percent());
    if (observable) e.observable_by_view.push_back(coverage.coverage_percent(*observable));
    e.points_by_view.push_back(points);
  }
  e.view_gains = view_gains(scan.views);
  e.new_surface_by_view = new_percents(e.view_gains);
  e.rig_time = sum_rig_time(scan.views);
  e.rig_time_s_by_view = rig_time_at_frames(scan.views);  // in step with coverage_by_view
  e.hand_eye = check_hand_eye(out);
  if (!metrics) return e;
  const PointCloud cloud = fs::exists(out / "cloud.ply") ? read_ply((out / "cloud.ply").string()) : merged;
  const bool has_mesh = fs::exists(out / "mesh.ply");
  if (!cloud.empty() || has_mesh) {
    const ReferenceSurface reference(truth, *metrics);
    if (!cloud.empty()) e.cloud_metrics = reference.compare_cloud(cloud);
    if (has_mesh) {
      try {
        e.mesh_metrics = reference.compare_mesh(load_mesh((out / "mesh.ply").string()));
      } catch (const std::exception& x) {  // the mesh's failure is reported, coverage and the cloud stand
        e.mesh_error = std::string(x.what()).find("mesh.ply") == std::string::npos
                           ? (out / "mesh.ply").string() + ": " + x.what()
                           : x.what();
      }
    }
  }
  return e;
}

}  // namespace

ScanEvaluation evaluate_scan(const fs::path& out, const CoverageParams& params, const std::vector<uint8_t>* observable,
                             const MetricParams& metrics) {
  return evaluate(out, params, observable, &metrics);
}

ScanEvaluation evaluate_coverage(const fs::path& out, const CoverageParams& params, const std::vector<uint8_t>* observable) {
  return evaluate(out, params, observable, nullptr);
}

json to_json(const SurfaceMetrics& m) {
  return {{"model", m.model},
          {"threshold_mm", m.threshold_m * 1e3},
          {"accuracy", stats_mm(m.accuracy)},
          {"completeness", stats_mm(m.completeness)},
          {"precision", m.precision},
          {"recall", m.recall},
          {"f_score", m.f_score},
          {"skipped_points", m.skipped_points}};
}

json to_json(const MetricParams& p) {
  return {{"threshold_mm", p.threshold_m * 1e3}, {"samples_per_cm2", p.samples_per_cm2}, {"seed", p.seed}};
}

json to_json(const ScanEvaluation& e, const CoverageParams& params) {
  json metrics = json::object();
  if (e.cloud_metrics || e.mesh_metrics) metrics["reference"] = "object.stl";
  if (e.cloud_metrics) metrics["cloud"] = to_json(*e.cloud_metrics);
  if (e.mesh_metrics) metrics["mesh"] = to_json(*e.mesh_metrics);
  if (!e.mesh_error.empty()) metrics["mesh"] = {{"error", e.mesh_error}};
  json hand_eye = nullptr;
  if (e.hand_eye) {
    const HandEyeCheck& c = *e.hand_eye;
    hand_eye = {{"views", c.views},         {"estimate_mm", c.estimate_mm}, {"estimate_deg", c.estimate_deg},
                {"true_mm", c.true_mm},     {"true_deg", c.true_deg},       {"error_mm", c.error_mm},
                {"error_deg", c.error_deg}, {"sigma_mm", c.sigma_mm},       {"sigma_deg", c.sigma_deg}};
  }
  return {{"pbnbv_version", std::string(pbnbv_version())},
          {"coverage_by_view", e.coverage_by_view},
          {"hand_eye", hand_eye},
          {"surface_metrics", metrics},
          {"planner_ms", e.planner_ms},
          {"planner_critical_ms", e.planner_critical_ms},
          {"points_by_view", e.points_by_view},
          {"new_surface_by_view", e.new_surface_by_view},
          {"rig_time_s_by_view", e.rig_time_s_by_view},
          {"state", e.state},
          {"stop_reason", e.stop_reason},
          {"views_done", e.views_done},
          {"coverage_rule", {{"samples", params.num_samples}, {"seed", params.seed}, {"radius_m", params.radius_m},
                             {"mesh", "object.stl (normalised, as rendered by the twin)"}}}};
}

ModelFile load_model(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  const std::string p = path.string();
  ModelFile m;
  if (ext == ".pcd") {
    m.cloud = read_pcd(p);
  } else if (ext == ".ply") {
    check_input_file(p, "pbnbv evaluate");
    std::ifstream in(p, std::ios::binary);
    if (check_ply_header(in, p, "pbnbv evaluate", true).faces > 0) m.mesh = load_mesh(p);
    else m.cloud = read_ply(p);
  } else if (ext == ".obj" || ext == ".stl" || ext == ".off") {
    m.mesh = load_mesh(p);
  } else {
    throw std::runtime_error(p + ": not a cloud (.ply .pcd) or a mesh (.ply .obj .stl .off)");
  }
  if (m.cloud && m.cloud->empty()) throw std::runtime_error(p + ": the cloud has no points");
  return m;
}

}  // namespace pbnbv::eval
