#pragma once
// Conversions between the planning messages (VOXEL_MAP, ELLIPSOIDS, PLAN_REQUEST, VIEW_PLAN) and
// the mapping and planning libraries' types, with the validation the view scorer applies.
#include <Eigen/Geometry>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bus/convert.hpp"
#include "bus/convert_kinds.hpp"
#include "core/mapping/voxel_map.hpp"
#include "core/planning/kinds.hpp"
#include "core/planning/ellipsoid.hpp"
#include "core/planning/planner.hpp"
#include "core/planning/planning_options.hpp"
#include "pbnbv/ellipsoid_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

namespace pbnbv::bus {

// An ellipsoid as a message: the principal axes become a proper rotation (a reflected frame
// has its third axis flipped, which describes the same ellipsoid).
inline ellipsoid_t to_msg(const Ellipsoid& e) {
  ellipsoid_t m;
  m.cls = e.cls == EllipsoidClass::kFrontier ? ellipsoid_t::kFrontier : ellipsoid_t::kOccupied;
  Eigen::Matrix3d r = e.axes;
  if (r.determinant() < 0) r.col(2) = -r.col(2);
  const Eigen::Quaterniond q(r);
  m.quat_wxyz[0] = q.w();
  m.quat_wxyz[1] = q.x();
  m.quat_wxyz[2] = q.y();
  m.quat_wxyz[3] = q.z();
  for (int k = 0; k < 3; ++k) {
    m.centre_m[k] = e.centre[k];
    m.semi_axes_m[k] = e.semi_axes[k];
  }
  m.num_voxels = e.num_points;
  return m;
}

// Throws std::invalid_argument naming `what` for an unknown class, a non-finite centre, a
// semi-axis that is not positive and finite, or a non-unit quaternion.
inline Ellipsoid from_msg(const ellipsoid_t& m, const std::string& what) {
  if (m.cls != ellipsoid_t::kOccupied && m.cls != ellipsoid_t::kFrontier) {
    throw std::invalid_argument(what + ".cls = " + std::to_string(m.cls) + " is neither kOccupied (0) nor kFrontier (1)");
  }
  Ellipsoid e;
  e.cls = m.cls == ellipsoid_t::kFrontier ? EllipsoidClass::kFrontier : EllipsoidClass::kOccupied;
  const Pose p = pose_from_arrays(m.centre_m, m.quat_wxyz, what);
  e.centre = p.translation();
  e.axes = p.linear();
  for (int k = 0; k < 3; ++k) {
    if (!(std::isfinite(m.semi_axes_m[k]) && m.semi_axes_m[k] > 0)) {
      std::ostringstream os;
      os << what << ".semi_axes_m[" << k << "] = " << m.semi_axes_m[k] << " is not a positive length";
      throw std::invalid_argument(os.str());
    }
    e.semi_axes[k] = m.semi_axes_m[k];
  }
  e.num_points = m.num_voxels;
  return e;
}

// The bounding box B of a voxel map message.
inline Eigen::AlignedBox3d bbox_of(const voxel_set_t& map) {
  return Eigen::AlignedBox3d(Eigen::Vector3d(map.bbox_min_m[0], map.bbox_min_m[1], map.bbox_min_m[2]),
                             Eigen::Vector3d(map.bbox_max_m[0], map.bbox_max_m[1], map.bbox_max_m[2]));
}

// The request as the core planner takes it, validated; throws naming the bad field.
inline PlanInput plan_input_from_msg(const plan_request_t& r) {
  PlanInput in;
  for (std::size_t i = 0; i < r.views_done.size(); ++i) {
    in.views_done.push_back(from_msg(r.views_done[i], "PLAN_REQUEST views_done[" + std::to_string(i) + "]"));
  }
  for (std::size_t i = 0; i < r.excluded.size(); ++i) {
    in.excluded.push_back(from_msg(r.excluded[i], "PLAN_REQUEST excluded[" + std::to_string(i) + "]"));
  }
  require_range(r.num_candidates, kCandidates.min, kCandidates.max, "PLAN_REQUEST num_candidates");
  require_range(r.num_parallels, kParallels.min, kParallels.max, "PLAN_REQUEST num_parallels");
  require_range(r.num_sectors, kSectors.min, kSectors.max, "PLAN_REQUEST num_sectors");
  require_range(r.working_distance_m, kWorkingDistance.min, kWorkingDistance.max, "PLAN_REQUEST working_distance_m");
  require_range(r.num_alternatives, kAlternatives.min, kAlternatives.max, "PLAN_REQUEST num_alternatives");
  require_range(r.stop_fraction, kStopFraction.min, kStopFraction.max, "PLAN_REQUEST stop_fraction");
  require_range(r.seconds_per_point, kSecondsPerPoint.min, kSecondsPerPoint.max, "PLAN_REQUEST seconds_per_point");
  if (r.seconds_per_point > 0) in.combined.seconds_per_point = r.seconds_per_point;
  if (!std::isnan(r.first_quality)) require_range(r.first_quality, -1e12, 1e12, "PLAN_REQUEST first_quality");
  if (r.num_parallels > r.num_candidates) throw std::invalid_argument("PLAN_REQUEST num_parallels exceeds num_candidates");
  in.candidates.num_views = r.num_candidates;
  in.candidates.num_parallels = r.num_parallels;
  in.candidates.area = r.full_sphere ? CandidateArea::kFullSphere : CandidateArea::kHemisphere;
  in.candidates.working_distance_m = r.working_distance_m;
  in.beta = r.num_sectors;
  in.num_alternatives = r.num_alternatives;
  in.stop_fraction = r.stop_fraction;
  in.when_done = r.spread_when_done ? WhenDone::kSpread : WhenDone::kStop;
  in.first_quality = r.first_quality;
  in.camera = CameraIntrinsics{r.width_px, r.height_px, r.fx, r.fy, r.cx, r.cy};
  in.camera.validate();
  in.depth_range = DepthRange{r.depth_min_m, r.depth_max_m};
  try {
    in.depth_range.validate();
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("PLAN_REQUEST depth_min_m / depth_max_m: ") + e.what());
  }
  return in;
}

// What the reachability of a request's candidates depends on, as a cache key: the scan, B (the
// map's bounding box), what places the candidates (count, parallels, sphere or hemisphere,
// working distance), the rig state the check starts from (joints, turntable: they order the IK
// solutions and choose among a turntable angle's whole turns), the object's height and the
// keep-out box. Exact (17 digits): equal keys, equal answers. ConvertPlanning's
// TheReachabilityKeyCoversEveryFieldItDependsOn classifies every field of PLAN_REQUEST, so a field
// added to the contract fails that test until it is placed in the key or said not to matter.
inline std::string reachability_key(const plan_request_t& r, const Eigen::AlignedBox3d& box) {
  std::ostringstream key;
  key.precision(17);
  key << r.scan_id.size() << ':' << r.scan_id << ' ' << box.min().transpose() << ' ' << box.max().transpose() << ' '
      << r.num_candidates << ' ' << r.num_parallels << ' ' << r.full_sphere << ' ' << r.working_distance_m << ' '
      << r.object_z_m << ' ' << r.turntable_angle_rad;
  for (int k = 0; k < 6; ++k) key << ' ' << r.joint_position_rad[k];
  for (int k = 0; k < 3; ++k) key << ' ' << r.keepout_min_m[k] << ' ' << r.keepout_max_m[k];
  key << ' ' << static_cast<int>(r.turntable_choice);
  return key.str();
}

static_assert(static_cast<int>(VoxelState::kNone) == voxel_set_t::kNone && static_cast<int>(VoxelState::kEmpty) == voxel_set_t::kEmpty &&
                  static_cast<int>(VoxelState::kOccupied) == voxel_set_t::kOccupied &&
                  static_cast<int>(VoxelState::kUnknown) == voxel_set_t::kUnknown &&
                  static_cast<int>(VoxelState::kFrontier) == voxel_set_t::kFrontier,
              "the map's states are the VOXEL_MAP constants");

// The VOXEL_MAP's cells as the ray caster reads them; throws naming the message's bad field.
inline VoxelGrid grid_from_msg(const voxel_set_t& map) {
  VoxelGrid g;
  g.origin_m = Eigen::Vector3d(map.bbox_min_m[0], map.bbox_min_m[1], map.bbox_min_m[2]);
  g.dims = Eigen::Vector3i(map.dims[0], map.dims[1], map.dims[2]);
  g.resolution_m = map.resolution_m;
  g.cells.resize(map.cells.size());
  for (std::size_t i = 0; i < map.cells.size(); ++i) g.cells[i] = static_cast<VoxelState>(static_cast<uint8_t>(map.cells[i]));
  g.validate("VOXEL_MAP of view " + std::to_string(map.iteration));
  if (g.empty()) throw std::invalid_argument("VOXEL_MAP of view " + std::to_string(map.iteration) + " carries no cells (dims 0)");
  return g;
}


// Writes a planning step's result into its VIEW_PLAN answer (the chosen view, its scores, the
// partition, the candidate counts, the alternatives, the stage times).
inline void fill_answer(view_plan_t& out, const PlanResult& res) {
  out.outcome = res.outcome == PlanResult::Outcome::kView ? view_plan_t::kView
                : res.outcome == PlanResult::Outcome::kStop ? view_plan_t::kStop : view_plan_t::kFailed;
  out.reason = res.reason;
  out.ranking = ranking_to_msg(res.ranking);
  if (const ViewScore* s = res.chosen_score()) {
    out.object_T_camera = to_msg(res.candidates[res.chosen]);
    out.view_quality = s->quality;
    out.frontier_area_px = s->frontier_sum;
    out.occupied_area_px = s->occupied_sum;
  }
  out.first_quality = res.first_quality;
  out.partition = res.partition;
  out.allowed_sectors = res.allowed_sectors;
  out.num_allowed_sectors = static_cast<int32_t>(out.allowed_sectors.size());
  out.partition_fallback = res.partition_fallback;
  for (int k = 0; k < 3; ++k) out.sphere_centre_m[k] = res.centre[k];
  out.sphere_radius_m = res.radius_m;
  out.num_candidates = static_cast<int32_t>(res.candidates.size());
  out.num_unreachable = res.num_unreachable;
  out.num_excluded = res.num_excluded;
  out.num_scored = res.num_scored;
  out.num_frontier_ellipsoids = res.num_frontier_ellipsoids;
  out.num_occupied_ellipsoids = res.num_occupied_ellipsoids;
  out.candidates_s = res.candidates_s;
  out.scoring_s = res.scoring_s;
  for (int a : res.alternatives) {
    out.alternatives.push_back(to_msg(res.candidates[a]));
    out.alternative_quality.push_back(res.scores[a].quality);
  }
  out.num_alternatives = static_cast<int32_t>(out.alternatives.size());
}


// The answer to `r` with nothing planned yet (outcome and reason to be set).
inline view_plan_t empty_answer(const plan_request_t& r) {
  view_plan_t out{};
  out.scan_id = r.scan_id;
  out.iteration = r.iteration;
  out.request_id = r.request_id;
  out.planner = r.planner;
  out.object_T_camera = to_msg(Pose::Identity());
  // No scores yet: what the planner asked for ranks by (a request naming no planner fails later).
  Ranking ranking = Ranking::kF;
  try {
    ranking = ranking_of(planner_from_msg(r.planner, "PLAN_REQUEST planner"));
  } catch (const std::invalid_argument&) {
  }
  out.ranking = ranking_to_msg(ranking);
  out.view_quality = 0;
  out.first_quality = r.first_quality;
  out.partition = -1;
  out.num_allowed_sectors = 0;
  out.num_alternatives = 0;
  return out;
}


}  // namespace pbnbv::bus
