#include "eval/evaluate.hpp"

#include <fstream>
#include <stdexcept>

#include "core/geometry/point_cloud.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "core/scan/scan_settings.hpp"
#include "core/scan/stop_rule.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {

ScanEvaluation evaluate_scan(const fs::path& out, const CoverageParams& params, const std::vector<uint8_t>* observable) {
  const json scan = read_json((out / "scan.json").string());
  const fs::path mesh_path = out / "object.stl";
  if (!fs::exists(mesh_path)) throw std::runtime_error(mesh_path.string() + " is missing: not a twin scan's output folder");
  CoverageEvaluator coverage(load_mesh(mesh_path.string()), params);
  if (observable && observable->size() != coverage.samples().size()) {
    throw std::invalid_argument("observable mask has " + std::to_string(observable->size()) + " flags for " +
                                std::to_string(coverage.samples().size()) + " coverage samples of " + mesh_path.string());
  }
  ScanEvaluation e;
  try {
    e.state = scan.at("status").at("state").get<std::string>();
    e.views_done = scan.at("status").at("views_done").get<int>();
    if (scan.contains("stop")) e.stop_reason = scan["stop"].at("reason").get<std::string>();
    else e.stop_reason = scan.at("status").at("message").get<std::string>();
    int points = 0;
    for (const auto& v : scan.at("views")) {
      if (v.contains("plan") && v["plan"].contains("planner_step_ms")) {
        e.planner_ms.push_back(v["plan"]["planner_step_ms"].get<double>());
      }
      if (v.value("merged", false)) {
        const PointCloud frame = read_ply((out / v.at("frame_file").get<std::string>()).string());
        coverage.add_cloud(frame);
        points += static_cast<int>(frame.size());
      }
      if (!v.contains("frame_file")) continue;  // the rig never captured this view
      e.coverage_by_view.push_back(coverage.coverage_percent());
      if (observable) e.observable_by_view.push_back(coverage.coverage_percent(*observable));
      e.points_by_view.push_back(points);
    }
    e.new_surface_by_view = new_surface_figures(scan.at("views"));
  } catch (const json::exception& x) {
    throw std::runtime_error((out / "scan.json").string() + ": " + x.what());
  }
  return e;
}

json to_json(const ScanEvaluation& e, const CoverageParams& params) {
  return {{"coverage_by_view", e.coverage_by_view},
          {"planner_ms", e.planner_ms},
          {"points_by_view", e.points_by_view},
          {"new_surface_by_view", e.new_surface_by_view},
          {"state", e.state},
          {"stop_reason", e.stop_reason},
          {"views_done", e.views_done},
          {"coverage_rule", {{"samples", params.num_samples}, {"seed", params.seed}, {"radius_m", params.radius_m},
                             {"mesh", "object.stl (normalised, as rendered by the twin)"}}}};
}

}  // namespace pbnbv::eval
