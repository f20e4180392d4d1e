#include "core/view/scene.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_file.hpp"
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

Eigen::AlignedBox3d bbox_from(const nlohmann::json& map, const std::string& what) {
  if (!map.is_object() || !map.contains("bbox_min_m") || !map.contains("bbox_max_m")) {
    throw std::runtime_error(what + " has no map.bbox_min_m / bbox_max_m");
  }
  return Eigen::AlignedBox3d(vec3_from_json(map["bbox_min_m"], what + " map.bbox_min_m"),
                             vec3_from_json(map["bbox_max_m"], what + " map.bbox_max_m"));
}

Ellipsoid ellipsoid_from(const nlohmann::json& e, const std::string& what) {
  Ellipsoid out;
  out.cls = e.at("class").get<std::string>() == "frontier" ? EllipsoidClass::kFrontier : EllipsoidClass::kOccupied;
  out.centre = vec3_from_json(e.at("centre_m"), what + " centre_m");
  out.semi_axes = vec3_from_json(e.at("semi_axes_m"), what + " semi_axes_m");
  const nlohmann::json& q = e.at("quat_wxyz");
  out.axes = Eigen::Quaterniond(q.at(0).get<double>(), q.at(1).get<double>(), q.at(2).get<double>(), q.at(3).get<double>())
                 .normalized()
                 .toRotationMatrix();
  out.num_points = e.value("voxels", 0);
  return out;
}

// The camera pose of a view taken: the registered one when the view was merged, else the one
// the capture used.
Pose view_pose(const nlohmann::json& v, const std::string& what) {
  const nlohmann::json& reg = v.value("registration", nlohmann::json::object());
  if (reg.is_object() && reg.contains("registered_object_T_camera") && reg.value("accepted", false)) {
    return pose_from_json(reg["registered_object_T_camera"], what + " registration.registered_object_T_camera");
  }
  return pose_from_json(v.at("capture").at("camera_object_T_camera"), what + " capture.camera_object_T_camera");
}

}  // namespace

std::vector<Scene> load_scan_folder(const std::string& dir, double voxel_m, std::size_t max_points) {
  const fs::path root(dir);
  if (!fs::is_directory(root)) throw std::runtime_error("scan folder " + dir + " does not exist");
  const fs::path scan_path = root / "scan.json";
  if (!fs::exists(scan_path)) throw std::runtime_error("scan folder " + dir + " has no scan.json (not a scan folder?)");
  const nlohmann::json scan = read_scan_json(scan_path);
  const nlohmann::json views = scan.value("views", nlohmann::json::array());
  const nlohmann::json settings = scan.value("settings", nlohmann::json::object());
  std::vector<double> coverage;
  if (fs::exists(root / "coverage.json")) {
    coverage = read_json((root / "coverage.json").string()).value("coverage_by_view", std::vector<double>{});
  }
  try {
    CameraIntrinsics camera;
    const nlohmann::json& c = settings.at("camera");
    camera.width = c.at("width").get<int>();
    camera.height = c.at("height").get<int>();
    camera.fx = c.at("fx").get<double>();
    camera.fy = c.at("fy").get<double>();
    camera.cx = c.at("cx").get<double>();
    camera.cy = c.at("cy").get<double>();
    const nlohmann::json& planning = settings.at("planning");
    const std::string status = scan.value("status", nlohmann::json::object()).value("state", std::string("?")) + ": " +
                               scan.value("status", nlohmann::json::object()).value("message", std::string());

    std::vector<Scene> scenes;
    PointCloud merged;  // the merged frames so far, voxel-downsampled as it grows
    std::size_t total = 0;
    std::vector<Pose> taken;
    for (std::size_t i = 0; i < views.size(); ++i) {
      const std::string what = dir + "/scan.json views[" + std::to_string(i) + "]";
      const nlohmann::json& v = views[i];
      if (!v.contains("capture")) continue;  // planned, never captured
      taken.push_back(view_pose(v, what));
      const std::string frame = view_frame_file(v, scan_path);  // its own name, or none
      if (v.value("merged", false) && !frame.empty() && fs::exists(root / frame)) {
        const PointCloud f = read_ply((root / frame).string());
        total += f.size();
        merged.insert(merged.end(), f.begin(), f.end());
        merged = voxel_downsample(merged, voxel_m);
      }
      Scene s;
      s.scan_id = settings.value("scan_id", std::string());
      s.view = static_cast<int>(taken.size());
      s.status = "view " + std::to_string(s.view) + " of " + std::to_string(views.size()) + " (" + status + ")";
      if (i < coverage.size()) s.coverage = coverage[i];
      s.cloud_points_total = total;
      if (!merged.empty()) s.cloud = decimate_cloud(merged, voxel_m, max_points);
      if (v.contains("map")) s.resolution_m = v["map"].value("resolution_m", 0.0);
      s.views_taken = taken;
      // The plan made after this view: the next view's.
      if (i + 1 < views.size() && views[i + 1].contains("plan") && views[i + 1]["plan"].contains("ellipsoids")) {
        const nlohmann::json& plan = views[i + 1]["plan"];
        const std::string pw = dir + "/scan.json views[" + std::to_string(i + 1) + "].plan";
        std::vector<Ellipsoid> ell;
        const nlohmann::json& list = plan["ellipsoids"].at("list");
        for (std::size_t k = 0; k < list.size(); ++k) ell.push_back(ellipsoid_from(list[k], pw + " ellipsoids[" + std::to_string(k) + "]"));
        for (const Ellipsoid& e : ell) s.ellipsoids.push_back(ellipsoid_mesh(e));
        const int map_view = plan.value("map_of_view", static_cast<int>(i));
        if (map_view < 0 || static_cast<std::size_t>(map_view) >= views.size()) throw std::runtime_error(pw + " map_of_view out of range");
        const Eigen::AlignedBox3d box = bbox_from(views[map_view].value("map", nlohmann::json()), what);
        CandidateSpec spec;
        spec.num_views = planning.at("candidates").get<int>();
        spec.num_parallels = planning.at("parallels").get<int>();
        spec.area = parse_name<CandidateArea>(planning.at("area").get<std::string>());
        // R = d_c + half the diagonal of B (candidate_sphere): d_c from the recorded R.
        spec.working_distance_m = plan.at("sphere").at("radius_m").get<double>() - 0.5 * box.diagonal().norm();
        s.candidates = score_candidates(ell, box, spec, camera);
        s.plan_candidates = plan.at("candidates").at("generated").get<int>();
        s.chosen = pose_from_json(plan.at("object_T_camera"), pw + " object_T_camera");
        s.chosen_quality = plan.value("view_quality_px", 0.0);
        s.chosen_ranking = plan.value("ranking", std::string("f_px"));  // folders before the field: F
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
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("scan folder " + dir + ": scan.json is malformed: " + e.what());
  }
}

}  // namespace pbnbv
