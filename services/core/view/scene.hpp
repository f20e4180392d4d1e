#pragma once
// One view of a scan as the 3-D page draws it (`pbnbv view`): the cloud so far (decimated for
// the page), the voxel map's frontier, the ellipsoids as mesh parameters, the candidates with F,
// the views taken and the chosen view, and the status text. Plain data and functions; the view
// service fills a Scene from the bus, load_scan_folder from a finished scan's files.
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/base/pose.hpp"
#include "core/geometry/camera_model.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/planning/ellipsoid.hpp"
#include "core/planning/planner.hpp"

namespace pbnbv {

// The cloud for the page: voxel_downsample at voxel_m, the edge grown by 1.5x until at most
// max_points remain. Throws std::invalid_argument for voxel_m <= 0 or max_points < 1.
PointCloud decimate_cloud(const PointCloud& cloud, double voxel_m, std::size_t max_points);

// An ellipsoid as a unit sphere scaled by `scale` (the semi-axes), rotated by `quat_xyzw` (a
// proper rotation, three.js order) and moved to `centre`: a point p of the unit sphere is drawn
// at centre + R * diag(scale) * p.
struct EllipsoidMesh {
  bool frontier = false;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();
  Eigen::Vector4d quat_xyzw = Eigen::Vector4d(0, 0, 0, 1);
};
EllipsoidMesh ellipsoid_mesh(const Ellipsoid& e);

// Every candidate of a planning step (candidate_views(bbox, spec), in that order) with its F
// (score_view with the plan's ellipsoids and camera), and each F scaled to 0..1 between the
// smallest and the largest F of the step (all 0.5 when they are equal): the page's colour.
struct ScoredCandidate {
  Pose object_T_camera = Pose::Identity();
  double quality = 0;  // F, px
  double shade = 0;    // 0 lowest F .. 1 highest
};
std::vector<ScoredCandidate> score_candidates(const std::vector<Ellipsoid>& ellipsoids,
                                              const Eigen::AlignedBox3d& bbox, const CandidateSpec& spec,
                                              const CameraIntrinsics& camera);

// One view's scene. `view` counts from 1 (view 1 is the first view taken).
struct Scene {
  std::string scan_id;
  int view = 0;                       // views taken so far (0: none yet)
  std::string status;                 // state and message
  double coverage = -1;               // percent, -1: unknown
  PointCloud cloud;                   // decimated
  std::size_t cloud_points_total = 0; // before decimation
  std::vector<Eigen::Vector3f> frontier;  // frontier voxel centres
  double resolution_m = 0;            // voxel edge of the map
  std::vector<EllipsoidMesh> ellipsoids;
  std::vector<ScoredCandidate> candidates;
  int plan_candidates = 0;            // candidates the plan generated (its count)
  std::vector<Pose> views_taken;      // camera poses, object frame
  std::optional<Pose> chosen;         // the next view the plan chose
  double chosen_quality = 0;
  std::string chosen_ranking = "f_px";  // what chosen_quality means (VIEW_PLAN's ranking)
};

// The scene as the page reads it: points as flat [x, y, z, ...] arrays in metres, poses as
// {"position_m", "quat_wxyz"}, counts beside each array.
nlohmann::json scene_json(const Scene& s);

// The scenes of a finished scan folder, one per view taken (views 1..n): the cloud of the merged
// frames/view_NNN.ply up to that view (cloud.ply when no frame file is there), the views taken up
// to it, and the plan made after it (the next view's plan in scan.json: its ellipsoids, the
// candidates around its B scored again with them, the chosen view); no frontier voxels (scan.json
// keeps their count only). Throws std::runtime_error naming the folder and what is missing or
// malformed.
std::vector<Scene> load_scan_folder(const std::string& dir, double voxel_m, std::size_t max_points);

}  // namespace pbnbv
