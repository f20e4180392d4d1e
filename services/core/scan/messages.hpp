#pragma once
// The requests and answers of a scan's sequence as plain data: what the coordinator asks of the
// motion executor and the camera service, and what they answer. The bus translates them to and
// from the LCM messages of the same names (bus/convert_scan.hpp); the sequencing classes of this
// library work on these alone, so they are tested without a bus.
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/base/pose.hpp"
#include "core/geometry/rig_kind.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/colour_image.hpp"
#include "core/geometry/mesh_summary.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/perception/new_surface.hpp"
#include "core/planning/kinds.hpp"

namespace pbnbv {

// MOVE_REQUEST: bring the camera to a pose (object frame).
struct MoveRequest {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  Pose object_T_camera = Pose::Identity();
  double object_z_m = 0;                // object frame origin above the turntable top, m
  Eigen::AlignedBox3d keepout;          // object-frame box the rig must not enter (empty: none)
  double speed_scale = 1.0;             // (0, 1]: fraction of the joint speed limits
  double timeout_s = 60.0;              // not settled after this long: timed out
  bool plan_only = false;               // only check reachability
  TurntableChoice turntable_choice = TurntableChoice::kPreferred;  // arm rig (core/rig/rig.hpp)
};

enum class MoveStatus : int8_t {
  kReached = 0, kUnreachable = 1, kTimedOut = 2, kRejected = 3, kPlanned = 4, kBusy = 5, kRigSilent = 6
};
const char* to_string(MoveStatus s);  // "reached", "unreachable", "timed_out", ...

// MOVE_RESULT: what became of a MoveRequest.
struct MoveResult {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  MoveStatus status = MoveStatus::kRejected;
  std::string reason;                          // empty when reached
  Pose requested_object_T_camera = Pose::Identity();
  Pose reached_object_T_camera = Pose::Identity();  // forward kinematics of the readings at settle
  double position_error_m = 0;
  double angle_error_rad = 0;
  Vector6d joint_target_rad = Vector6d::Zero();
  Vector6d joint_position_rad = Vector6d::Zero();
  double turntable_target_rad = 0;
  double turntable_angle_rad = 0;
  double plan_s = 0, move_s = 0, settle_s = 0, rig_motion_s = 0;  // see move_result_t
  int64_t settled_utime = 0;                   // rig clock at settle, microseconds
  std::string route;                           // the path taken: "direct", or the detour's name
  double path_s = 0;                           // the path's time by the rig-time model, s
  int32_t contacts = 0;                        // contact events the rig reported during the move (-1: it cannot tell)
  std::string contact;                         // the last one ("" when contacts <= 0)
  int64_t within_tolerance_utime = 0;          // rig clock when within tolerance (0: never)
};

// CAPTURE_REQUEST: one frame at the current pose, as an object-frame cloud.
struct CaptureRequest {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  int64_t not_before_utime = 0;          // rig clock: only a frame exposed at or after this
  double object_z_m = 0;
  Eigen::AlignedBox3d crop;              // working volume, object frame
  double ground_clearance_m = 0;
  double voxel_m = 0;
  double timeout_s = 10.0;               // per trigger
};

// CLOUD: the answer to a CaptureRequest.
struct CaptureResult {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  bool ok = false;
  std::string message;                     // what happened (why not, when !ok)
  Pose object_T_camera = Pose::Identity(); // the pose the points were placed with
  Vector6d joint_position_rad = Vector6d::Zero();
  double turntable_angle_rad = 0;
  int64_t depth_frame_seq = -1;
  int64_t depth_frame_utime = 0;
  int num_valid_pixels = 0;
  int num_cropped = 0;
  double voxel_m = 0;
  double capture_s = 0, process_s = 0;
  // The turntable top's plane as the frame saw it (point_cloud_t): z = a x + b y + c.
  int ground_points = 0;                   // 0: no fit
  double ground_z_m = 0;
  Eigen::Vector3d ground_abc = Eigen::Vector3d::Zero();
  double ground_sigma_m = 0;
  PointCloud points;                       // object frame, m
  // One unit normal per point, object frame, facing the camera, from the depth image's
  // neighbourhood (zero where none was found); empty: none sent.
  std::vector<Eigen::Vector3f> normals;
  // One colour per point from the frame's colour image; empty: the frame had none.
  std::vector<Rgb> colours;
};

// ---- What the coordinator sends and receives besides moves and captures ----------------------

// REGISTERED_CLOUD: the registration service's answer to a CLOUD (same request_id). `cloud`
// holds the registered pose and points when accepted, the kinematic ones otherwise.
struct RegisteredCloud {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;                  // the CaptureRequest the cloud answered
  CaptureResult cloud;
  Pose kinematic_object_T_camera = Pose::Identity();
  bool accepted = false;                   // merged into the model
  bool refined = false;                    // a correction was taken
  bool flagged = false;                    // merged at the kinematic pose: alignment not trusted
  std::string reason;
  double constraint = 0;                   // 0..1, see registered_cloud_t
  Pose correction = Pose::Identity();      // registered = correction * kinematic
  double translation_m = 0;
  double rotation_deg = 0;
  double overlap = 0;
  double rmse_m = 0;
  double icp_translation_m = 0;            // ICP's proposal, before the prior
  double icp_rotation_deg = 0;
  double prior_sigmas = 0;                 // its distance under the kinematic pose's uncertainty
  int iterations = 0;                      // ICP iterations
  int model_points = 0;
  double register_s = 0;
  // What the registration service made of the view in the scan's folder (empty names: it writes
  // none): the frame, the depth image, the model (cloud.ply) it was merged into.
  std::string frame_file;                  // "frames/view_NNN.ply"
  std::string depth_file;                  // "depth/view_NNN.png" ("": the frame did not arrive)
  bool normals_from_depth = true;          // false: fitted to the nearest points
  std::optional<NewSurface> new_surface;   // accepted views: what the view added to the model
  double accumulate_s = 0;                 // writing the frame and the model, s
};

// MESH_REQUEST: mesh the scan's merged views (the registration service's frames) at its end.
struct MeshRequest {
  std::string scan_id;
  int64_t request_id = 0;
  std::vector<int> views;           // the merged views, 0-based, ascending (MESH_REQUEST's count from 1)
  CameraIntrinsics camera;          // the frames' camera
  double point_spacing_m = 0;       // their downsampling voxel
};

// MESH_RESULT: the mesh written into the scan's folder (ok), or why there is none.
struct MeshResult {
  std::string scan_id;
  int64_t request_id = 0;
  bool ok = false;
  std::string message;              // why not
  MeshSummary mesh;                 // ok only
};

// VOXEL_MAP as the coordinator records it: the map's state after a view, without the voxels.
struct VoxelMapSummary {
  std::string scan_id;
  int iteration = 0;                       // view integrated last
  int64_t request_id = 0;                  // that view's capture request
  bool updated = false;                    // false: this view left the map unchanged
  std::string message;
  double resolution_m = 0;
  Eigen::Vector3d bbox_min_m = Eigen::Vector3d::Zero();  // B, object frame
  Eigen::Vector3d bbox_max_m = Eigen::Vector3d::Zero();
  int num_none = 0, num_empty = 0, num_occupied = 0, num_unknown = 0, num_frontier = 0;
  double update_s = 0;                     // wall time of the map update
};

// One ellipsoid of ELLIPSOIDS as the fitter sent it (recorded, not computed with).
struct EllipsoidSummary {
  bool frontier = false;                   // false: an Occupied cluster
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d semi_axes_m = Eigen::Vector3d::Zero();
  std::array<double, 4> quat_wxyz = {1, 0, 0, 0};  // principal axes
  int num_voxels = 0;
};

// ELLIPSOIDS as the coordinator records it in the plan made from it.
struct EllipsoidSetSummary {
  std::string scan_id;
  int iteration = 0;                       // the map's view
  int64_t request_id = 0;                  // the map's request (its view's capture request)
  int occupied_components = 0;             // T chosen by BIC
  int frontier_components = 0;
  double fit_s = 0;
  std::vector<EllipsoidSummary> ellipsoids;
};

// PLAN_REQUEST: the coordinator asks the view scorer for the view after `iteration - 1`.
struct PlanRequest {
  std::string scan_id;
  int iteration = 0;                       // the view to plan, 0-based
  int64_t request_id = 0;
  PlannerKind planner = PlannerKind::kPbnbv;  // pbnbv, raycast, random or oracle (not ring)
  int64_t seed = 0;                        // the random planner's seed for this request
  int map_iteration = -1;                  // plan from the map of this view
  int64_t map_request_id = 0;              // answering this request (that view's capture request)
  std::vector<Pose> views_done;            // registered camera poses of the mapped views
  std::vector<Pose> excluded;              // views the rig could not reach, capture or map
  int num_candidates = 0;                  // N
  int num_parallels = 0;                   // alpha
  int num_sectors = 0;                     // beta
  CandidateArea area = CandidateArea::kHemisphere;
  double working_distance_m = 0;           // d_c
  int num_alternatives = 0;
  double stop_fraction = 0;
  WhenDone when_done = WhenDone::kStop;
  double first_quality = 0;                // F of the first planned view, NaN before it
  CameraIntrinsics camera;
  DepthRange depth_range;
  bool check_reachability = false;         // arm rig
  Vector6d joint_position_rad = Vector6d::Zero();  // the rig state the plan starts from
  double turntable_angle_rad = 0;
  double object_z_m = 0;
  Eigen::AlignedBox3d keepout;             // empty: none
  TurntableChoice turntable_choice = TurntableChoice::kPreferred;  // as the motion executor's
  double seconds_per_point = 0;            // motion-aware ranking (0: off)
};

enum class PlanOutcome : int8_t { kView = 0, kStop = 1, kFailed = 2 };
const char* to_string(PlanOutcome o);      // "view", "stop", "failed"

// VIEW_PLAN: the view scorer's answer to a PlanRequest (same request_id). Every number is 0
// unless the scorer filled it (a plan that could not be asked for stays so).
struct ViewPlan {
  std::string scan_id;
  int iteration = 0;
  int64_t request_id = 0;
  PlannerKind planner = PlannerKind::kPbnbv;
  PlanOutcome outcome = PlanOutcome::kFailed;
  std::string reason;
  Pose object_T_camera = Pose::Identity(); // the next view (outcome kView)
  Ranking ranking = Ranking::kF;           // what view_quality and alternative_quality mean
  double view_quality = 0;                 // in the unit of `ranking` (F: pixels)
  double first_quality = 0;
  double frontier_area_px = 0, occupied_area_px = 0;
  int partition = 0;
  std::vector<int> allowed_sectors;
  bool partition_fallback = false;
  Eigen::Vector3d sphere_centre_m = Eigen::Vector3d::Zero();
  double sphere_radius_m = 0;
  int num_candidates = 0, num_unreachable = 0, num_excluded = 0, num_scored = 0;
  int num_frontier_ellipsoids = 0, num_occupied_ellipsoids = 0;
  double candidates_s = 0, reachability_s = 0, scoring_s = 0, wait_s = 0, plan_s = 0;
  std::vector<Pose> alternatives;          // next best views, best first (outcome kView)
  std::vector<double> alternative_quality;
};

// SCAN_STATUS: where the scan is.
enum class ScanState : int8_t {
  kStarting = 0, kMoving = 1, kCapturing = 2, kIntegrating = 3, kPlanning = 4, kDone = 5, kFailed = 6, kStopped = 7
};

struct ScanStatus {
  std::string scan_id;
  int iteration = 0;                       // current view, 0-based
  int num_views_planned = 0;
  int num_views_done = 0;
  ScanState state = ScanState::kStarting;
  std::string message;
  double elapsed_s = 0;
  int num_points = 0;                      // in the accumulated cloud
};

}  // namespace pbnbv
