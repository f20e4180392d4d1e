#pragma once
// Everything that defines a scan, decided once by the launcher (from the command line and the
// object) and read by the coordinator. Written into scan.json as "settings", so a scan's
// output folder says exactly how it was made and can be resumed or repeated from it.
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "core/geometry/camera_model.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/json.hpp"
#include "core/rig/rig.hpp"

namespace pbnbv {

struct ScanSettings {
  std::string scan_id;
  RigKind rig = RigKind::kArm;
  std::string rig_model_path;
  std::string planner = "pbnbv";  // "pbnbv" (next best view), "ring" (fixed views), or a
                                  // benchmark baseline: "raycast", "random"
  int views = 10;                  // at most this many views

  // Object (twin runs): how the mesh was normalised and where its frame sits.
  std::string object_name;
  MeshNormalisation normalisation;
  double object_z_m = 0;  // object frame origin above the turntable top (arm rig)

  // View geometry.
  double working_distance_m = 0.6;   // d_c: camera to the object's bounding sphere
  double ring_elevation_deg = 30.0;  // ring planner: elevation above the object centre
  double ring_start_azimuth_deg = 0.0;
  // The first view of a next-best-view scan: camera position in the object frame, looking at
  // the origin; unset (NaN): the ring's first view (azimuth ring_start_azimuth_deg, elevation
  // ring_elevation_deg on the arm rig, 0 on the free rig).
  Eigen::Vector3d initial_view_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());

  // PB-NBV planning (docs/method.md: "Candidate views", "Global partitioning", "Termination").
  int candidates = 800;          // N
  int parallels = 24;            // alpha
  int sectors = 4;               // beta
  bool full_sphere = false;      // candidate area: full sphere, else hemisphere
  int t_max = 10;                // ellipsoid fitter's T_max
  double map_resolution_m = 0.03;
  double stop_fraction = 0.0;    // stop when best F < this * F of the first planned view (0: off)
  std::string when_done = "stop";  // nothing left to aim at: "stop", or "spread" (use the budget)
  int alternatives = 5;          // next-best views tried when the rig cannot reach the best
  int64_t seed = 1;              // the random planner's seed (view i uses seed + i)

  // Keep-out box for the arm (object frame) and the working volume for clouds.
  Eigen::Vector3d keepout_min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d keepout_max_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d crop_min_m = Eigen::Vector3d::Constant(-0.5);
  Eigen::Vector3d crop_max_m = Eigen::Vector3d::Constant(0.5);
  double ground_clearance_m = 0.004;
  double voxel_m = 0.002;  // per-frame and accumulated cloud downsampling

  CameraIntrinsics camera;
  DepthRange depth_range;

  double speed_scale = 1.0;
  double move_timeout_s = 60.0;
  double capture_timeout_s = 10.0;
  double sim_speed = 4.0;
  double startup_timeout_s = 90.0;
};

nlohmann::json to_json(const ScanSettings& s);
ScanSettings scan_settings_from_json(const nlohmann::json& j);  // throws naming the field

nlohmann::json to_json(const MeshNormalisation& n);

// Where the normalised object sits and what the rig must keep clear of (s.normalisation and
// s.rig set): on the arm rig it rests on the turntable, on the free rig it floats at the origin.
// Fills object_z_m, the keep-out box and the cloud's crop box.
void place_object(ScanSettings& s);

}  // namespace pbnbv
