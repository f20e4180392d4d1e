#include "core/io/json.hpp"
#include "core/scan/scan_settings.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <cctype>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>

namespace pbnbv {

nlohmann::json to_json(const MeshNormalisation& n) {
  nlohmann::json rot = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rot.push_back({n.up_rotation(r, 0), n.up_rotation(r, 1), n.up_rotation(r, 2)});
  return {{"source_path", n.source_path},
          {"up", std::string(name_of(n.up))},
          {"up_rotation", rot},
          {"scale", n.scale},
          {"centre_removed_m", to_json(n.centre_m)},
          {"extent_m", to_json(n.extent_m)},
          {"num_vertices", n.num_vertices},
          {"num_triangles", n.num_triangles},
          {"rule", "p_object = scale * (up_rotation * p_file) - centre_removed_m"}};
}

nlohmann::json to_json(const ScanSettings& s) {
  return {
      {"scan_id", s.scan_id},
      {"rig", to_string(s.rig)},
      {"rig_model_path", s.rig_model_path},
      {"planner", std::string(name_of(s.planner))},
      {"views", s.views},
      {"stop_rule", {{"rule", std::string(name_of(s.stop_rule))}, {"window", s.surface_rule.window},
                     {"max_new_percent", s.surface_rule.max_new_percent}, {"min_views", s.surface_rule.min_views},
                     {"radius_m", s.stop_radius_m},
                     {"seconds", to_json(s.seconds_rule)}}},
      {"registration", {{"pose_sigma_mm", s.pose_sigma_m * 1e3}, {"pose_sigma_deg", s.pose_sigma_deg},
                        {"icp_voxel_m", s.icp_voxel_m}}},
      {"depth_filter", s.depth_filter},
      {"external_rig", s.external_rig},
      {"object", s.working_volume ? nlohmann::json{{"name", s.object_name}, {"working_volume", s.working_volume->to_text()}}
                                  : nlohmann::json{{"name", s.object_name}, {"normalisation", to_json(s.normalisation)}}},
      {"object_z_m", s.object_z_m},
      {"working_distance_m", s.working_distance_m},
      {"ring_elevation_deg", s.ring_elevation_deg},
      {"ring_start_azimuth_deg", s.ring_start_azimuth_deg},
      {"initial_view_m", s.initial_view_m.allFinite() ? to_json(s.initial_view_m) : nlohmann::json(nullptr)},
      {"planning", {{"candidates", s.candidates}, {"parallels", s.parallels}, {"sectors", s.sectors},
                    {"area", std::string(name_of(s.area))}, {"t_max", s.t_max},
                    {"map_resolution_m", s.map_resolution_m}, {"stop_fraction", s.stop_fraction}, {"when_done", std::string(name_of(s.when_done))},
                    {"motion", std::string(name_of(s.motion))}, {"seconds_per_point", s.seconds_per_point},
                    {"map_pose", std::string(name_of(s.map_pose))},
                    {"least_turn", std::string(name_of(s.least_turn))}, {"alternatives", s.alternatives}, {"seed", s.seed}}},
      {"keepout", {{"min_m", to_json(s.keepout_min_m)}, {"max_m", to_json(s.keepout_max_m)}}},
      {"crop", {{"min_m", to_json(s.crop_min_m)}, {"max_m", to_json(s.crop_max_m)},
                {"ground_clearance_m", s.ground_clearance_m}}},
      {"voxel_m", s.voxel_m},
      {"camera", {{"model", name_of(s.camera_model)}, {"width", s.camera.width}, {"height", s.camera.height}, {"fx", s.camera.fx},
                  {"fy", s.camera.fy}, {"cx", s.camera.cx}, {"cy", s.camera.cy},
                  {"depth_min_m", s.depth_range.min_m}, {"depth_max_m", s.depth_range.max_m}}},
      {"speed_scale", s.speed_scale},
      {"move_timeout_s", s.move_timeout_s},
      {"capture_timeout_s", s.capture_timeout_s},
      {"sim_speed", s.sim_speed},
      {"startup_timeout_s", s.startup_timeout_s},
  };
}

namespace {

// A whole number of settings.json, read without a cast that a huge or fractional value would make
// undefined; the ranges are checked by validate() after.
int int_at(const nlohmann::json& o, const char* key, const std::string& what) {
  return static_cast<int>(
      integer_from_json(o.at(key), std::numeric_limits<int>::min(), std::numeric_limits<int>::max(), what));
}
std::size_t count_at(const nlohmann::json& o, const char* key, const std::string& what) {
  return static_cast<std::size_t>(integer_from_json(o.at(key), 0, int64_t{1} << 53, what));
}

}  // namespace

ScanSettings scan_settings_from_json(const nlohmann::json& j) {
  ScanSettings s;
  try {
    s.scan_id = j.at("scan_id").get<std::string>();
    s.rig = parse_rig_kind(j.at("rig").get<std::string>());
    s.rig_model_path = j.at("rig_model_path").get<std::string>();
    s.planner = parse_name<PlannerKind>(j.at("planner").get<std::string>());
    s.views = int_at(j, "views", "views");
    if (j.contains("stop_rule")) {
      const auto& r = j["stop_rule"];
      s.stop_rule = parse_name<StopRule>(r.at("rule").get<std::string>());
      s.surface_rule.window = int_at(r, "window", "stop_rule.window");
      s.surface_rule.max_new_percent = r.at("max_new_percent").get<double>();
      s.surface_rule.min_views = int_at(r, "min_views", "stop_rule.min_views");
      s.stop_radius_m = r.at("radius_m").get<double>();
      if (r.contains("seconds")) {  // since the rule in seconds (before: its defaults, unused)
        const auto& t = r["seconds"];
        s.seconds_rule.window = int_at(t, "window", "stop_rule.seconds.window");
        s.seconds_rule.min_percent_per_s = t.at("min_percent_per_s").get<double>();
        s.seconds_rule.min_views = int_at(t, "min_views", "stop_rule.seconds.min_views");
      }
    } else {
      s.stop_rule = StopRule::kOff;  // a scan recorded before the rule existed ran without it
    }
    if (j.contains("registration")) {  // written since pbnbv 0.11 (before: the defaults)
      s.pose_sigma_m = j["registration"].at("pose_sigma_mm").get<double>() * 1e-3;
      s.pose_sigma_deg = j["registration"].at("pose_sigma_deg").get<double>();
      // Written since stop 47; a scan recorded before it aligned at 2 mm and resumes so.
      s.icp_voxel_m = j["registration"].value("icp_voxel_m", 0.002);
    }
    s.external_rig = j.value("external_rig", false);
    s.depth_filter = j.value("depth_filter", false);  // a scan recorded before the filter ran without it
    s.object_name = j.at("object").at("name").get<std::string>();
    if (j.at("object").contains("working_volume")) {
      s.working_volume = parse_working_volume(j.at("object").at("working_volume").get<std::string>());
    } else {
    const auto& n = j.at("object").at("normalisation");
    s.normalisation.source_path = n.at("source_path").get<std::string>();
    s.normalisation.up = parse_name<UpAxis>(n.at("up").get<std::string>());
    s.normalisation.scale = n.at("scale").get<double>();
    s.normalisation.centre_m = vec3_from_json(n.at("centre_removed_m"), "centre_removed_m");
    s.normalisation.extent_m = vec3_from_json(n.at("extent_m"), "extent_m");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) s.normalisation.up_rotation(r, c) = n.at("up_rotation").at(r).at(c).get<double>();
    s.normalisation.num_vertices = count_at(n, "num_vertices", "object.normalisation.num_vertices");
    s.normalisation.num_triangles = count_at(n, "num_triangles", "object.normalisation.num_triangles");
    }
    s.object_z_m = j.at("object_z_m").get<double>();
    s.working_distance_m = j.at("working_distance_m").get<double>();
    s.ring_elevation_deg = j.at("ring_elevation_deg").get<double>();
    s.ring_start_azimuth_deg = j.at("ring_start_azimuth_deg").get<double>();
    if (!j.at("initial_view_m").is_null()) s.initial_view_m = vec3_from_json(j.at("initial_view_m"), "initial_view_m");
    const auto& pl = j.at("planning");
    s.candidates = int_at(pl, "candidates", "planning.candidates");
    s.parallels = int_at(pl, "parallels", "planning.parallels");
    s.sectors = int_at(pl, "sectors", "planning.sectors");
    s.area = parse_name<CandidateArea>(pl.at("area").get<std::string>());
    s.t_max = int_at(pl, "t_max", "planning.t_max");
    s.map_resolution_m = pl.at("map_resolution_m").get<double>();
    s.stop_fraction = pl.at("stop_fraction").get<double>();
    s.when_done = parse_name<WhenDone>(pl.value("when_done", std::string(name_of(kWhenDone.value))));
    // Settings written before pbnbv 0.13.0 have none: their scans turned every view to the arm.
    s.motion = parse_name<Motion>(pl.value("motion", std::string(name_of(Motion::kPlain))));
    s.seconds_per_point = pl.value("seconds_per_point", 0.0);
    // Settings written before the map took the rig's pose have none: their maps waited for the registration.
    s.map_pose = parse_name<MapPose>(pl.value("map_pose", std::string(name_of(MapPose::kRegistered))));
    // Settings written before the least turn was narrowed have none: their moves took the grid's.
    s.least_turn = parse_name<LeastTurn>(pl.value("least_turn", std::string(name_of(LeastTurn::kGrid))));
    s.alternatives = int_at(pl, "alternatives", "planning.alternatives");
    if (pl.contains("seed")) {
      s.seed = integer_from_json(pl["seed"], std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max(),
                                 "planning.seed");
    }
    s.keepout_min_m = vec3_from_json(j.at("keepout").at("min_m"), "keepout.min_m");
    s.keepout_max_m = vec3_from_json(j.at("keepout").at("max_m"), "keepout.max_m");
    s.crop_min_m = vec3_from_json(j.at("crop").at("min_m"), "crop.min_m");
    s.crop_max_m = vec3_from_json(j.at("crop").at("max_m"), "crop.max_m");
    s.ground_clearance_m = j.at("crop").at("ground_clearance_m").get<double>();
    s.voxel_m = j.at("voxel_m").get<double>();
    const auto& c = j.at("camera");
    if (c.contains("model")) s.camera_model = parse_name<CameraKind>(c.at("model").get<std::string>());  // since stop 37
    s.camera.width = int_at(c, "width", "camera.width");
    s.camera.height = int_at(c, "height", "camera.height");
    s.camera.fx = c.at("fx").get<double>();
    s.camera.fy = c.at("fy").get<double>();
    s.camera.cx = c.at("cx").get<double>();
    s.camera.cy = c.at("cy").get<double>();
    s.depth_range.min_m = c.at("depth_min_m").get<double>();
    s.depth_range.max_m = c.at("depth_max_m").get<double>();
    s.speed_scale = j.at("speed_scale").get<double>();
    s.move_timeout_s = j.at("move_timeout_s").get<double>();
    s.capture_timeout_s = j.at("capture_timeout_s").get<double>();
    s.sim_speed = j.at("sim_speed").get<double>();
    s.startup_timeout_s = j.at("startup_timeout_s").get<double>();
    s.validate();
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string("scan settings: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("scan settings: ") + e.what());
  }
  return s;
}

void ScanSettings::validate() const {
  kViews.checked(views);
  kWorkingDistance.checked(working_distance_m);
  kRingElevation.checked(ring_elevation_deg);
  kCandidates.checked(candidates);
  kParallels.checked(parallels);
  if (parallels > candidates) {
    throw std::invalid_argument(fmt::format("--{} {} must not exceed --{} {}", kParallels.name, parallels,
                                            kCandidates.name, candidates));
  }
  kSectors.checked(sectors);
  kTMax.checked(t_max);
  kMapResolution.checked(map_resolution_m);
  kStopFraction.checked(stop_fraction);
  kStopWindow.checked(surface_rule.window);
  kStopNewSurface.checked(surface_rule.max_new_percent);
  kStopMinViews.checked(surface_rule.min_views);
  kStopRateViews.checked(seconds_rule.window);
  kStopGainPerSecond.checked(seconds_rule.min_percent_per_s);
  kStopMinViews.checked(seconds_rule.min_views);
  kStopRadius.checked(stop_radius_m);
  kPoseSigmaMm.checked(pose_sigma_m * 1e3);
  kPoseSigmaDeg.checked(pose_sigma_deg);
  kIcpVoxel.checked(icp_voxel_m);
  kAlternatives.checked(alternatives);
  kPlannerSeed.checked(seed);
  kCloudVoxel.checked(voxel_m);
  kSpeedScale.checked(speed_scale);
  kSimSpeed.checked(sim_speed);
  // Not given: every coordinate NaN.
  if (!initial_view_m.array().isNaN().all()) check_initial_view(initial_view_m);
  camera.validate();
  depth_range.validate();
}

void check_initial_view(const Eigen::Vector3d& p) {
  const std::string given = fmt::format("--initial-view {},{},{}", p.x(), p.y(), p.z());
  if (!p.allFinite()) throw std::invalid_argument(given + ": every coordinate must be a finite number (m)");
  if (p.norm() < 0.05) throw std::invalid_argument(given + " must be away from the object centre (at least 0.05 m)");
  if (p.norm() > kMaxInitialViewM) {
    throw std::invalid_argument(fmt::format("{} is {:.3g} m from the object centre: at most {} m", given, p.norm(), kMaxInitialViewM));
  }
}

Eigen::Vector3d ScanSettings::expected_extent_m() const {
  return working_volume ? Eigen::Vector3d(working_volume->bounds().sizes()) : normalisation.extent_m;
}

void place_object(ScanSettings& s) {
  const Eigen::Vector3d half = s.expected_extent_m() / 2.0;
  s.object_z_m = s.rig == RigKind::kArm ? half.z() : 0.0;
  s.keepout_min_m = -half - Eigen::Vector3d::Constant(0.02);
  s.keepout_max_m = half + Eigen::Vector3d::Constant(0.02);
  if (s.rig == RigKind::kArm) s.keepout_min_m.z() = -half.z();  // down to the turntable top
  s.crop_min_m = -half - Eigen::Vector3d::Constant(0.05);
  s.crop_max_m = half + Eigen::Vector3d::Constant(0.05);
}

void check_object_limits(const TriangleMesh& mesh, const MeshNormalisation& n, const std::string& what, bool for_twin) {
  if (for_twin && n.num_triangles > kTwinMaxTriangles) {
    throw std::invalid_argument(what + " has " + std::to_string(n.num_triangles) + " triangles; the twin (MuJoCo) loads at most " +
                                std::to_string(kTwinMaxTriangles) +
                                " per mesh: simplify it first (e.g. quadric edge collapse to 100,000 faces)");
  }
  // Flatness along any direction: the spread of the vertices along their principal axes.
  if (!mesh.vertices.empty()) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& v : mesh.vertices) mean += v;
    mean /= static_cast<double>(mesh.vertices.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& v : mesh.vertices) cov += (v - mean) * (v - mean).transpose();
    const Eigen::Vector3d spread = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues().cwiseMax(0).cwiseSqrt();
    if (!(spread(0) * kMaxObjectAspect >= spread(2))) {
      throw std::invalid_argument(fmt::format(
          "{} is flat ({} vertices, {} triangles; its thinnest direction spreads {:.2g} of its widest): a sheet or a "
          "degenerate mesh has no volume to scan",
          what, mesh.vertices.size(), mesh.triangles.size(), spread(2) > 0 ? spread(0) / spread(2) : 0.0));
    }
  }
  const double shortest = n.extent_m.minCoeff(), longest = n.extent_m.maxCoeff();
  const auto m = [](double v) { return fmt::format("{:.3g} m", v); };
  if (longest > kMaxObjectAspect * shortest) {
    throw std::invalid_argument(fmt::format(
        "{} is {:.0f} times longer than it is thick (its bounding box, normalised: {} x {} x {}): a flat or "
        "degenerate mesh; a scan needs a solid object (longest / shortest edge at most {:.0f})",
        what, longest / shortest, m(n.extent_m.x()), m(n.extent_m.y()), m(n.extent_m.z()), kMaxObjectAspect));
  }
  if (longest > kMaxObjectExtentM) {
    throw std::invalid_argument(fmt::format(
        "{} would be {} long once its shortest edge is scaled to {} (bounding box {} x {} x {}); the rig scans objects "
        "up to {}: give a smaller --size",
        what, m(longest), m(shortest), m(n.extent_m.x()), m(n.extent_m.y()), m(n.extent_m.z()), m(kMaxObjectExtentM)));
  }
}

std::string new_scan_id(const std::string& name) {
  std::random_device source;  // /dev/urandom (libstdc++ on Linux)
  const uint64_t bits = (static_cast<uint64_t>(source()) << 32) ^ source();
  std::string id;
  for (char c : name) id += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' ? c : '_';
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(bits));
  return (id.empty() ? "scan" : id) + "-" + hex;
}

TurntableChoice turntable_choice(const ScanSettings& s) {
  const bool aware = s.motion == Motion::kAware || (s.motion == Motion::kAuto && s.planner != PlannerKind::kPbnbvPaper);
  if (!aware) return TurntableChoice::kPreferred;
  switch (s.least_turn) {
    case LeastTurn::kQuickest: return TurntableChoice::kQuickest;
    case LeastTurn::kNarrowed: return TurntableChoice::kLeastTurn;
    case LeastTurn::kGrid: return TurntableChoice::kLeastTurnOnGrid;
  }
  throw std::logic_error("turntable_choice: a least turn without a rule");
}

}  // namespace pbnbv
