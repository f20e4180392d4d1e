#pragma once
// One PB-NBV planning step as a plain function (docs/method.md "Candidate views", "Scoring a
// candidate view", "Global partitioning", "Termination"): candidates on the sphere
// around B, reachability filter, F for every candidate, the partition rule, the choice and the
// next best alternatives. The view scorer service wraps this; benchmarks and tests call it
// directly.
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/geometry/camera_model.hpp"
#include "core/geometry/mesh.hpp"
#include "core/geometry/visibility.hpp"
#include "core/planning/ellipsoid.hpp"
#include "core/base/pose.hpp"
#include "core/planning/raycast.hpp"
#include "core/planning/view_scoring.hpp"
#include "core/base/units.hpp"
#include "core/planning/kinds.hpp"
#include "core/planning/planning_options.hpp"

namespace pbnbv {

// What became of a candidate in a planning step. kExcluded: skipped as too close to a view the
// rig could not reach or capture (or, with skip_revisits, to a view already taken).
enum class CandidateStatus : uint8_t {
  kScored = 0,
  kUnreachable = 1,
  kOutsidePartition = 2,
  kExcluded = 3
};

struct CandidateSpec {
  int num_views = kCandidates.value;             // N
  int num_parallels = kParallels.value;          // alpha
  CandidateArea area = kArea.value;              // kHemisphere: above the centre of B
  double working_distance_m = kWorkingDistance.value;  // d_c; R = d_c + d_b, d_b = half the diagonal of B
};

// The candidate sphere for a bounding box: centre of B and R = d_c + d_b.
void candidate_sphere(const Eigen::AlignedBox3d& bbox, double working_distance_m,
                      Eigen::Vector3d* centre, double* radius);

// The candidate views for B (sphere_band_views over [0, pi/2] or [0, pi]).
std::vector<Pose> candidate_views(const Eigen::AlignedBox3d& bbox, const CandidateSpec& spec);

// pbnbv's combined ranking (docs/method.md "Beyond the paper", departure 4). F alone is a weak
// guide on objects it was not tuned on: after the first view it aims at the rim of the seen
// surface rather than the unseen back, and it has no memory of where the views are. Three terms,
// each scaled to [0, 1] over a shortlist and summed with equal weights, rank the candidates:
//  - F, the paper's projection score (from the ellipsoids; absent with no Frontier ellipsoid);
//  - the gap: the angle, seen from the centre of B, to the nearest view taken;
//  - the rays: unobserved_ray_scores through the map coarsened to cells of at least ray_cell_m,
//    saturating at saturation_m (raycast.hpp).
// The shortlist is the top `shortlist` candidates by F and the top `shortlist` by the gap (within
// the partition's allowed sectors), so the rays are cast for at most 2 x shortlist candidates.
//
// Motion-aware (PlanInput::move_time_s given): each candidate's rig time to reach it from where the
// rig stands is charged against its combined score, one point per `seconds_per_point` seconds, so
// that of two equally good views the quicker one is taken, and a view twice as far away must be
// that much better.
// A candidate's path from where the rig stands, for motion-aware planning (PlanInput::path).
struct CandidatePath {
  bool clear = false;
  double time_s = 0;  // clear: the path's time at full speed, s
  std::string route;  // "direct", "via home", ...; !clear: why none is clear
};
// The most paths the ranking asks for in one plan (each a path check of the rig model).
inline constexpr int kPathChecks = 8;

struct CombinedRanking {
  int shortlist = kShortlistPerTerm;
  double saturation_m = kRaySaturationM;
  double ray_cell_m = kRayCellM;
  double seconds_per_point = kMotionSecondsPerPoint;
};

struct PlanInput {
  std::vector<Ellipsoid> ellipsoids;
  Eigen::AlignedBox3d bbox;          // B
  CandidateSpec candidates;
  int beta = kSectors.value;         // partition sectors; 1: no partitioning
  // Where sector 0 starts: centred on the first view (its azimuth - pi / beta), so that the first
  // view lies in the middle of the scanned sector and the two adjacent sectors lie symmetrically
  // on either side of it (the paper does not say where the sectors start; starting them at
  // azimuth 0 puts a default first view at azimuth 0 on a sector boundary). false: azimuth 0.
  bool sectors_centred_on_first_view = true;
  std::vector<Pose> views_done;      // camera poses of the views taken (object frame)
  std::vector<Pose> excluded;        // views the rig could not reach or capture
  double exclude_angle_rad = 10.0 * kPi / 180.0;  // candidates this close (seen from the
                                                   // centre) to an excluded view are skipped
  // Also skip candidates this close to a view already taken: in a static scene the same view
  // sees nothing new, yet F (which has no memory) can keep choosing it once the map stops
  // changing.
  bool skip_revisits = true;
  CameraIntrinsics camera;
  DepthRange depth_range;  // the camera's (the combined ranking's rays stop at its ends)
  double stop_fraction = kStopFraction.value;  // stop when best F < stop_fraction * first_quality
  double first_quality = std::numeric_limits<double>::quiet_NaN();  // NaN: this is the first
  int num_alternatives = kAlternatives.value;
  // When the planner has nothing left to aim at (PB-NBV: no frontier ellipsoid; raycast: no
  // unobserved voxel in view) it stops (kStop), or (kSpread: a fixed view budget, as in the
  // paper's evaluation) chooses the candidate farthest in angle from every view taken.
  WhenDone when_done = kWhenDone.value;
  // Our departure (planner pbnbv; null for pbnbv-paper, which ranks by F alone): the combined
  // ranking (CombinedRanking below) casts its rays through this map, B's cells.
  const VoxelGrid* grid = nullptr;
  CombinedRanking combined;
  // Called between chunks of a long scoring (ray casting's, the oracle's), so that a service can show it is
  // alive (its heartbeat) while it plans; empty: not called.
  std::function<void()> progress;
  // Reachability of each candidate (the motion executor's check), called once with every
  // candidate (candidate_views(bbox, candidates), so a caller may compute it ahead), or empty:
  // all reachable.
  std::function<std::vector<bool>(const std::vector<Pose>&)> reachable;
  // Motion-aware planning (the combined ranking only): per candidate (candidate_views order), the
  // rig's time to reach it from where it stands, s (core/rig move_s); empty: every view costs the
  // same. Its size must be the candidates' (else std::invalid_argument).
  std::vector<double> move_time_s;
  // Motion-aware with path checks: candidate i's path from where the rig stands, its time and
  // route (the scorer: the direct move when it is clear along its whole path, core/rig
  // ReachabilityChecker::path_collision, else a detour through home). move_time_s holds the direct
  // moves' times, which a detour exceeds; the ranking asks for the best candidate's path, charges
  // its time, ranks again, and so on until the best has its path's time (at most kPathChecks
  // asks); a candidate whose path is not clear is unreachable. Empty: move_time_s as given.
  std::function<CandidatePath(int)> path;
};

struct PlanResult {
  enum class Outcome { kView, kStop, kFailed };
  Outcome outcome = Outcome::kFailed;
  std::string reason;
  Ranking ranking = Ranking::kF;  // what `scores[..].quality` means (kinds.hpp; set by every planner)

  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // candidate sphere
  double radius_m = 0;
  std::vector<Pose> candidates;
  std::vector<CandidateStatus> status;  // per candidate
  std::vector<ViewScore> scores;        // per candidate (zero unless kScored)
  int chosen = -1;                      // index into candidates
  std::vector<int> alternatives;        // next best scored candidates, best first
  double first_quality = std::numeric_limits<double>::quiet_NaN();

  int partition = -1;                   // sector of the chosen view (-1: beta 1)
  double sector_start_rad = 0;          // azimuth where sector 0 starts
  std::vector<int> allowed_sectors;
  bool partition_fallback = false;      // nothing scorable in the allowed sectors

  int num_unreachable = 0, num_excluded = 0, num_scored = 0;
  int num_frontier_ellipsoids = 0, num_occupied_ellipsoids = 0;
  // The combined ranking's terms per candidate (empty otherwise): F in pixels (0 without a Frontier
  // ellipsoid), the gap in degrees, the ray term (0 off the shortlist).
  std::vector<double> f_px, gap_deg, rays;
  std::vector<double> move_time_s;  // motion-aware: the rig time charged against each candidate, s
  int path_checks = 0;              // motion-aware: the paths asked for (PlanInput::path)
  std::string route;                // the chosen candidate's, when its path was asked for
  double candidates_s = 0, reachability_s = 0, scoring_s = 0;  // wall time per stage

  const ViewScore* chosen_score() const { return chosen >= 0 ? &scores[chosen] : nullptr; }
};

// One planning step. By F (the paper's) or, with in.grid, by the combined ranking (pbnbv). Has
// nothing left to aim at when no Frontier ellipsoid remains (combined: and no shortlisted candidate's
// rays reach an unobserved voxel): stops (kStop) or chooses the farthest view instead (when_done
// kSpread); stops when the best F is below stop_fraction * first_quality. Fails (kFailed) when B is empty or no candidate is
// reachable. The sectors already scanned are those of views_done about the current centre of
// B; while some sector is unscanned the choice is limited to unscanned sectors adjacent to
// scanned ones (falling back to every sector, and saying so, when none of those holds a
// scorable candidate); with nothing scanned every sector is allowed.
PlanResult plan_pbnbv(const PlanInput& in);

// The baselines of the benchmark, on the same candidates (the same sphere around B, the same
// reachability filter and exclusions) and the same map; no global partitioning (that is PB-NBV's).
//  - raycast: the candidate whose rays reveal the most unobserved voxels (raycast.hpp); quality =
//    that count. Stops when no candidate sees an unobserved voxel, or by stop_fraction.
//  - random: a uniformly random candidate (and random alternatives), reproducible from `seed`.
PlanResult plan_raycast(const PlanInput& in, const VoxelGrid& grid, const RaycastParams& params);
PlanResult plan_random(const PlanInput& in, uint64_t seed);

// The benchmark's yardstick, not a planner for an unknown object: it knows the true surface.
// On the same candidates, reachability filter and exclusions, greedily the candidate that sees
// the most of `truth`'s samples not seen by any view taken (in.views_done; seen as
// visible_from_any counts, core/geometry/visibility.hpp, with the camera and depth range of
// `visibility`); quality = that count. No partitioning. Nothing new to see: kStop, or kSpread's
// farthest view. Throws as visible_from_any for a bad mesh, samples or parameters.
PlanResult plan_oracle(const PlanInput& in, const TriangleMesh& truth, const SurfaceSamples& samples,
                       const VisibilityParams& visibility);

}  // namespace pbnbv
