// One PB-NBV planning step (planner.hpp): the candidate sphere, the choice, partitions,
// reachability, exclusion and termination, on scenes whose answer is plain geometry.
#include "core/planning/planner.hpp"
#include "core/base/units.hpp"
#include "sphere_ellipsoid.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace pbnbv {
namespace {

using testing::sphere_ellipsoid;

// A 0.3 m object (occupied ball at the origin) with unexplored structure (a frontier ball) on
// the side at azimuth `azimuth_deg`.
PlanInput scene(double azimuth_deg, int beta) {
  PlanInput in;
  in.bbox = Eigen::AlignedBox3d(Eigen::Vector3d(-0.15, -0.15, 0.0), Eigen::Vector3d(0.15, 0.15, 0.3));
  const double a = azimuth_deg * kPi / 180.0;
  in.ellipsoids = {sphere_ellipsoid(Eigen::Vector3d(0, 0, 0.15), 0.1, EllipsoidClass::kOccupied),
                   sphere_ellipsoid(Eigen::Vector3d(0.18 * std::cos(a), 0.18 * std::sin(a), 0.15), 0.08, EllipsoidClass::kFrontier)};
  in.beta = beta;
  in.candidates.area = CandidateArea::kHemisphere;
  return in;
}

double azimuth_deg(const Pose& p, const Eigen::Vector3d& centre) {
  const Eigen::Vector3d d = p.translation() - centre;
  double a = std::atan2(d.y(), d.x()) * 180.0 / kPi;
  return a < 0 ? a + 360.0 : a;
}

TEST(Planner, CandidateSphereFollowsTheBoundingBox) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.1, -0.2, 0.0), Eigen::Vector3d(0.3, 0.2, 0.4));
  Eigen::Vector3d c;
  double r = 0;
  candidate_sphere(box, 0.6, &c, &r);
  EXPECT_NEAR((c - Eigen::Vector3d(0.1, 0.0, 0.2)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r, 0.6 + 0.5 * std::sqrt(0.4 * 0.4 * 3), 1e-12);  // d_c + half the diagonal
  CandidateSpec spec;
  const std::vector<Pose> v = candidate_views(box, spec);
  ASSERT_EQ(v.size(), 800u);
  for (const auto& p : v) {
    EXPECT_NEAR((p.translation() - c).norm(), r, 1e-9);
    EXPECT_GE(p.translation().z(), c.z() - 1e-9) << "hemisphere above the centre of B";
    // Looks at the centre: the optical axis (+z of the camera) points from the eye to it.
    EXPECT_NEAR(p.linear().col(2).dot((c - p.translation()).normalized()), 1.0, 1e-9);
  }
}

TEST(Planner, ChoosesTheSideWithTheFrontierAndRanksAlternatives) {
  PlanInput in = scene(90.0, 1);
  const PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_EQ(r.num_scored, 800);
  EXPECT_EQ(r.num_frontier_ellipsoids, 1);
  EXPECT_EQ(r.num_occupied_ellipsoids, 1);
  // The frontier ball sits at azimuth 90 deg, in front of the occupied ball seen from +y.
  EXPECT_NEAR(azimuth_deg(r.candidates[r.chosen], r.centre), 90.0, 30.0);
  EXPECT_GT(r.scores[r.chosen].quality, 0.0);
  ASSERT_EQ(r.alternatives.size(), 5u);
  double last = r.scores[r.chosen].quality;
  for (int a : r.alternatives) {
    EXPECT_LE(r.scores[a].quality, last);
    last = r.scores[a].quality;
  }
  // The first planned view defines F_1.
  EXPECT_DOUBLE_EQ(r.first_quality, r.scores[r.chosen].quality);
}

TEST(Planner, PartitionsOnlyAllowSectorsAdjacentToTheScannedOne) {
  // One view taken at azimuth 45 deg (sector 0 of 4); the frontier is on the far side
  // (azimuth 225 deg, sector 2). With beta = 4 the choice must come from sector 1 or 3;
  // without partitions it goes straight to the far side.
  PlanInput in = scene(225.0, 4);
  in.views_done = {look_at_z_up(Eigen::Vector3d(0.6, 0.6, 0.5), Eigen::Vector3d(0, 0, 0.15))};
  const PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_EQ(r.allowed_sectors, (std::vector<int>{1, 3}));
  EXPECT_TRUE(r.partition == 1 || r.partition == 3) << r.partition;
  EXPECT_FALSE(r.partition_fallback);
  int outside = 0;
  for (const auto s : r.status) outside += s == CandidateStatus::kOutsidePartition;
  EXPECT_NEAR(outside, 400, 20) << "about half of a hemisphere's candidates lie in sectors 0 and 2";

  in.beta = 1;
  const PlanResult free = plan_pbnbv(in);
  ASSERT_EQ(free.outcome, PlanResult::Outcome::kView);
  EXPECT_EQ(free.partition, -1);
  EXPECT_NEAR(azimuth_deg(free.candidates[free.chosen], free.centre), 225.0, 30.0);
}

TEST(Planner, UnreachableCandidatesAreDroppedAndCounted) {
  PlanInput in = scene(0.0, 1);
  const Eigen::Vector3d centre = in.bbox.center();
  // A rig that cannot reach anything on the +x side.
  in.reachable = [&](const std::vector<Pose>& c) {
    std::vector<bool> ok;
    for (const auto& p : c) ok.push_back(p.translation().x() < centre.x());
    return ok;
  };
  const PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_EQ(r.num_unreachable + r.num_scored, 800);
  EXPECT_NEAR(r.num_unreachable, 400, 30);
  EXPECT_LT(r.candidates[r.chosen].translation().x(), centre.x());
  for (int i = 0; i < 800; ++i) {
    EXPECT_EQ(r.status[i] == CandidateStatus::kUnreachable, r.candidates[i].translation().x() >= centre.x());
  }

  in.reachable = [](const std::vector<Pose>& c) { return std::vector<bool>(c.size(), false); };
  const PlanResult none = plan_pbnbv(in);
  EXPECT_EQ(none.outcome, PlanResult::Outcome::kFailed);
  EXPECT_NE(none.reason.find("800 of 800 unreachable"), std::string::npos) << none.reason;
}

TEST(Planner, ExcludedViewsAreSkipped) {
  PlanInput in = scene(90.0, 1);
  const PlanResult first = plan_pbnbv(in);
  ASSERT_EQ(first.outcome, PlanResult::Outcome::kView);
  in.excluded = {first.candidates[first.chosen]};
  const PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView);
  EXPECT_GT(r.num_excluded, 0);
  const Eigen::Vector3d a = (first.candidates[first.chosen].translation() - r.centre).normalized();
  const Eigen::Vector3d b = (r.candidates[r.chosen].translation() - r.centre).normalized();
  EXPECT_GT(std::acos(std::clamp(a.dot(b), -1.0, 1.0)), 10.0 * kPi / 180.0);
}

TEST(Planner, StopsWhenNoFrontierRemainsOrTheBestViewIsWorthTooLittle) {
  PlanInput in = scene(0.0, 4);
  in.ellipsoids.pop_back();  // only the occupied ball
  in.when_done = WhenDone::kStop;
  const PlanResult done = plan_pbnbv(in);
  EXPECT_EQ(done.outcome, PlanResult::Outcome::kStop);
  EXPECT_EQ(done.reason, "no frontier ellipsoid remains");

  PlanInput small = scene(0.0, 1);
  const PlanResult first = plan_pbnbv(small);
  ASSERT_EQ(first.outcome, PlanResult::Outcome::kView);
  const double best = first.scores[first.chosen].quality;
  small.first_quality = best / 0.04;  // best F = 4 % of the first view's
  small.stop_fraction = 0.05;
  const PlanResult stop = plan_pbnbv(small);
  EXPECT_EQ(stop.outcome, PlanResult::Outcome::kStop);
  EXPECT_NE(stop.reason.find("below 0.05"), std::string::npos) << stop.reason;
  small.stop_fraction = 0.03;  // 4 % is above 3 %: go on
  EXPECT_EQ(plan_pbnbv(small).outcome, PlanResult::Outcome::kView);
  small.stop_fraction = 0.0;   // never
  small.first_quality = 1e12;
  EXPECT_EQ(plan_pbnbv(small).outcome, PlanResult::Outcome::kView);
}

TEST(Planner, WithABudgetLeftItFillsTheLargestGapInsteadOfStopping) {
  PlanInput in = scene(0.0, 4);
  in.ellipsoids.pop_back();  // nothing left to aim at
  in.when_done = WhenDone::kSpread;
  Eigen::Vector3d centre;
  double radius = 0;
  candidate_sphere(in.bbox, in.candidates.working_distance_m, &centre, &radius);
  // One view taken at azimuth 0, 45 deg above the centre: the farthest hemisphere candidate is
  // across the object at the equator, 135 deg away (the lowest parallel is 1.9 deg above it).
  in.views_done = {look_at_z_up(centre + radius * Eigen::Vector3d(std::sqrt(0.5), 0, std::sqrt(0.5)), centre)};
  const PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_NE(r.reason.find("no frontier ellipsoid remains"), std::string::npos) << r.reason;
  EXPECT_NEAR(azimuth_deg(r.candidates[r.chosen], centre), 180.0, 8.0);
  EXPECT_NEAR(r.scores[r.chosen].quality, 135.0 - 1.9, 2.0);  // degrees to the view taken
  EXPECT_EQ(r.ranking, Ranking::kGapAngle);
  for (int a : r.alternatives) EXPECT_LE(r.scores[a].quality, r.scores[r.chosen].quality);
  EXPECT_TRUE(std::isnan(r.first_quality));
}

TEST(Planner, EmptyBoundingBoxFails) {
  PlanInput in = scene(0.0, 4);
  in.bbox = Eigen::AlignedBox3d();
  const PlanResult r = plan_pbnbv(in);
  EXPECT_EQ(r.outcome, PlanResult::Outcome::kFailed);
  EXPECT_NE(r.reason.find("bounding box B is empty"), std::string::npos);
}

}  // namespace
// Ours (planner pbnbv, docs/method.md departure 4): the combined ranking. B as a grid of 0.03 m
// voxels in state `s`.
VoxelGrid grid_of(const Eigen::AlignedBox3d& box, VoxelState s) {
  VoxelGrid g;
  g.resolution_m = 0.03;
  g.origin_m = box.min();
  g.dims = (box.sizes() / g.resolution_m).array().round().cast<int>();
  g.cells.assign(static_cast<std::size_t>(g.dims.prod()), s);
  return g;
}

std::vector<double> scaled(const std::vector<double>& v, const std::vector<int>& over) {
  double lo = 1e300, hi = -1e300;
  for (int i : over) lo = std::min(lo, v[i]), hi = std::max(hi, v[i]);
  std::vector<double> out(v.size(), 0.0);
  for (int i : over) out[i] = hi > lo ? (v[i] - lo) / (hi - lo) : 0.0;
  return out;
}

std::vector<int> top(const std::vector<double>& v, const std::vector<int>& over, int k) {
  std::vector<int> o = over;
  std::stable_sort(o.begin(), o.end(), [&](int a, int b) { return v[a] > v[b]; });
  o.resize(std::min<std::size_t>(o.size(), k));
  return o;
}

// One view taken at +x; the frontier ball at +x; B all Unknown, so every candidate's rays reach
// unobserved space. The shortlist is the top 10 by F and the top 10 by the gap; each of them is
// scored F + gap + rays, each scaled to [0, 1] over the shortlist; the best of them is chosen.
TEST(Planner, CombinedRankingSumsThreeScaledTermsOverAShortlist) {
  PlanInput in = scene(0.0, 1);
  Eigen::Vector3d centre;
  double radius = 0;
  candidate_sphere(in.bbox, in.candidates.working_distance_m, &centre, &radius);
  const Eigen::Vector3d taken = centre + radius * Eigen::Vector3d::UnitX();
  in.views_done = {look_at_z_up(taken, centre)};
  const VoxelGrid grid = grid_of(in.bbox, VoxelState::kUnknown);
  in.grid = &grid;
  in.combined.shortlist = 10;
  const PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_EQ(r.ranking, Ranking::kCombined);
  std::vector<int> scored, shortlist;
  for (int i = 0; i < static_cast<int>(r.candidates.size()); ++i) {
    if (r.status[i] != CandidateStatus::kScored) continue;
    scored.push_back(i);
    // The gap by hand: the angle at the centre between the candidate and the view taken.
    const double gap = std::acos((r.candidates[i].translation() - centre).normalized().dot(Eigen::Vector3d::UnitX()));
    EXPECT_NEAR(r.gap_deg[i], gap * 180.0 / kPi, 1e-9);
    if (r.rays[i] > 0) shortlist.push_back(i);
  }
  EXPECT_EQ(r.num_excluded, static_cast<int>(r.candidates.size() - scored.size()));  // near the view taken
  ASSERT_GE(shortlist.size(), 10u);
  ASSERT_LE(shortlist.size(), 20u);
  for (const auto& by : {r.f_px, r.gap_deg}) {
    for (int i : top(by, scored, 10)) EXPECT_GT(r.rays[i], 0.0) << "candidate " << i << " is in the top 10";
  }
  const auto f = scaled(r.f_px, shortlist), g = scaled(r.gap_deg, shortlist), ray = scaled(r.rays, shortlist);
  int best = shortlist.front();
  for (int i : shortlist) {
    EXPECT_NEAR(r.scores[i].quality, f[i] + g[i] + ray[i], 1e-12);
    if (r.scores[i].quality > r.scores[best].quality) best = i;
  }
  EXPECT_EQ(r.chosen, best);
  EXPECT_LE(r.scores[r.chosen].quality, 3.0);
  for (std::size_t k = 0; k < r.alternatives.size(); ++k) {
    EXPECT_LE(r.scores[r.alternatives[k]].quality, k ? r.scores[r.alternatives[k - 1]].quality : r.scores[r.chosen].quality);
  }
  EXPECT_NE(r.reason.find("shortlist"), std::string::npos) << r.reason;

  // The paper's planner (no grid) ranks by F alone, as ever.
  in.grid = nullptr;
  EXPECT_EQ(plan_pbnbv(in).ranking, Ranking::kF);
}

// The motion-aware tests' scene: one view taken (on +x), the map all unknown (`grid`, which the
// input points to), a shortlist of 10 per term.
PlanInput one_view_taken(VoxelGrid& grid) {
  PlanInput in = scene(0.0, 1);
  Eigen::Vector3d centre;
  double radius = 0;
  candidate_sphere(in.bbox, in.candidates.working_distance_m, &centre, &radius);
  in.views_done = {look_at_z_up(centre + radius * Eigen::Vector3d::UnitX(), centre)};
  grid = grid_of(in.bbox, VoxelState::kUnknown);
  in.grid = &grid;
  in.combined.shortlist = 10;
  return in;
}

// Motion-aware: each candidate's score is its combined score less its move time over
// seconds_per_point. The plain ranking's best (a) and runner-up (b): with equal times a is taken;
// once a is slower than b by more than its lead times seconds_per_point, b (of two views equal
// but for the time, the quicker).
TEST(Planner, MotionAwareRankingTakesTheQuickerViewWhenItsTimeIsWorthMoreThanTheOthersLead) {
  VoxelGrid grid;
  PlanInput in = one_view_taken(grid);
  const PlanResult plain = plan_pbnbv(in);
  ASSERT_EQ(plain.outcome, PlanResult::Outcome::kView) << plain.reason;
  ASSERT_FALSE(plain.alternatives.empty());
  EXPECT_TRUE(plain.move_time_s.empty());
  const int a = plain.chosen, b = plain.alternatives.front();
  const double lead = plain.scores[a].quality - plain.scores[b].quality;
  ASSERT_GT(lead, 0.0);

  // Every other candidate 100 s away (out of the running); b 1 s.
  in.combined.seconds_per_point = 4.0;
  in.move_time_s.assign(plain.candidates.size(), 100.0);
  in.move_time_s[b] = 1.0;
  in.move_time_s[a] = 1.0;  // equal times: the better
  PlanResult aware = plan_pbnbv(in);
  ASSERT_EQ(aware.outcome, PlanResult::Outcome::kView) << aware.reason;
  EXPECT_EQ(aware.chosen, a);
  EXPECT_NEAR(aware.scores[a].quality, plain.scores[a].quality - 0.25, 1e-12);
  in.move_time_s[a] = 1.0 + 4.0 * lead - 0.01;  // slower, but its lead is worth more
  EXPECT_EQ(plan_pbnbv(in).chosen, a);
  in.move_time_s[a] = 1.0 + 4.0 * lead + 0.01;  // its lead is worth less than the time
  aware = plan_pbnbv(in);
  EXPECT_EQ(aware.chosen, b);
  EXPECT_NEAR(aware.scores[b].quality, plain.scores[b].quality - 0.25, 1e-12);
  EXPECT_NE(aware.reason.find("1 s to reach"), std::string::npos) << aware.reason;
  // A time for each candidate or none.
  in.move_time_s.pop_back();
  EXPECT_THROW(plan_pbnbv(in), std::invalid_argument);
}

// Motion-aware with path checks: the best view's direct move collides and its detour is slow: the
// ranking charges the detour's time and takes the runner-up (a clear direct move), asking for the
// paths of those two only; a best with no clear path is unreachable; the detour's route is named.
TEST(Planner, MotionAwareRankingChargesTheDetourOfAViewWhoseDirectMoveCollides) {
  VoxelGrid grid;
  PlanInput in = one_view_taken(grid);
  in.combined.seconds_per_point = 4.0;
  const PlanResult plain = plan_pbnbv(in);
  ASSERT_EQ(plain.outcome, PlanResult::Outcome::kView) << plain.reason;
  const int a = plain.chosen, b = plain.alternatives.front();
  const double lead = plain.scores[a].quality - plain.scores[b].quality;
  ASSERT_GT(lead, 0.0);
  in.move_time_s.assign(plain.candidates.size(), 100.0);
  in.move_time_s[a] = in.move_time_s[b] = 1.0;  // their direct moves: equally quick
  std::vector<int> asked;
  // a's direct move collides: its detour takes 1 s more than its lead is worth.
  const double detour_s = 1.0 + 4.0 * lead + 1.0;
  in.path = [&](int i) {
    asked.push_back(i);
    if (i == a) return CandidatePath{true, detour_s, "via home"};
    return CandidatePath{true, in.move_time_s[i], "direct"};
  };
  PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_EQ(r.chosen, b);
  EXPECT_EQ(asked, (std::vector<int>{a, b}));
  EXPECT_EQ(r.path_checks, 2);
  EXPECT_EQ(r.move_time_s[a], detour_s);
  EXPECT_NEAR(r.scores[a].quality, plain.scores[a].quality - detour_s / 4.0, 1e-12);
  EXPECT_NEAR(r.scores[b].quality, plain.scores[b].quality - 0.25, 1e-12);
  EXPECT_EQ(r.route, "direct");
  // A shorter detour (its lead still worth more): a, named with its route; one path asked, then a again.
  asked.clear();
  in.path = [&](int i) {
    asked.push_back(i);
    return CandidatePath{true, i == a ? 1.0 + 4.0 * lead - 0.01 : in.move_time_s[i], i == a ? "via home" : "direct"};
  };
  r = plan_pbnbv(in);
  EXPECT_EQ(r.chosen, a);
  EXPECT_EQ(asked, (std::vector<int>{a}));
  EXPECT_EQ(r.route, "via home");
  EXPECT_NE(r.reason.find("to reach (via home)"), std::string::npos) << r.reason;
  // No clear path to a: unreachable, b taken.
  in.path = [&](int i) {
    return i == a ? CandidatePath{false, 0, "no collision-free path"} : CandidatePath{true, in.move_time_s[i], "direct"};
  };
  r = plan_pbnbv(in);
  EXPECT_EQ(r.chosen, b);
  EXPECT_EQ(r.status[a], CandidateStatus::kUnreachable);
  EXPECT_EQ(r.num_unreachable, plain.num_unreachable + 1);
  // Every path blocked: at most kPathChecks asked, then nothing left to aim at reachable.
  asked.clear();
  in.path = [&](int i) {
    asked.push_back(i);
    return CandidatePath{false, 0, "blocked"};
  };
  in.when_done = WhenDone::kStop;
  r = plan_pbnbv(in);
  EXPECT_EQ(static_cast<int>(asked.size()), kPathChecks);
  EXPECT_EQ(r.path_checks, kPathChecks);
}

// No Frontier ellipsoid: while rays still reach unobserved space the combined ranking goes on
// (gap and rays); once they reach none there is nothing left to aim at: the largest gap, or a stop.
TEST(Planner, CombinedRankingGoesOnWithoutAFrontierUntilNoRayReachesUnobservedSpace) {
  PlanInput in = scene(0.0, 1);
  in.ellipsoids.pop_back();
  in.views_done = {look_at_z_up(Eigen::Vector3d(1.0, 0, 0.15), Eigen::Vector3d(0, 0, 0.15))};
  in.when_done = WhenDone::kSpread;
  VoxelGrid grid = grid_of(in.bbox, VoxelState::kUnknown);
  in.grid = &grid;
  const PlanResult on = plan_pbnbv(in);
  ASSERT_EQ(on.outcome, PlanResult::Outcome::kView) << on.reason;
  EXPECT_EQ(on.ranking, Ranking::kCombined);
  EXPECT_NE(on.reason.find("no frontier ellipsoid"), std::string::npos) << on.reason;

  grid = grid_of(in.bbox, VoxelState::kEmpty);
  const PlanResult spread = plan_pbnbv(in);
  ASSERT_EQ(spread.outcome, PlanResult::Outcome::kView) << spread.reason;
  EXPECT_EQ(spread.ranking, Ranking::kGapAngle);
  EXPECT_NE(spread.reason.find("no shortlisted candidate's rays reach an unobserved voxel"), std::string::npos) << spread.reason;
  EXPECT_NEAR(azimuth_deg(spread.candidates[spread.chosen], spread.centre), 180.0, 15.0);  // across from +x

  in.when_done = WhenDone::kStop;
  EXPECT_EQ(plan_pbnbv(in).outcome, PlanResult::Outcome::kStop);
}

// The shortlist against full ray casting, on a scene counted by hand: B (0.3 m, ten 0.03 m voxels a
// side) is all Occupied except a slot two voxels wide down its middle from the top, six deep,
// never seen into. Four views were taken round the equator; no frontier ellipsoid is left. Only a
// candidate whose eye is above B's top (z > 0.3 m: polar angle below 80 deg on the sphere of
// radius 0.6 + 0.26 m about (0, 0, 0.15)) can see into the slot, and to its bottom only within
// atan(0.06 / 0.18) = 18 deg of the vertical: the ray term cast for every candidate is 0 below
// that height and largest near the top. The shortlist (the top 40 by the gap, all near the top)
// holds it, and the combined ranking chooses a view down the slot that full casting ranks at
// its best.
TEST(Planner, CombinedRankingFindsTheViewDownADeepSlotThatFullRayCastingFinds) {
  PlanInput in = scene(0.0, 1);
  in.ellipsoids.pop_back();  // no frontier ellipsoid
  Eigen::Vector3d centre;
  double radius = 0;
  candidate_sphere(in.bbox, in.candidates.working_distance_m, &centre, &radius);
  for (const Eigen::Vector3d& d : std::vector<Eigen::Vector3d>{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}}) {
    in.views_done.push_back(look_at_z_up(centre + radius * d, centre));
  }
  VoxelGrid grid = grid_of(in.bbox, VoxelState::kOccupied);
  ASSERT_EQ(grid.dims, Eigen::Vector3i(10, 10, 10));
  for (int z = 4; z < 10; ++z)
    for (int y = 4; y < 6; ++y)
      for (int x = 4; x < 6; ++x) grid.cells[x + 10 * (y + 10 * z)] = VoxelState::kUnknown;
  in.grid = &grid;
  const PlanResult r = plan_pbnbv(in);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  ASSERT_EQ(r.ranking, Ranking::kCombined);

  // Full ray casting: the same ray term for every scored candidate.
  std::vector<uint8_t> all(r.candidates.size(), 0);
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = r.status[i] == CandidateStatus::kScored;
  UnobservedRayParams rp;
  rp.camera = in.camera;
  rp.range = in.depth_range;
  rp.saturation_voxels = in.combined.saturation_m / grid.resolution_m;
  const std::vector<double> full = unobserved_ray_scores(grid, r.candidates, all, rp);
  auto polar_deg = [&](int i) {
    return std::acos((r.candidates[i].translation() - centre).normalized().z()) * 180.0 / kPi;
  };
  int best = -1;
  for (int i = 0; i < static_cast<int>(full.size()); ++i) {
    if (!all[i]) continue;
    if (polar_deg(i) > 81.0) EXPECT_EQ(full[i], 0.0) << "candidate " << i << " below B's top sees into the slot";
    if (best < 0 || full[i] > full[best]) best = i;
  }
  ASSERT_GE(best, 0);
  EXPECT_GT(full[best], 0.0);
  EXPECT_LT(polar_deg(best), 18.5) << "full casting's best looks down the slot";
  EXPECT_EQ(r.rays[best], full[best]) << "full casting's best is in the shortlist";
  EXPECT_EQ(r.rays[r.chosen], full[r.chosen]);
  EXPECT_GE(r.rays[r.chosen], 0.95 * full[best]);
  EXPECT_LT(polar_deg(r.chosen), 18.5);
}

}  // namespace pbnbv
