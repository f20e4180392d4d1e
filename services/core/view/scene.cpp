#include "core/view/scene.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_record.hpp"
#include "core/perception/cloud_filter.hpp"
#include "core/planning/view_scoring.hpp"

namespace pbnbv {

namespace fs = std::filesystem;

PointCloud decimate_cloud(const PointCloud& cloud, double voxel_m, std::size_t max_points) {
  if (!(voxel_m > 0)) throw std::invalid_argument("decimate_cloud: the voxel edge must be > 0 m, got " + std::to_string(voxel_m));
  if (max_points < 1) throw std::invalid_argument("decimate_cloud: max_points must be at least 1");
  PointCloud out = voxel_downsample(cloud, voxel_m);
  while (out.size() > max_points) {
    voxel_m *= 1.5;
    out = voxel_downsample(cloud, voxel_m);
  }
  return out;
}

EllipsoidMesh ellipsoid_mesh(const Ellipsoid& e) {
  EllipsoidMesh m;
  m.frontier = e.cls == EllipsoidClass::kFrontier;
  m.centre = e.centre;
  m.scale = e.semi_axes;
  Eigen::Matrix3d r = e.axes;
  if (r.determinant() < 0) r.col(2) = -r.col(2);  // a reflection draws the same ellipsoid
  const Eigen::Quaterniond q(r);
  m.quat_xyzw = Eigen::Vector4d(q.x(), q.y(), q.z(), q.w());
  return m;
}

std::vector<ScoredCandidate> score_candidates(const std::vector<Ellipsoid>& ellipsoids,
                                              const Eigen::AlignedBox3d& bbox, const CandidateSpec& spec,
                                              const CameraIntrinsics& camera) {
  const std::vector<Pose> views = candidate_views(bbox, spec);
  std::vector<ScoredCandidate> out(views.size());
  double lo = 0, hi = 0;
  for (std::size_t i = 0; i < views.size(); ++i) {
    out[i].object_T_camera = views[i];
    out[i].quality = score_view(ellipsoids, camera, views[i]).quality;
    lo = i == 0 ? out[i].quality : std::min(lo, out[i].quality);
    hi = i == 0 ? out[i].quality : std::max(hi, out[i].quality);
  }
  for (ScoredCandidate& c : out) c.shade = hi > lo ? (c.quality - lo) / (hi - lo) : 0.5;
  return out;
}

namespace {

nlohmann::json flat(const std::vector<Eigen::Vector3f>& points) {
  std::vector<float> v;
  v.reserve(points.size() * 3);
  for (const Eigen::Vector3f& p : points) v.insert(v.end(), {p.x(), p.y(), p.z()});
  return v;
}

}  // namespace

nlohmann::json scene_json(const Scene& s) {
  nlohmann::json j;
  j["scan_id"] = s.scan_id;
  j["view"] = s.view;
  j["status"] = s.status;
  j["coverage_percent"] = s.coverage >= 0 ? nlohmann::json(s.coverage) : nlohmann::json(nullptr);
  j["cloud_points"] = s.cloud.size();
  j["cloud_points_total"] = s.cloud_points_total;
  j["cloud"] = flat(s.cloud);
  j["frontier_voxels"] = s.frontier.size();
  j["frontier"] = flat(s.frontier);
  j["resolution_m"] = s.resolution_m;
  j["ellipsoids"] = nlohmann::json::array();
  for (const EllipsoidMesh& e : s.ellipsoids) {
    j["ellipsoids"].push_back({{"frontier", e.frontier},
                               {"centre_m", to_json(e.centre)},
                               {"scale_m", to_json(e.scale)},
                               {"quat_xyzw", {e.quat_xyzw[0], e.quat_xyzw[1], e.quat_xyzw[2], e.quat_xyzw[3]}}});
  }
  j["plan_candidates"] = s.plan_candidates;
  j["candidates"] = nlohmann::json::array();
  for (const ScoredCandidate& c : s.candidates) {
    j["candidates"].push_back({{"pose", to_json(c.object_T_camera)}, {"quality_px", c.quality}, {"shade", c.shade}});
  }
  j["views_taken"] = nlohmann::json::array();
  for (const Pose& p : s.views_taken) j["views_taken"].push_back(to_json(p));
  j["chosen"] = s.chosen ? to_json(*s.chosen) : nlohmann::json(nullptr);
  j["chosen_quality_px"] = s.chosen_quality;
  j["chosen_ranking"] = s.chosen_ranking;
  return j;
}

namespace {

// A recorded ellipsoid as the planner's type.
Ellipsoid ellipsoid_of(const EllipsoidSummary& e) {
  Ellipsoid out;
  out.cls = e.frontier ? EllipsoidClass::kFrontier : EllipsoidClass::kOccupied;
  out.centre = e.centre_m;
  out.semi_axes = e.semi_axes_m;
  out.axes = Eigen::Quaterniond(e.quat_wxyz[0], e.quat_wxyz[1], e.quat_wxyz[2], e.quat_wxyz[3]).normalized().toRotationMatrix();
  out.num_points = e.num_voxels;
  return out;
}

// The camera pose of a view taken: the registered one when the view was merged, else the one
// the capture used.
Pose view_pose(const ViewRecord& v) {
  if (v.registration && v.registration->accepted) return v.registration->cloud.object_T_camera;
  return v.capture->object_T_camera;
}

}  // namespace

std::vector<Scene> load_scan_folder(const std::string& dir, double voxel_m, std::size_t max_points) {
  const fs::path root(dir);
  if (!fs::is_directory(root)) throw std::runtime_error("scan folder " + dir + " does not exist");
  const fs::path scan_path = root / "scan.json";
  if (!fs::exists(scan_path)) throw std::runtime_error("scan folder " + dir + " has no scan.json (not a scan folder?)");
  const RecordedScan scan = read_scan_record(scan_path);  // every field checked, frame files the views' own
  const std::vector<ViewRecord>& views = scan.views;
  std::vector<double> coverage;
  if (fs::exists(root / "coverage.json")) {
    coverage = read_json((root / "coverage.json").string()).value("coverage_by_view", std::vector<double>{});
  }
  const CameraIntrinsics& camera = scan.settings.camera;
  const std::string status = scan.status.state + ": " + scan.status.message;
  std::vector<Scene> scenes;
  PointCloud merged;  // the merged frames so far, voxel-downsampled as it grows
  std::size_t total = 0;
  std::vector<Pose> taken;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const ViewRecord& v = views[i];
    if (!v.capture) continue;  // planned, never captured
    taken.push_back(view_pose(v));
    const std::string frame = v.registration ? v.registration->frame_file : std::string();
    if (v.registration && v.registration->accepted && !frame.empty() && fs::exists(root / frame)) {
      const PointCloud f = read_ply((root / frame).string());
      total += f.size();
      merged.insert(merged.end(), f.begin(), f.end());
      merged = voxel_downsample(merged, voxel_m);
    }
    Scene s;
    s.scan_id = scan.settings.scan_id;
    s.view = static_cast<int>(taken.size());
    s.status = "view " + std::to_string(s.view) + " of " + std::to_string(views.size()) + " (" + status + ")";
    if (i < coverage.size()) s.coverage = coverage[i];
    s.cloud_points_total = total;
    if (!merged.empty()) s.cloud = decimate_cloud(merged, voxel_m, max_points);
    if (v.map) s.resolution_m = v.map->resolution_m;
    s.views_taken = taken;
    // The plan made after this view: the next view's.
    if (i + 1 < views.size() && views[i + 1].plan && views[i + 1].plan->ellipsoids) {
      const PlanRecord& plan = *views[i + 1].plan;
      const std::string pw = dir + "/scan.json views[" + std::to_string(i + 1) + "].plan";
      std::vector<Ellipsoid> ell;
      for (const EllipsoidSummary& e : plan.ellipsoids->ellipsoids) ell.push_back(ellipsoid_of(e));
      for (const Ellipsoid& e : ell) s.ellipsoids.push_back(ellipsoid_mesh(e));
      const int map_view = plan.map_of_view < 0 ? static_cast<int>(i) : plan.map_of_view;
      if (static_cast<std::size_t>(map_view) >= views.size() || !views[static_cast<std::size_t>(map_view)].map) {
        throw std::runtime_error(pw + " map_of_view " + std::to_string(map_view + 1) + " names no view with a map");
      }
      const VoxelMapSummary& m = *views[static_cast<std::size_t>(map_view)].map;
      const Eigen::AlignedBox3d box(m.bbox_min_m, m.bbox_max_m);
      CandidateSpec spec;
      spec.num_views = scan.settings.candidates;
      spec.num_parallels = scan.settings.parallels;
      spec.area = scan.settings.area;
      // R = d_c + half the diagonal of B (candidate_sphere): d_c from the recorded R.
      spec.working_distance_m = plan.plan.sphere_radius_m - 0.5 * box.diagonal().norm();
      s.candidates = score_candidates(ell, box, spec, camera);
      s.plan_candidates = plan.plan.num_candidates;
      if (plan.plan.outcome == PlanOutcome::kView) s.chosen = plan.plan.object_T_camera;
      s.chosen_quality = plan.plan.view_quality;
      s.chosen_ranking = std::string(name_of(plan.plan.ranking));
    }
    scenes.push_back(std::move(s));
  }
  if (scenes.empty()) throw std::runtime_error("scan folder " + dir + ": scan.json lists no view taken");
  if (scenes.back().cloud.empty() && fs::exists(root / "cloud.ply")) {
    const PointCloud all = read_ply((root / "cloud.ply").string());
    scenes.back().cloud_points_total = all.size();
    scenes.back().cloud = decimate_cloud(all, voxel_m, max_points);
  }
  return scenes;
}

}  // namespace pbnbv
