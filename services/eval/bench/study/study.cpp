#include "study.hpp"

#include <sstream>

#include "core/planning/ellipsoid_fit.hpp"
#include "core/planning/raycast.hpp"

namespace pbnbv::study {
namespace {

// The request the scan sequencer sends on the free rig, full sphere, for `planner`.
PlanInput request(const std::string& planner, const VoxelMap& map, const State& st, const CameraIntrinsics& camera,
                  const DepthRange& range) {
  const PlannerKind kind = parse_name<PlannerKind>(planner);
  PlanInput in;
  in.bbox = map.bounds();
  in.candidates.area = CandidateArea::kFullSphere;
  in.views_done = st.views_done;
  in.camera = camera;
  in.depth_range = range;
  in.first_quality = st.first_quality;
  in.when_done = WhenDone::kSpread;
  in.beta = partition_sectors(kind, true, kSectors.value);
  if (uses_ellipsoids(kind)) {
    EllipsoidParams p;
    p.voxel_m = map.params().resolution_m;
    in.ellipsoids = fit_both_classes(map.centres(VoxelState::kOccupied), map.centres(VoxelState::kFrontier), p);
  }
  return in;
}

template <typename F>
std::string json_array(std::size_t n, F f) {
  std::ostringstream os;
  os.precision(6);
  os << "[";
  for (std::size_t i = 0; i < n; ++i) os << (i ? "," : "") << f(i);
  os << "]";
  return os.str();
}

}  // namespace

Choice plan(const std::string& planner, const VoxelMap& map, State& st, const CameraIntrinsics& camera,
            const DepthRange& range, const Truth& truth) {
  const PlannerKind kind = parse_name<PlannerKind>(planner);
  PlanInput in = request(planner, map, st, camera, range);
  const VoxelGrid grid = map.grid();
  PlanResult r;
  if (kind == PlannerKind::kRaycast) {
    RaycastParams rp;
    rp.camera = camera;
    rp.range = range;
    r = plan_raycast(in, grid, rp);
  } else if (kind == PlannerKind::kOracle) {
    VisibilityParams vp;
    vp.camera = camera;
    vp.range = range;
    r = plan_oracle(in, *truth.mesh, *truth.samples, vp);
  } else if (is_pbnbv(kind)) {
    if (combined_ranking(kind)) in.grid = &grid;
    r = plan_pbnbv(in);
  } else {
    throw std::invalid_argument("pbnbv-study plans with pbnbv, pbnbv-paper, raycast or oracle, not " + planner);
  }
  Choice c;
  c.why = std::string(name_of(r.ranking));
  if (r.outcome != PlanResult::Outcome::kView) {
    c.why = r.reason;
    return c;
  }
  if (!std::isfinite(st.first_quality)) st.first_quality = r.first_quality;
  c.ok = true;
  c.view = r.candidates[r.chosen];
  c.why += " " + std::to_string(r.scores[r.chosen].quality);
  return c;
}

std::string analyse_state(const VoxelMap& map, const State& st, const CameraIntrinsics& camera, const DepthRange& range,
                          const Truth& truth) {
  PlanInput in = request("pbnbv", map, st, camera, range);
  const VoxelGrid grid = map.grid();
  in.grid = &grid;
  in.when_done = WhenDone::kStop;
  const PlanResult combined = plan_pbnbv(in);
  in.grid = nullptr;
  const PlanResult f = plan_pbnbv(in);  // F for every candidate (empty without a frontier)
  const std::size_t n = combined.candidates.size();
  std::vector<uint8_t> active(n);
  for (std::size_t i = 0; i < n; ++i) active[i] = combined.status[i] == CandidateStatus::kScored;
  RaycastParams rp;
  rp.camera = camera;
  rp.range = range;
  const std::vector<RaycastGain> ray = raycast_gains(grid, combined.candidates, active, rp);
  UnobservedRayParams up;
  up.camera = camera;
  up.range = range;
  const VoxelGrid coarse = coarsened(grid, std::max(1, static_cast<int>(std::lround(kRayCellM / grid.resolution_m))));
  up.saturation_voxels = kRaySaturationM / coarse.resolution_m;
  const std::vector<double> rays = unobserved_ray_scores(coarse, combined.candidates, active, up);
  VisibilityParams vp;
  vp.camera = camera;
  vp.range = range;
  const std::vector<uint8_t> seen =
      visible_from_any(*truth.mesh, truth.samples->points, truth.samples->normals, st.views_done, vp);
  const std::vector<int> oracle =
      count_newly_visible(*truth.mesh, truth.samples->points, truth.samples->normals, combined.candidates, seen, vp);
  const bool has_f = f.scores.size() == n && f.num_frontier_ellipsoids > 0;
  const bool has_combined = combined.ranking == Ranking::kCombined;
  std::ostringstream os;
  os << "{\"active\":" << json_array(n, [&](std::size_t i) { return int(active[i]); })
     << ",\"oracle\":" << json_array(n, [&](std::size_t i) { return oracle[i]; })
     << ",\"raycast\":" << json_array(n, [&](std::size_t i) { return ray[i].unknown; })
     << ",\"F\":" << json_array(n, [&](std::size_t i) { return has_f ? f.scores[i].quality : 0.0; })
     << ",\"gap\":" << json_array(n, [&](std::size_t i) { return combined.gap_deg.empty() ? 0.0 : combined.gap_deg[i]; })
     << ",\"rays\":" << json_array(n, [&](std::size_t i) { return rays[i]; })
     << ",\"combined\":" << json_array(n, [&](std::size_t i) { return has_combined ? combined.scores[i].quality : 0.0; })
     << "}";
  return os.str();
}

}  // namespace pbnbv::study
