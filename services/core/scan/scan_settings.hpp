#pragma once
// Everything that defines a scan, decided once by the launcher (from the command line and the
// object) and read by the coordinator. Defaults and ranges: the table of scan options
// (core/scan/scan_options.hpp and the settings of the layers below). Written into scan.json as "settings", so a scan's
// output folder says exactly how it was made and can be resumed or repeated from it.
#include <limits>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>

#include "core/geometry/camera_model.hpp"
#include "core/geometry/depth_sensor.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/json.hpp"
#include "core/mapping/map_options.hpp"
#include "core/perception/perception_options.hpp"
#include "core/planning/kinds.hpp"
#include "core/planning/planning_options.hpp"
#include "core/geometry/rig_kind.hpp"
#include "core/geometry/working_volume.hpp"
#include "core/scan/scan_options.hpp"
#include "core/scan/stop_rule.hpp"

namespace pbnbv {

// The farthest --initial-view from the object centre, m (a camera farther sees nothing a rig can use).
inline constexpr double kMaxInitialViewM = 10.0;
// Throws std::invalid_argument naming --initial-view unless `p` is finite and 0.05..10 m from the
// object centre.
void check_initial_view(const Eigen::Vector3d& p);

struct ScanSettings;
// The turntable choice of the scan's moves and plans when `motion` is aware (auto: for every
// planner but pbnbv-paper): the quickest move, or for a scan recorded before it the least turn it
// was moved with (least_turn); else the preferred azimuth.
TurntableChoice turntable_choice(const ScanSettings& s);

struct ScanSettings {
  std::string scan_id;
  RigKind rig = kRig.value;
  std::string rig_model_path;
  PlannerKind planner = kPlanner.value;  // next best view, fixed ring views, or a baseline
  int views = kViews.value;              // at most this many views
  // Stop before the budget when the last views added (almost) no new surface, or too little per
  // second of rig time (stop_rule.hpp).
  StopRule stop_rule = kStopRule.value;
  SurfaceStopRule surface_rule;
  SecondsStopRule seconds_rule;
  double stop_radius_m = kStopRadius.value;  // a point farther than this from the model is new surface
  // How well the rig knows the camera's pose (registration's prior, 1 sigma per axis).
  double pose_sigma_m = kPoseSigmaMm.value * 1e-3;
  double pose_sigma_deg = kPoseSigmaDeg.value;
  double icp_voxel_m = kIcpVoxel.value;   // registration's ICP voxel (pbnbv-registration --icp-voxel)
  bool depth_filter = true;  // flying pixels and speckles removed from each frame (--depth-filter)

  // The rig's drivers run outside (a physical rig, or a twin started as one): the launcher
  // starts no twin and the object is unknown.
  bool external_rig = false;

  // Object. Twin runs: how the mesh was normalised. An unknown object (external rig): only the
  // working volume it stands in; the object frame sits at the volume's centre.
  std::string object_name;
  MeshNormalisation normalisation;
  std::optional<WorkingVolume> working_volume;  // set exactly when the object is unknown
  double object_z_m = 0;  // object frame origin above the turntable top (arm rig)

  // The object's bounding-box edges as far as the scan knows before it starts: the normalised
  // mesh's, or the working volume's (the first view's distance, the keep-out box, the crop).
  Eigen::Vector3d expected_extent_m() const;

  // View geometry.
  double working_distance_m = kWorkingDistance.value;  // d_c: camera to the object's bounding sphere
  double ring_elevation_deg = kRingElevation.value;    // ring planner: elevation above the object centre
  double ring_start_azimuth_deg = 0.0;
  // The first view of a next-best-view scan: camera position in the object frame, looking at
  // the origin; unset (NaN): the ring's first view (azimuth ring_start_azimuth_deg, elevation
  // ring_elevation_deg on the arm rig, 0 on the free rig).
  Eigen::Vector3d initial_view_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());

  // PB-NBV planning (method.md).
  int candidates = kCandidates.value;         // N
  int parallels = kParallels.value;           // alpha
  int sectors = kSectors.value;               // beta
  CandidateArea area = kArea.value;           // candidate area: hemisphere or full sphere
  int t_max = kTMax.value;                    // ellipsoid fitter's T_max
  double map_resolution_m = kMapResolution.value;
  double stop_fraction = kStopFraction.value;  // stop when best F < this * F of the first planned view (0: off)
  WhenDone when_done = kWhenDone.value;       // nothing left to aim at: stop, or spread (use the budget)
  MapPose map_pose = kMapPose.value;         // the pose each view enters the planner's map at
  Motion motion = kMotion.value;              // arm rig: moves chosen for what they cost (turntable_choice)
  double seconds_per_point = kSecondsPerPoint.value;  // motion-aware: pbnbv's ranking charges rig time
  // Motion-aware: how the motion executor chooses a view's turntable angle (kQuickest: the quickest
  // clear move; kNarrowed: the least turn, narrowed, the rule of scans recorded before; kGrid: on
  // the grid of 15 deg offsets alone, the rule of scans whose settings.json has no
  // planning.least_turn; the older two kept so that such scans replay as they were moved).
  LeastTurn least_turn = LeastTurn::kQuickest;
  int alternatives = kAlternatives.value;     // next-best views tried when the rig cannot reach the best
  int64_t seed = kPlannerSeed.value;          // the random planner's seed (view i uses seed + i)

  // Keep-out box for the arm (object frame) and the working volume for clouds.
  Eigen::Vector3d keepout_min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d keepout_max_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d crop_min_m = Eigen::Vector3d::Constant(-0.5);
  Eigen::Vector3d crop_max_m = Eigen::Vector3d::Constant(0.5);
  double ground_clearance_m = 0.004;
  double voxel_m = kCloudVoxel.value;  // per-frame and accumulated cloud downsampling

  CameraKind camera_model = kCamera.value;  // the named camera (its noise: depth_sensor.hpp)
  CameraIntrinsics camera;
  DepthRange depth_range;

  double speed_scale = kSpeedScale.value;
  double move_timeout_s = 60.0;
  double capture_timeout_s = 10.0;
  double sim_speed = kSimSpeed.value;
  double startup_timeout_s = 90.0;

  // Throws std::invalid_argument naming the first setting outside its range (the table's
  // ranges; parallels at most candidates; the camera and depth range valid; an initial view
  // away from the object centre).
  void validate() const;
};

nlohmann::json to_json(const ScanSettings& s);
ScanSettings scan_settings_from_json(const nlohmann::json& j);  // throws naming the field; validated

nlohmann::json to_json(const MeshNormalisation& n);

// Where the object sits and what the rig must keep clear of (s.rig and s.normalisation or
// s.working_volume set): on the arm rig it rests on the turntable, on the free rig it floats at
// the origin. Fills object_z_m, the keep-out box and the cloud's crop box from
// s.expected_extent_m(): an unknown object's keep-out box is its whole working volume (what the
// camera has not seen may be anywhere in it).
void place_object(ScanSettings& s);

// Limits on the object a scan is asked for, checked before anything starts.
inline constexpr std::size_t kTwinMaxTriangles = 200000;  // MuJoCo's limit on one mesh's faces
inline constexpr double kMaxObjectExtentM = 3.0;          // longest edge once normalised
inline constexpr double kMaxObjectAspect = 1000.0;        // longest / shortest bounding-box edge

// Throws std::invalid_argument naming `what` (the object) and the limit it breaks: more
// triangles than the twin can load (`for_twin`); a flat mesh (a sheet, a single triangle: its
// thinnest principal direction under 1/kMaxObjectAspect of its widest, whatever its tilt); a
// bounding box so thin that scaling its shortest edge to the object size makes it absurdly long;
// an object longer than the rig can walk around (kMaxObjectExtentM) once normalised (`mesh`
// normalised as `n` says).
void check_object_limits(const TriangleMesh& mesh, const MeshNormalisation& n, const std::string& what, bool for_twin);

// A scan id unique on any bus: "<name>-" and 16 hex digits from the system's random source
// (64 bits; two scans of one object started in the same second still differ). `name` is kept
// for people reading logs; characters other than letters, digits, '-', '_' and '.' become '_'.
std::string new_scan_id(const std::string& name);

}  // namespace pbnbv
