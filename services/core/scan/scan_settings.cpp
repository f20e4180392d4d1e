#include "core/io/json.hpp"
#include "core/scan/scan_settings.hpp"

#include <cstdio>
#include <fstream>
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
      {"object", {{"name", s.object_name}, {"normalisation", to_json(s.normalisation)}}},
      {"object_z_m", s.object_z_m},
      {"working_distance_m", s.working_distance_m},
      {"ring_elevation_deg", s.ring_elevation_deg},
      {"ring_start_azimuth_deg", s.ring_start_azimuth_deg},
      {"initial_view_m", s.initial_view_m.allFinite() ? to_json(s.initial_view_m) : nlohmann::json(nullptr)},
      {"planning", {{"candidates", s.candidates}, {"parallels", s.parallels}, {"sectors", s.sectors},
                    {"area", std::string(name_of(s.area))}, {"t_max", s.t_max},
                    {"map_resolution_m", s.map_resolution_m}, {"stop_fraction", s.stop_fraction}, {"when_done", std::string(name_of(s.when_done))},
                    {"alternatives", s.alternatives}, {"seed", s.seed}}},
      {"keepout", {{"min_m", to_json(s.keepout_min_m)}, {"max_m", to_json(s.keepout_max_m)}}},
      {"crop", {{"min_m", to_json(s.crop_min_m)}, {"max_m", to_json(s.crop_max_m)},
                {"ground_clearance_m", s.ground_clearance_m}}},
      {"voxel_m", s.voxel_m},
      {"camera", {{"width", s.camera.width}, {"height", s.camera.height}, {"fx", s.camera.fx},
                  {"fy", s.camera.fy}, {"cx", s.camera.cx}, {"cy", s.camera.cy},
                  {"depth_min_m", s.depth_range.min_m}, {"depth_max_m", s.depth_range.max_m}}},
      {"speed_scale", s.speed_scale},
      {"move_timeout_s", s.move_timeout_s},
      {"capture_timeout_s", s.capture_timeout_s},
      {"sim_speed", s.sim_speed},
      {"startup_timeout_s", s.startup_timeout_s},
  };
}

ScanSettings scan_settings_from_json(const nlohmann::json& j) {
  ScanSettings s;
  try {
    s.scan_id = j.at("scan_id").get<std::string>();
    s.rig = parse_rig_kind(j.at("rig").get<std::string>());
    s.rig_model_path = j.at("rig_model_path").get<std::string>();
    s.planner = parse_name<PlannerKind>(j.at("planner").get<std::string>());
    s.views = j.at("views").get<int>();
    s.object_name = j.at("object").at("name").get<std::string>();
    const auto& n = j.at("object").at("normalisation");
    s.normalisation.source_path = n.at("source_path").get<std::string>();
    s.normalisation.up = parse_name<UpAxis>(n.at("up").get<std::string>());
    s.normalisation.scale = n.at("scale").get<double>();
    s.normalisation.centre_m = vec3_from_json(n.at("centre_removed_m"), "centre_removed_m");
    s.normalisation.extent_m = vec3_from_json(n.at("extent_m"), "extent_m");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) s.normalisation.up_rotation(r, c) = n.at("up_rotation").at(r).at(c).get<double>();
    s.normalisation.num_vertices = n.at("num_vertices").get<std::size_t>();
    s.normalisation.num_triangles = n.at("num_triangles").get<std::size_t>();
    s.object_z_m = j.at("object_z_m").get<double>();
    s.working_distance_m = j.at("working_distance_m").get<double>();
    s.ring_elevation_deg = j.at("ring_elevation_deg").get<double>();
    s.ring_start_azimuth_deg = j.at("ring_start_azimuth_deg").get<double>();
    if (!j.at("initial_view_m").is_null()) s.initial_view_m = vec3_from_json(j.at("initial_view_m"), "initial_view_m");
    const auto& pl = j.at("planning");
    s.candidates = pl.at("candidates").get<int>();
    s.parallels = pl.at("parallels").get<int>();
    s.sectors = pl.at("sectors").get<int>();
    s.area = parse_name<CandidateArea>(pl.at("area").get<std::string>());
    s.t_max = pl.at("t_max").get<int>();
    s.map_resolution_m = pl.at("map_resolution_m").get<double>();
    s.stop_fraction = pl.at("stop_fraction").get<double>();
    s.when_done = parse_name<WhenDone>(pl.value("when_done", std::string(name_of(kWhenDone.value))));
    s.alternatives = pl.at("alternatives").get<int>();
    s.seed = pl.value("seed", kPlannerSeed.value);
    s.keepout_min_m = vec3_from_json(j.at("keepout").at("min_m"), "keepout.min_m");
    s.keepout_max_m = vec3_from_json(j.at("keepout").at("max_m"), "keepout.max_m");
    s.crop_min_m = vec3_from_json(j.at("crop").at("min_m"), "crop.min_m");
    s.crop_max_m = vec3_from_json(j.at("crop").at("max_m"), "crop.max_m");
    s.ground_clearance_m = j.at("crop").at("ground_clearance_m").get<double>();
    s.voxel_m = j.at("voxel_m").get<double>();
    const auto& c = j.at("camera");
    s.camera.width = c.at("width").get<int>();
    s.camera.height = c.at("height").get<int>();
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
  kAlternatives.checked(alternatives);
  kPlannerSeed.checked(seed);
  kCloudVoxel.checked(voxel_m);
  kSpeedScale.checked(speed_scale);
  kSimSpeed.checked(sim_speed);
  if (initial_view_m.allFinite() && initial_view_m.norm() < 0.05) {
    throw std::invalid_argument("--initial-view must be away from the object centre (at least 0.05 m)");
  }
  camera.validate();
  depth_range.validate();
}

void place_object(ScanSettings& s) {
  const Eigen::Vector3d half = s.normalisation.extent_m / 2.0;
  s.object_z_m = s.rig == RigKind::kArm ? half.z() : 0.0;
  s.keepout_min_m = -half - Eigen::Vector3d::Constant(0.02);
  s.keepout_max_m = half + Eigen::Vector3d::Constant(0.02);
  if (s.rig == RigKind::kArm) s.keepout_min_m.z() = -half.z();  // down to the turntable top
  s.crop_min_m = -half - Eigen::Vector3d::Constant(0.05);
  s.crop_max_m = half + Eigen::Vector3d::Constant(0.05);
}

}  // namespace pbnbv
