// One PB-NBV planning step (planner.hpp).
#include "core/planning/planner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>
#include <sstream>

#include "core/geometry/views.hpp"
#include <limits>
#include "core/base/units.hpp"

namespace pbnbv {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

void candidate_sphere(const Eigen::AlignedBox3d& bbox, double working_distance_m,
                      Eigen::Vector3d* centre, double* radius) {
  *centre = bbox.center();
  *radius = working_distance_m + 0.5 * bbox.diagonal().norm();
}

std::vector<Pose> candidate_views(const Eigen::AlignedBox3d& bbox, const CandidateSpec& spec) {
  Eigen::Vector3d centre;
  double radius = 0;
  candidate_sphere(bbox, spec.working_distance_m, &centre, &radius);
  return sphere_band_views(spec.num_views, spec.num_parallels, radius, centre, 0.0,
                           spec.area == CandidateArea::kFullSphere ? kPi : kPi / 2);
}

// Candidates on the sphere around B, the reachability filter and the exclusions, shared by every
// planner so that they choose among the same views.
static void prepare_candidates(const PlanInput& in, PlanResult& r) {
  auto t0 = std::chrono::steady_clock::now();
  r.candidates = candidate_views(in.bbox, in.candidates);
  const int n = static_cast<int>(r.candidates.size());
  r.status.assign(n, CandidateStatus::kScored);
  r.scores.assign(n, ViewScore{});
  r.candidates_s = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  if (in.reachable) {
    const std::vector<bool> ok = in.reachable(r.candidates);
    if (ok.size() != r.candidates.size()) throw std::logic_error("reachability returned a wrong number of answers");
    for (int i = 0; i < n; ++i) {
      if (!ok[i]) {
        r.status[i] = CandidateStatus::kUnreachable;
        ++r.num_unreachable;
      }
    }
  }
  r.reachability_s = seconds_since(t0);

  // Excluded views: compare viewing directions seen from the centre.
  std::vector<Eigen::Vector3d> excluded_dirs;
  auto exclude = [&](const std::vector<Pose>& views) {
    for (const auto& p : views) {
      const Eigen::Vector3d d = p.translation() - r.centre;
      if (d.norm() > 0) excluded_dirs.push_back(d.normalized());
    }
  };
  exclude(in.excluded);
  if (in.skip_revisits) exclude(in.views_done);
  const double cos_exclude = std::cos(in.exclude_angle_rad);
  for (int i = 0; i < n && !excluded_dirs.empty(); ++i) {
    if (r.status[i] != CandidateStatus::kScored) continue;
    const Eigen::Vector3d d = (r.candidates[i].translation() - r.centre).normalized();
    for (const auto& x : excluded_dirs) {
      if (d.dot(x) >= cos_exclude) {
        r.status[i] = CandidateStatus::kExcluded;
        ++r.num_excluded;
        break;
      }
    }
  }
}

// Checks B and fills the candidate sphere; false (with the reason) when B is empty.
static bool check_bbox(const PlanInput& in, PlanResult& r) {
  if (in.bbox.isEmpty() || !(in.bbox.diagonal().norm() > 0)) {
    r.reason = "the bounding box B is empty: no view has been mapped yet";
    return false;
  }
  candidate_sphere(in.bbox, in.candidates.working_distance_m, &r.centre, &r.radius_m);
  return true;
}

static std::string nothing_to_score(const PlanResult& r) {
  std::ostringstream os;
  os << "no candidate can be scored: " << r.num_unreachable << " of " << r.candidates.size() << " unreachable, "
     << r.num_excluded << " near excluded views";
  return os.str();
}

// Ranks the pool (candidate indices), best quality first, ties broken by index so the plan is
// deterministic; fills chosen and the alternatives.
static void rank_pool(const PlanInput& in, PlanResult& r, std::vector<int> pool) {
  std::stable_sort(pool.begin(), pool.end(), [&](int a, int b) { return r.scores[a].quality > r.scores[b].quality; });
  r.chosen = pool.front();
  for (std::size_t k = 1; k < pool.size() && static_cast<int>(r.alternatives.size()) < in.num_alternatives; ++k) {
    r.alternatives.push_back(pool[k]);
  }
}

// Per candidate, the angle in degrees (seen from the centre) to the nearest view taken; 180 with
// no view taken.
static std::vector<double> gap_to_views_deg(const PlanResult& r, const std::vector<Pose>& views_done) {
  std::vector<Eigen::Vector3d> taken;
  for (const auto& v : views_done) {
    const Eigen::Vector3d d = v.translation() - r.centre;
    if (d.norm() > 0) taken.push_back(d.normalized());
  }
  std::vector<double> gap(r.candidates.size(), 180.0);
  for (std::size_t i = 0; i < gap.size(); ++i) {
    const Eigen::Vector3d d = (r.candidates[i].translation() - r.centre).normalized();
    double nearest = kPi;
    for (const auto& t : taken) nearest = std::min(nearest, std::acos(std::clamp(d.dot(t), -1.0, 1.0)));
    gap[i] = nearest * 180.0 / kPi;
  }
  return gap;
}

// The planner has nothing left to aim at but views remain in the budget: the scorable candidate
// farthest (in angle, seen from the centre of B) from every view taken, filling the largest gap.
// `r` has its candidates prepared (prepare_candidates); any scores it holds are replaced.
static PlanResult plan_spread(const PlanInput& in, PlanResult r, const std::string& why) {
  r.chosen = -1;
  r.alternatives.clear();
  r.scores.assign(r.candidates.size(), ViewScore{});
  r.first_quality = in.first_quality;  // a gap-filling view has no quality of the planner's kind
  r.ranking = Ranking::kGapAngle;
  const std::vector<double> gap = gap_to_views_deg(r, in.views_done);
  std::vector<int> pool;
  for (int i = 0; i < static_cast<int>(r.candidates.size()); ++i) {
    if (r.status[i] != CandidateStatus::kScored) continue;
    r.scores[i].quality = gap[i];  // degrees to the nearest view taken
    pool.push_back(i);
  }
  r.num_scored = static_cast<int>(pool.size());
  if (pool.empty()) {
    r.outcome = PlanResult::Outcome::kStop;
    r.reason = why + "; " + nothing_to_score(r);
    return r;
  }
  rank_pool(in, r, std::move(pool));
  r.outcome = PlanResult::Outcome::kView;
  std::ostringstream os;
  os << why << ": the view farthest from every view taken (" << r.scores[r.chosen].quality << " deg from the nearest)";
  r.reason = os.str();
  return r;
}

// Nothing left to aim at (`why`): --when-done decides: fill the largest gap, or stop.
static PlanResult nothing_left(const PlanInput& in, PlanResult r, const std::string& why) {
  if (in.when_done == WhenDone::kSpread) return plan_spread(in, std::move(r), why);
  r.outcome = PlanResult::Outcome::kStop;
  r.reason = why;
  return r;
}

// --stop-fraction: true (and r a stop with the reason) when the best F is below stop_fraction
// times the first planned view's F.
static bool below_stop_fraction(const PlanInput& in, double best_f, PlanResult& r) {
  if (!(std::isfinite(in.first_quality) && in.stop_fraction > 0 && best_f < in.stop_fraction * in.first_quality)) {
    return false;
  }
  std::ostringstream os;
  os << "best view quality F = " << best_f << " px is below " << in.stop_fraction << " of the first planned view's F ("
     << in.first_quality << " px)";
  r.outcome = PlanResult::Outcome::kStop;
  r.reason = os.str();
  return true;
}

// `v` scaled to [0, 1] over the candidates of `pool` (0 where they are all equal).
static std::vector<double> scaled_over(const std::vector<double>& v, const std::vector<int>& pool) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int i : pool) {
    lo = std::min(lo, v[i]);
    hi = std::max(hi, v[i]);
  }
  std::vector<double> out(v.size(), 0.0);
  if (hi > lo) {
    for (int i : pool) out[i] = (v[i] - lo) / (hi - lo);
  }
  return out;
}

// The top `k` of `pool` by `v` (ties to the earlier candidate).
static std::vector<int> top_by(const std::vector<double>& v, std::vector<int> pool, int k) {
  std::stable_sort(pool.begin(), pool.end(), [&](int a, int b) { return v[a] > v[b]; });
  if (static_cast<int>(pool.size()) > k) pool.resize(static_cast<std::size_t>(k));
  return pool;
}

// Motion-aware with path checks (PlanInput::path): r ranked over `shortlist` with each candidate
// charged its direct move's time; the best's path asked for, the time a detour adds charged (one
// point per seconds_per_point), a candidate with no clear path made unreachable and taken off the
// shortlist, and ranked again, until the best's path is known (or kPathChecks asked; the shortlist
// may end empty).
static void charge_paths(const PlanInput& in, PlanResult& r, std::vector<int>& shortlist) {
  std::vector<uint8_t> asked(r.candidates.size(), 0);
  std::vector<std::string> routes(r.candidates.size());
  while (!shortlist.empty() && !asked[r.chosen] && r.path_checks < kPathChecks) {
    const int k = r.chosen;
    asked[k] = 1;
    const CandidatePath p = in.path(k);
    ++r.path_checks;
    routes[k] = p.route;
    if (!p.clear) {
      r.status[k] = CandidateStatus::kUnreachable;
      ++r.num_unreachable;
      --r.num_scored;
      r.scores[k].quality = 0;
      shortlist.erase(std::find(shortlist.begin(), shortlist.end(), k));
    } else if (p.time_s > r.move_time_s[k]) {
      r.scores[k].quality -= (p.time_s - r.move_time_s[k]) / in.combined.seconds_per_point;
      r.move_time_s[k] = p.time_s;
    }
    r.alternatives.clear();
    r.chosen = -1;
    if (shortlist.empty()) return;
    rank_pool(in, r, shortlist);
  }
  if (r.chosen >= 0 && asked[r.chosen]) r.route = routes[r.chosen];
}

// pbnbv's combined ranking (planner.hpp CombinedRanking) over `pool` (the scored candidates of the
// allowed sectors); r.scores hold F where a Frontier ellipsoid exists.
static PlanResult rank_combined(const PlanInput& in, PlanResult r, const std::vector<int>& pool) {
  const CombinedRanking& c = in.combined;
  if (c.shortlist < 1) throw std::invalid_argument("combined ranking: shortlist " + std::to_string(c.shortlist) + " must be >= 1");
  if (!(c.saturation_m > 0) || !(c.ray_cell_m > 0)) {
    throw std::invalid_argument("combined ranking: saturation_m and ray_cell_m must be positive");
  }
  const std::size_t n = r.candidates.size();
  const bool has_f = r.num_frontier_ellipsoids > 0;
  r.f_px.assign(n, 0.0);
  if (has_f) {
    for (int i : pool) r.f_px[i] = r.scores[i].quality;
  }
  r.gap_deg = gap_to_views_deg(r, in.views_done);
  std::vector<int> shortlist = top_by(r.gap_deg, pool, c.shortlist);
  if (has_f) {
    const std::vector<int> by_f = top_by(r.f_px, pool, c.shortlist);
    shortlist.insert(shortlist.end(), by_f.begin(), by_f.end());
    std::sort(shortlist.begin(), shortlist.end());
    shortlist.erase(std::unique(shortlist.begin(), shortlist.end()), shortlist.end());
  }
  std::vector<uint8_t> cast(n, 0);
  for (int i : shortlist) cast[i] = 1;
  const auto t0 = std::chrono::steady_clock::now();
  const int factor = std::max(1, static_cast<int>(std::lround(c.ray_cell_m / in.grid->resolution_m)));
  const VoxelGrid grid = coarsened(*in.grid, factor);
  UnobservedRayParams rp;
  rp.camera = in.camera;
  rp.range = in.depth_range;
  rp.saturation_voxels = c.saturation_m / grid.resolution_m;
  r.rays = unobserved_ray_scores(grid, r.candidates, cast, rp);
  r.scoring_s += seconds_since(t0);
  const double rays_max = *std::max_element(r.rays.begin(), r.rays.end());
  if (!has_f && !(rays_max > 0)) {
    std::ostringstream os;
    os << "no frontier ellipsoid remains and no shortlisted candidate's rays reach an unobserved voxel ("
       << shortlist.size() << " cast)";
    const int scored = r.num_scored;
    PlanResult done = nothing_left(in, std::move(r), os.str());
    done.num_scored = scored;
    return done;
  }
  const std::vector<double> f = scaled_over(r.f_px, shortlist), g = scaled_over(r.gap_deg, shortlist),
                            ray = scaled_over(r.rays, shortlist);
  for (int i : pool) r.scores[i].quality = 0;
  for (int i : shortlist) r.scores[i].quality = f[i] + g[i] + ray[i];
  if (!in.move_time_s.empty()) {
    if (in.move_time_s.size() != n) {
      throw std::invalid_argument("motion-aware ranking: " + std::to_string(in.move_time_s.size()) + " move times for " +
                                  std::to_string(n) + " candidates");
    }
    if (!(c.seconds_per_point > 0)) throw std::invalid_argument("motion-aware ranking: seconds_per_point must be positive");
    r.move_time_s = in.move_time_s;
    for (int i : shortlist) {
      if (!(in.move_time_s[i] >= 0)) {
        throw std::invalid_argument("motion-aware ranking: candidate " + std::to_string(i) + "'s move time is not a time");
      }
      r.scores[i].quality -= in.move_time_s[i] / c.seconds_per_point;
    }
  }
  r.ranking = Ranking::kCombined;
  rank_pool(in, r, shortlist);
  if (!r.move_time_s.empty() && in.path) {
    charge_paths(in, r, shortlist);
    if (shortlist.empty()) {
      return nothing_left(in, std::move(r), "no shortlisted candidate has a collision-free path from where the rig stands");
    }
  }
  const int k = r.chosen;
  std::ostringstream os;
  os << "combined " << r.scores[k].quality << " of 3 (F " << r.f_px[k] << " px" << (has_f ? "" : ": no frontier ellipsoid")
     << ", gap " << r.gap_deg[k] << " deg, rays " << r.rays[k];
  if (!r.move_time_s.empty()) {
    os << ", less " << r.move_time_s[k] << " s to reach" << (r.route.empty() ? "" : " (" + r.route + ")") << " / "
       << c.seconds_per_point << " s per point";
  }
  os << ") over a shortlist of " << shortlist.size() << " of " << r.num_scored << " scored";
  r.reason = os.str();
  r.outcome = PlanResult::Outcome::kView;
  return r;
}

PlanResult plan_pbnbv(const PlanInput& in) {
  PlanResult r;
  r.ranking = Ranking::kF;
  for (const auto& e : in.ellipsoids) {
    (e.cls == EllipsoidClass::kFrontier ? r.num_frontier_ellipsoids : r.num_occupied_ellipsoids)++;
  }
  if (in.beta < 1) throw std::invalid_argument("beta (partition sectors) must be >= 1, got " + std::to_string(in.beta));
  if (!check_bbox(in, r)) return r;
  if (r.num_frontier_ellipsoids == 0 && !in.grid) {
    if (in.when_done == WhenDone::kSpread) prepare_candidates(in, r);
    return nothing_left(in, std::move(r), "no frontier ellipsoid remains");
  }

  prepare_candidates(in, r);
  const int n = static_cast<int>(r.candidates.size());

  auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) {
    if (r.status[i] != CandidateStatus::kScored) continue;
    if (r.num_frontier_ellipsoids > 0) r.scores[i] = score_view(in.ellipsoids, in.camera, r.candidates[i]);
    ++r.num_scored;
  }
  r.scoring_s = seconds_since(t0);
  if (r.num_scored == 0) {
    r.reason = nothing_to_score(r);
    return r;
  }

  // Global partitioning.
  std::vector<int> sector(n, 0);
  if (in.beta > 1) {
    std::vector<bool> scanned(in.beta, false);
    if (in.sectors_centred_on_first_view && !in.views_done.empty()) {
      const Eigen::Vector3d d = in.views_done.front().translation() - r.centre;
      if (d.head<2>().norm() > 1e-9) r.sector_start_rad = std::atan2(d.y(), d.x()) - kPi / in.beta;
    }
    for (const auto& v : in.views_done) scanned[sector_of(v.translation(), r.centre, in.beta, r.sector_start_rad)] = true;
    r.allowed_sectors = allowed_sectors(scanned);
    for (int i = 0; i < n; ++i) sector[i] = sector_of(r.candidates[i].translation(), r.centre, in.beta, r.sector_start_rad);
  } else {
    r.allowed_sectors = {0};
  }
  std::vector<bool> allowed(std::max(in.beta, 1), false);
  for (int s : r.allowed_sectors) allowed[s] = true;
  std::vector<int> pool;
  for (int i = 0; i < n; ++i) {
    if (r.status[i] == CandidateStatus::kScored && allowed[sector[i]]) pool.push_back(i);
  }
  if (pool.empty()) {
    r.partition_fallback = true;
    for (int i = 0; i < n; ++i) if (r.status[i] == CandidateStatus::kScored) pool.push_back(i);
  } else {
    for (int i = 0; i < n; ++i) {
      if (r.status[i] == CandidateStatus::kScored && !allowed[sector[i]]) r.status[i] = CandidateStatus::kOutsidePartition;
    }
  }
  if (in.grid) {
    // The first F and the stop fraction stay F's (the best F over the pool).
    double best_f = -std::numeric_limits<double>::infinity();
    for (int i : pool) best_f = std::max(best_f, r.scores[i].quality);
    if (r.num_frontier_ellipsoids > 0) r.first_quality = std::isfinite(in.first_quality) ? in.first_quality : best_f;
    else r.first_quality = in.first_quality;
    if (r.num_frontier_ellipsoids > 0 && below_stop_fraction(in, best_f, r)) return r;
    PlanResult out = rank_combined(in, std::move(r), pool);
    if (out.chosen >= 0) out.partition = in.beta > 1 ? sector[out.chosen] : -1;
    return out;
  }
  rank_pool(in, r, std::move(pool));
  r.partition = in.beta > 1 ? sector[r.chosen] : -1;

  const double best = r.scores[r.chosen].quality;
  r.first_quality = std::isfinite(in.first_quality) ? in.first_quality : best;
  if (below_stop_fraction(in, best, r)) return r;
  r.outcome = PlanResult::Outcome::kView;
  std::ostringstream os;
  os << "F = " << best << " px (frontier " << r.scores[r.chosen].frontier_sum << ", occupied "
     << r.scores[r.chosen].occupied_sum << ") of " << r.num_scored << " scored";
  r.reason = os.str();
  return r;
}

PlanResult plan_raycast(const PlanInput& in, const VoxelGrid& grid, const RaycastParams& params) {
  PlanResult r;
  r.ranking = Ranking::kUnobservedVoxels;
  if (!check_bbox(in, r)) return r;
  prepare_candidates(in, r);
  const int n = static_cast<int>(r.candidates.size());
  std::vector<uint8_t> active(n, 0);
  for (int i = 0; i < n; ++i) active[i] = r.status[i] == CandidateStatus::kScored;
  const auto t0 = std::chrono::steady_clock::now();
  // In chunks of candidates, reporting progress between them: at 0.005 m one plan takes seconds.
  std::vector<RaycastGain> gains(static_cast<std::size_t>(n));
  constexpr int kChunk = 50;
  for (int first = 0; first < n;) {
    std::vector<uint8_t> chunk(static_cast<std::size_t>(n), 0);
    int taken = 0, i = first;
    for (; i < n && taken < kChunk; ++i) {
      if (active[i]) {
        chunk[i] = 1;
        ++taken;
      }
    }
    const std::vector<RaycastGain> g = raycast_gains(grid, r.candidates, chunk, params);
    for (int j = first; j < i; ++j) {
      if (chunk[j]) gains[j] = g[j];
    }
    first = i;
    if (in.progress) in.progress();
  }
  int64_t rays = 0;
  for (int i = 0; i < n; ++i) {
    if (!active[i]) continue;
    r.scores[i].quality = static_cast<double>(gains[i].unknown);
    r.scores[i].frontier_sum = static_cast<double>(gains[i].unknown);
    r.scores[i].visible = gains[i].rays;
    rays += gains[i].rays;
    ++r.num_scored;
  }
  r.scoring_s = seconds_since(t0);
  if (r.num_scored == 0) {
    r.reason = nothing_to_score(r);
    return r;
  }
  std::vector<int> pool;
  for (int i = 0; i < n; ++i) {
    if (active[i]) pool.push_back(i);
  }
  rank_pool(in, r, std::move(pool));
  const double best = r.scores[r.chosen].quality;
  r.first_quality = std::isfinite(in.first_quality) ? in.first_quality : best;
  std::ostringstream os;
  if (best <= 0) {
    os << "no candidate sees an unobserved voxel (" << r.num_scored << " scored, " << rays << " rays)";
    return nothing_left(in, std::move(r), os.str());
  } else if (std::isfinite(in.first_quality) && in.stop_fraction > 0 && best < in.stop_fraction * in.first_quality) {
    r.outcome = PlanResult::Outcome::kStop;
    os << "best gain " << best << " voxels is below " << in.stop_fraction << " of the first planned view's ("
       << in.first_quality << ")";
  } else {
    r.outcome = PlanResult::Outcome::kView;
    os << "gain " << best << " unobserved voxels of " << r.num_scored << " scored (" << rays << " rays)";
  }
  r.reason = os.str();
  return r;
}

PlanResult plan_random(const PlanInput& in, uint64_t seed) {
  PlanResult r;
  r.ranking = Ranking::kRandom;
  if (!check_bbox(in, r)) return r;
  prepare_candidates(in, r);
  std::vector<int> pool;
  for (int i = 0; i < static_cast<int>(r.candidates.size()); ++i) {
    if (r.status[i] == CandidateStatus::kScored) pool.push_back(i);
  }
  r.num_scored = static_cast<int>(pool.size());
  if (pool.empty()) {
    r.reason = nothing_to_score(r);
    return r;
  }
  // A partial Fisher-Yates shuffle with our own draws (std::shuffle's sequence is not specified
  // across standard libraries): the choice, then the alternatives.
  std::mt19937_64 rng(seed);
  const int picks = std::min<int>(static_cast<int>(pool.size()), in.num_alternatives + 1);
  for (int k = 0; k < picks; ++k) {
    const uint64_t left = pool.size() - k;
    std::swap(pool[k], pool[k + static_cast<int>(rng() % left)]);
  }
  r.chosen = pool[0];
  r.alternatives.assign(pool.begin() + 1, pool.begin() + picks);
  r.outcome = PlanResult::Outcome::kView;
  r.reason = "random choice among " + std::to_string(r.num_scored) + " candidates (seed " + std::to_string(seed) + ")";
  return r;
}

PlanResult plan_oracle(const PlanInput& in, const TriangleMesh& truth, const SurfaceSamples& samples,
                       const VisibilityParams& visibility) {
  PlanResult r;
  r.ranking = Ranking::kTrueSamples;
  if (!check_bbox(in, r)) return r;
  prepare_candidates(in, r);
  const int n = static_cast<int>(r.candidates.size());
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<uint8_t> seen = visible_from_any(truth, samples.points, samples.normals, in.views_done, visibility);
  std::vector<int> pool;
  std::vector<Pose> active;
  for (int i = 0; i < n; ++i) {
    if (r.status[i] != CandidateStatus::kScored) continue;
    pool.push_back(i);
    active.push_back(r.candidates[i]);
  }
  // In chunks, reporting progress between them: a large mesh takes seconds.
  std::vector<int> gains;
  constexpr std::size_t kChunk = 50;
  for (std::size_t b = 0; b < active.size(); b += kChunk) {
    const std::vector<Pose> chunk(active.begin() + b, active.begin() + std::min(active.size(), b + kChunk));
    const std::vector<int> g = count_newly_visible(truth, samples.points, samples.normals, chunk, seen, visibility);
    gains.insert(gains.end(), g.begin(), g.end());
    if (in.progress) in.progress();
  }
  for (std::size_t k = 0; k < pool.size(); ++k) {
    r.scores[pool[k]].quality = gains[k];
    r.scores[pool[k]].frontier_sum = gains[k];
  }
  r.num_scored = static_cast<int>(pool.size());
  r.scoring_s = seconds_since(t0);
  if (pool.empty()) {
    r.reason = nothing_to_score(r);
    return r;
  }
  rank_pool(in, r, std::move(pool));
  const double best = r.scores[r.chosen].quality;
  r.first_quality = std::isfinite(in.first_quality) ? in.first_quality : best;
  const std::size_t seen_count = static_cast<std::size_t>(std::count(seen.begin(), seen.end(), uint8_t{1}));
  std::ostringstream os;
  os << seen_count << " of " << samples.points.size() << " true surface samples seen by the views taken";
  if (best <= 0) return nothing_left(in, std::move(r), "no candidate sees a new true surface sample (" + os.str() + ")");
  r.outcome = PlanResult::Outcome::kView;
  r.reason = "sees " + std::to_string(static_cast<int>(best)) + " new true surface samples (" + os.str() + ", " +
             std::to_string(r.num_scored) + " candidates scored)";
  return r;
}

}  // namespace pbnbv
