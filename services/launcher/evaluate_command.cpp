// `pbnbv evaluate`: a scan folder, a cloud or a mesh against a reference mesh.
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "core/base/format.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "eval/evaluate.hpp"
#include "launcher/commands.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::launcher {

namespace {

std::string column(double mm) {
  std::ostringstream s;
  s << std::setw(9) << fixed(mm * 1e3, 3);
  return s.str();
}

// One model's figures, as a few lines of a table.
void print_metrics(std::ostream& out, const std::string& file, const SurfaceMetrics& m) {
  out << file << ": " << m.model << ", " << m.accuracy.count << (m.model == "cloud" ? " points" : " samples")
      << (m.skipped_points ? " (" + std::to_string(m.skipped_points) + " non-finite points left out)" : "") << "\n"
      << "                     mean   median     RMSE      p95      max  (mm)\n";
  for (const auto& [name, s] : {std::pair{"accuracy    ", &m.accuracy}, std::pair{"completeness", &m.completeness}}) {
    out << "  " << name << " " << column(s->mean_m) << column(s->median_m) << column(s->rmse_m) << column(s->p95_m)
        << column(s->max_m) << "\n";
  }
  out << "  precision " << fixed(m.precision, 4) << "   recall " << fixed(m.recall, 4) << "   F-score "
      << fixed(m.f_score, 4) << "   (within " << fixed(m.threshold_m * 1e3, 2) << " mm)\n";
}

}  // namespace

int run_evaluate(const EvaluateOptions& o, std::ostream& out) {
  const fs::path target = o.target;
  if (!fs::exists(target)) throw std::runtime_error(o.target + ": no such file or folder");
  json result = {{"settings", eval::to_json(o.metrics)}, {"models", json::array()}};
  int code = 0;  // 1: a scan folder's mesh.ply could not be evaluated

  // A twin scan's folder without --reference: what `pbnbv scan` evaluates (coverage as well).
  if (fs::is_directory(target) && o.reference.empty()) {
    if (!fs::exists(target / "object.stl")) {
      throw std::runtime_error(o.target + " has no object.stl (the true mesh of a twin scan): give --reference MESH");
    }
    const CoverageParams cp;
    const eval::ScanEvaluation e = eval::evaluate_scan(target, cp, nullptr, o.metrics);
    if (!e.cloud_metrics && !e.mesh_metrics) throw std::runtime_error(o.target + ": the scan has no point to evaluate");
    out << "pbnbv evaluate: " << o.target << " against its object.stl (the mesh the twin rendered), "
        << fixed(o.metrics.samples_per_cm2, 0) << " samples per cm^2\n";
    if (!e.coverage_by_view.empty()) out << "coverage after the last view: " << fixed(e.coverage_by_view.back(), 2) << " %\n";
    result["reference"] = (target / "object.stl").string();
    result["scan"] = eval::to_json(e, cp);
    if (e.cloud_metrics) {
      print_metrics(out, "cloud.ply", *e.cloud_metrics);
      result["models"].push_back(eval::to_json(*e.cloud_metrics));
      result["models"].back()["file"] = (target / "cloud.ply").string();
    }
    if (e.mesh_metrics) {
      print_metrics(out, "mesh.ply", *e.mesh_metrics);
      result["models"].push_back(eval::to_json(*e.mesh_metrics));
      result["models"].back()["file"] = (target / "mesh.ply").string();
    }
    if (!e.mesh_error.empty()) {
      out << "mesh.ply: not evaluated: " << e.mesh_error << "\n";
      result["models"].push_back({{"file", (target / "mesh.ply").string()}, {"error", e.mesh_error}});
      code = 1;
    }
  } else {
    if (o.reference.empty()) throw std::runtime_error("--reference MESH is required to evaluate a file: " + o.target);
    std::vector<fs::path> models;
    if (fs::is_directory(target)) {
      for (const char* name : {"cloud.ply", "mesh.ply"}) {
        if (fs::exists(target / name)) models.push_back(target / name);
      }
      if (models.empty()) throw std::runtime_error(o.target + " has neither cloud.ply nor mesh.ply: not a scan folder");
    } else {
      models.push_back(target);
    }
    TriangleMesh reference = load_mesh(o.reference);
    for (auto& v : reference.vertices) v *= o.reference_scale;
    const ReferenceSurface surface(reference, o.metrics);
    out << "pbnbv evaluate: against " << o.reference << " (" << reference.triangles.size() << " triangles, "
        << fixed(surface.area_m2() * 1e4, 1) << " cm^2"
        << (o.reference_scale != 1.0 ? ", coordinates times " + std::to_string(o.reference_scale) : std::string())
        << "), " << surface.samples().size() << " samples on it\n";
    result["reference"] = o.reference;
    result["reference_scale"] = o.reference_scale;
    for (const fs::path& file : models) {
      const eval::ModelFile model = eval::load_model(file);
      SurfaceMetrics m;
      try {
        m = model.cloud ? surface.compare_cloud(*model.cloud) : surface.compare_mesh(*model.mesh);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(file.string() + ": " + e.what());
      }
      print_metrics(out, file.string(), m);
      result["models"].push_back(eval::to_json(m));
      result["models"].back()["file"] = file.string();
    }
  }
  if (!o.json.empty()) {
    write_json_atomic(result, o.json);
    out << "figures: " << o.json << "\n";
  }
  out << std::flush;
  return code;
}

}  // namespace pbnbv::launcher
