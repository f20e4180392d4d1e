// Ray-casting information gain and the benchmark's baseline planners, against counts that can be
// checked by hand on small grids.
#include <gtest/gtest.h>

#include <set>

#include "core/planning/planner.hpp"
#include "core/planning/raycast.hpp"

namespace pbnbv {
namespace {

// An n^3 grid of 0.1 m voxels centred on the origin, every voxel in state s.
VoxelGrid cube_grid(int n, VoxelState s) {
  VoxelGrid g;
  g.resolution_m = 0.1;
  g.dims = Eigen::Vector3i::Constant(n);
  g.origin_m = Eigen::Vector3d::Constant(-0.05 * n);
  g.cells.assign(static_cast<std::size_t>(n) * n * n, s);
  return g;
}

void set(VoxelGrid& g, int x, int y, int z, VoxelState s) {
  g.cells[x + int64_t(g.dims.x()) * (y + int64_t(g.dims.y()) * z)] = s;
}

// A camera on the +z axis at height h looking down at the origin (optical z = -z).
Pose from_above(double h) { return look_at(Eigen::Vector3d(0, 0, h), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY()); }

RaycastParams dense() {
  RaycastParams p;
  p.camera = CameraIntrinsics{640, 480, 500, 500, 320, 240};
  p.range = DepthRange{0.1, 10.0};
  p.ray_spacing_voxels = 0.2;  // five rays per voxel footprint: nothing in the frustum is missed
  p.threads = 2;
  return p;
}

TEST(Raycast, EveryUnknownVoxelOfABoxInViewCountsOnce) {
  const VoxelGrid g = cube_grid(10, VoxelState::kUnknown);  // 1 m cube
  const auto gains = raycast_gains(g, {from_above(3.0)}, {}, dense());
  // From 3 m with a 640 x 480, f = 500 camera the whole cube is in view (half-width 0.5 m at
  // depth 2.5 m projects to 100 px): all 1,000 voxels, each once however many rays cross it.
  EXPECT_EQ(gains[0].unknown, 1000);
  EXPECT_GT(gains[0].rays, 1000);
}

TEST(Raycast, RaysStopAtTheFirstOccupiedVoxel) {
  VoxelGrid g = cube_grid(10, VoxelState::kUnknown);
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 10; ++y) set(g, x, y, 5, VoxelState::kOccupied);  // a floor at layer z = 5
  const auto gains = raycast_gains(g, {from_above(3.0)}, {}, dense());
  // Seen from above: layers z = 6..9 above the floor, 4 x 100 voxels; the floor and below hidden.
  EXPECT_EQ(gains[0].unknown, 400);
}

TEST(Raycast, EmptyVoxelsAreNotAGainAndAllUnobservedStatesAre) {
  VoxelGrid g = cube_grid(10, VoxelState::kEmpty);
  EXPECT_EQ(raycast_gains(g, {from_above(3.0)}, {}, dense())[0].unknown, 0);
  set(g, 1, 2, 3, VoxelState::kNone);
  set(g, 4, 5, 6, VoxelState::kUnknown);
  set(g, 7, 8, 9, VoxelState::kFrontier);
  EXPECT_EQ(raycast_gains(g, {from_above(3.0)}, {}, dense())[0].unknown, 3);
}

TEST(Raycast, ViewsFacingAwayOrInactiveCastNothing) {
  const VoxelGrid g = cube_grid(10, VoxelState::kUnknown);
  const Pose away = look_at(Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(0, 0, 6), Eigen::Vector3d::UnitY());
  const auto gains = raycast_gains(g, {away, from_above(3.0)}, {1, 0}, dense());
  EXPECT_EQ(gains[0].unknown, 0);
  EXPECT_EQ(gains[0].rays, 0);
  EXPECT_EQ(gains[1].rays, 0);  // inactive
}

TEST(Raycast, DepthRangeLimitsTheRays) {
  const VoxelGrid g = cube_grid(10, VoxelState::kUnknown);
  RaycastParams p = dense();
  p.range.max_m = 2.95;  // the cube's top face is at depth 2.5 m: layers z = 9..5 reachable
  EXPECT_EQ(raycast_gains(g, {from_above(3.0)}, {}, p)[0].unknown, 500);
}

TEST(Raycast, OneRayPerVoxelFootprintAtTheCentre) {
  const VoxelGrid g = cube_grid(10, VoxelState::kUnknown);
  RaycastParams p = dense();
  p.ray_spacing_voxels = 1.0;
  const auto gains = raycast_gains(g, {from_above(3.0)}, {}, p);
  // 0.1 m at the 3 m to the centre is 500 * 0.1 / 3 = 16.7 px.
  EXPECT_NEAR(gains[0].spacing_px, 500 * 0.1 / 3.0, 1e-9);
  // The box projects to a square of 2 * 500 * 0.5 / 2.5 = 200 px (top face, nearest): 12 x 12
  // rays; the columns under them are all counted, the rest of the back layers not.
  EXPECT_EQ(gains[0].rays, 144);
  EXPECT_LT(gains[0].unknown, 1000);
  EXPECT_GE(gains[0].unknown, 100 * 6);  // at least the nearest layers are covered
}

TEST(Raycast, BadInputIsNamed) {
  VoxelGrid g = cube_grid(4, VoxelState::kUnknown);
  try {
    raycast_gains(g, {from_above(3.0)}, {1, 1}, dense());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("active"), std::string::npos);
  }
  g.cells.pop_back();
  try {
    raycast_gains(g, {from_above(3.0)}, {}, dense());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cells"), std::string::npos);
  }
  g = cube_grid(4, VoxelState::kUnknown);
  RaycastParams p = dense();
  p.ray_spacing_voxels = 0;
  EXPECT_THROW(raycast_gains(g, {from_above(3.0)}, {}, p), std::invalid_argument);
}

TEST(Raycast, ProjectedBoxOfACubeSeenFaceOn) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Constant(-0.5), Eigen::Vector3d::Constant(0.5));
  const CameraIntrinsics k{640, 480, 500, 500, 320, 240};
  const PixelRect r = projected_box(box, k, from_above(3.0));
  // The top face at depth 2.5 m spans +-0.5 m: +-100 px about the principal point (edges +0.5).
  EXPECT_NEAR(r.u0, 220.5, 1e-9);
  EXPECT_NEAR(r.u1, 420.5, 1e-9);
  EXPECT_NEAR(r.v0, 140.5, 1e-9);
  EXPECT_NEAR(r.v1, 340.5, 1e-9);
  const PixelRect inside = projected_box(box, k, from_above(0.2));  // the camera is inside the box
  EXPECT_EQ(inside.u1, 640);
  EXPECT_EQ(inside.v1, 480);
}

// A map whose unobserved half is behind an occupied wall on the -x side: only views from +x see it.
VoxelGrid walled_grid() {
  VoxelGrid g = cube_grid(10, VoxelState::kEmpty);
  for (int y = 0; y < 10; ++y)
    for (int z = 0; z < 10; ++z) {
      set(g, 4, y, z, VoxelState::kOccupied);
      for (int x = 5; x < 10; ++x) set(g, x, y, z, VoxelState::kUnknown);
    }
  return g;
}

PlanInput plan_input(const VoxelGrid& g) {
  PlanInput in;
  in.bbox = g.bounds();
  in.candidates.num_views = 200;
  in.candidates.num_parallels = 10;
  in.candidates.area = CandidateArea::kFullSphere;
  in.candidates.working_distance_m = 1.0;
  in.camera = CameraIntrinsics{640, 480, 500, 500, 320, 240};
  return in;
}

TEST(RaycastPlanner, ChoosesTheSideWithUnobservedVoxels) {
  const VoxelGrid g = walled_grid();
  const PlanInput in = plan_input(g);
  RaycastParams p;
  p.camera = in.camera;
  // Cast in chunks of 50 candidates with progress reported after each (the scorer's heartbeat);
  // chunks change nothing: the gains equal those of one call over every candidate.
  PlanInput chunked = in;
  int calls = 0;
  chunked.progress = [&] { ++calls; };
  const PlanResult r = plan_raycast(chunked, g, p);
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_EQ(r.num_scored, 200);
  EXPECT_EQ(calls, 4);  // 200 / 50
  const std::vector<RaycastGain> whole = raycast_gains(g, r.candidates, {}, p);
  for (std::size_t i = 0; i < whole.size(); ++i) EXPECT_EQ(r.scores[i].quality, static_cast<double>(whole[i].unknown)) << i;
  const Eigen::Vector3d eye = r.candidates[r.chosen].translation();
  EXPECT_GT(eye.x(), 0.5 * eye.norm());  // well on the +x side
  for (int a : r.alternatives) EXPECT_LE(r.scores[a].quality, r.scores[r.chosen].quality);
  // Seen from straight -x the wall hides everything.
  const auto from_minus_x = raycast_gains(g, {look_at(Eigen::Vector3d(-3, 0, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ())}, {}, p);
  EXPECT_EQ(from_minus_x[0].unknown, 0);
}

TEST(RaycastPlanner, StopsWhenNothingIsUnobserved) {
  const VoxelGrid g = cube_grid(10, VoxelState::kEmpty);
  RaycastParams p;
  PlanInput in = plan_input(g);
  in.when_done = WhenDone::kStop;
  const PlanResult r = plan_raycast(in, g, p);
  EXPECT_EQ(r.outcome, PlanResult::Outcome::kStop);
  EXPECT_NE(r.reason.find("unobserved"), std::string::npos);
}

TEST(RaycastPlanner, WithABudgetLeftItFillsTheLargestGapInsteadOfStopping) {
  const VoxelGrid g = cube_grid(10, VoxelState::kEmpty);
  PlanInput in = plan_input(g);
  in.when_done = WhenDone::kSpread;
  in.views_done = {look_at(Eigen::Vector3d(3, 0, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ())};
  const PlanResult r = plan_raycast(in, g, RaycastParams{});
  ASSERT_EQ(r.outcome, PlanResult::Outcome::kView) << r.reason;
  EXPECT_NE(r.reason.find("no candidate sees an unobserved voxel"), std::string::npos) << r.reason;
  // Across the object from the one view taken (+x): the full sphere's candidate nearest -x.
  const Eigen::Vector3d eye = r.candidates[r.chosen].translation().normalized();
  EXPECT_LT(eye.x(), -0.98);
  EXPECT_GT(r.scores[r.chosen].quality, 165.0);  // degrees to the view taken
  EXPECT_GT(r.scoring_s, 0.0);                    // the casting that found nothing is timed
}

TEST(RandomPlanner, ReproducibleChoiceAmongAllowedCandidatesOnly) {
  const VoxelGrid g = walled_grid();
  PlanInput in = plan_input(g);
  // Candidates above the equator are unreachable.
  in.reachable = [](const std::vector<Pose>& c) {
    std::vector<bool> ok;
    for (const auto& p : c) ok.push_back(p.translation().z() < 0);
    return ok;
  };
  const PlanResult a = plan_random(in, 7), b = plan_random(in, 7);
  ASSERT_EQ(a.outcome, PlanResult::Outcome::kView);
  EXPECT_EQ(a.chosen, b.chosen);
  EXPECT_EQ(a.alternatives, b.alternatives);
  EXPECT_EQ(a.alternatives.size(), 5u);
  std::set<int> chosen;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const PlanResult r = plan_random(in, seed);
    EXPECT_LT(r.candidates[r.chosen].translation().z(), 0);
    for (int k : r.alternatives) EXPECT_LT(r.candidates[k].translation().z(), 0);
    chosen.insert(r.chosen);
  }
  EXPECT_GT(chosen.size(), 30u);  // 40 seeds over ~100 allowed candidates: mostly different
}


// The combined ranking's ray term (unobserved_ray_scores) casts the same rays as ray casting; per
// ray 1 - exp(-n / saturation), n the unobserved voxels it crosses before an Occupied one.
UnobservedRayParams saturating(double saturation_voxels) {
  UnobservedRayParams p;
  p.camera = dense().camera;
  p.range = dense().range;
  p.ray_spacing_voxels = dense().ray_spacing_voxels;
  p.saturation_voxels = saturation_voxels;
  p.threads = 2;
  return p;
}

TEST(UnobservedRays, AShortSaturationCountsTheRaysThatReachUnobservedSpace) {
  const VoxelGrid g = cube_grid(10, VoxelState::kUnknown);
  const auto rays = raycast_gains(g, {from_above(3.0)}, {}, dense())[0].rays;
  // Every ray enters the cube's top layer, so with n >= 1 and a saturation of 1e-3 voxel each ray
  // scores 1 - exp(-1000) = 1: the score is the number of rays.
  EXPECT_NEAR(unobserved_ray_scores(g, {from_above(3.0)}, {}, saturating(1e-3))[0], rays, 1e-9);
}

TEST(UnobservedRays, ALongSaturationAddsUpTheVoxelsEachRayCrosses) {
  // One unknown layer (z = 9) over empty space: a ray from 3 m above crosses it once, in one voxel
  // (or two where it crosses a side of a voxel within the 0.1 m layer). With saturation S much
  // larger than n, 1 - exp(-n / S) = n / S to within n^2 / 2S^2: S x score is the crossings.
  VoxelGrid g = cube_grid(10, VoxelState::kEmpty);
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 10; ++y) set(g, x, y, 9, VoxelState::kUnknown);
  const auto rays = raycast_gains(g, {from_above(3.0)}, {}, dense())[0].rays;
  const double crossings = 1e6 * unobserved_ray_scores(g, {from_above(3.0)}, {}, saturating(1e6))[0];
  EXPECT_GE(crossings, rays - 1e-3);        // every ray crosses the layer
  EXPECT_LE(crossings, 1.25 * rays);         // at most a quarter cross it in two voxels
}

TEST(UnobservedRays, OccupiedVoxelsStopTheRaysAndEmptySpaceScoresNothing) {
  VoxelGrid g = cube_grid(10, VoxelState::kUnknown);
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 10; ++y) set(g, x, y, 9, VoxelState::kOccupied);  // a lid on top
  EXPECT_EQ(unobserved_ray_scores(g, {from_above(3.0)}, {}, saturating(8))[0], 0.0);
  EXPECT_EQ(unobserved_ray_scores(cube_grid(10, VoxelState::kEmpty), {from_above(3.0)}, {}, saturating(8))[0], 0.0);
  EXPECT_EQ(unobserved_ray_scores(g, {from_above(3.0)}, {0}, saturating(8))[0], 0.0);  // inactive
}

// A box with a deep slot: a 10 x 10 x 10 block of Occupied voxels (seen surface all round), with a
// one-voxel slot down its middle from the top, x = y = 5, z = 4..9, never seen into (Unknown).
// Looking down the slot the rays reach its bottom, 6 voxels deep; from above at 45 degrees a ray
// that enters the 0.1 m opening meets a wall within two voxels; from the side nothing is seen.
// A short saturation counts the rays that reach the slot, a long one the voxels they cross: their
// ratio is the mean depth reached.
TEST(UnobservedRays, ADeepSlotIsSeenToItsBottomOnlyAlongIt) {
  VoxelGrid g = cube_grid(10, VoxelState::kOccupied);
  for (int z = 4; z < 10; ++z) set(g, 5, 5, z, VoxelState::kUnknown);
  const Pose side = look_at(Eigen::Vector3d(3, 0, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  const Pose oblique = look_at(Eigen::Vector3d(2.1, 0, 2.1), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  const std::vector<Pose> views = {from_above(3.0), side, oblique};
  const auto reached = unobserved_ray_scores(g, views, {}, saturating(1e-3));
  const auto crossed = unobserved_ray_scores(g, views, {}, saturating(1e6));
  // From above: the rays through the slot's 0.1 m opening at 2.5 m depth, 20 x 20 px at f = 500,
  // with 5 rays per 0.1 m voxel footprint at B's centre (3 m, 16.7 px): about 6 x 6 = 36.
  EXPECT_GT(reached[0], 20.0);
  EXPECT_LT(reached[0], 50.0);
  EXPECT_GT(1e6 * crossed[0] / reached[0], 5.0);   // nearly all 6 voxels deep
  EXPECT_EQ(reached[1], 0.0);                     // the side: walls only
  EXPECT_GT(reached[2], 0.0);                     // at 45 degrees: into the opening...
  EXPECT_LE(1e6 * crossed[2] / reached[2], 2.0);  // ...but no deeper than two voxels
}

// A thin rod not yet seen: one 0.1 m voxel thick (x = y = 6), the whole height of a 1.2 m grid of
// Empty space. Coarsened by 3 (the combined ranking's 0.03 m cells over a 0.01 m map, scaled) it
// stays: the 4 coarse cells of its column are unobserved, the other 60 Empty. Looking down it from
// 4 m, the rays enter its 0.3 m top at 3.4 m and spread as they go: a ray entering at (x, y) off
// the axis leaves through the side at 3.4 * 0.15 / max(|x|, |y|) m, so over the top's square the
// mean is 3.19 of the 4 cells (the 55 % within 0.111 m of the axis cross all 4). From the side a
// ray crosses it in one cell (two where it passes a cell's corner). The rod seen at 0.1 m is
// reached from the side as well.
TEST(UnobservedRays, AThinRodOfUnseenSpaceSurvivesCoarseningAndIsSeenAlongItsLength) {
  VoxelGrid g = cube_grid(12, VoxelState::kEmpty);
  for (int z = 0; z < 12; ++z) set(g, 6, 6, z, VoxelState::kUnknown);
  const VoxelGrid c = coarsened(g, 3);
  ASSERT_EQ(c.dims, Eigen::Vector3i(4, 4, 4));
  int unobserved = 0;
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) {
        const bool rod = x == 2 && y == 2;
        EXPECT_EQ(c.at(x, y, z), rod ? VoxelState::kUnknown : VoxelState::kEmpty) << x << " " << y << " " << z;
        unobserved += c.at(x, y, z) == VoxelState::kUnknown;
      }
  EXPECT_EQ(unobserved, 4);
  // The coarse rod's column is centred at (0.15, 0.15): look down it from above and across it.
  const Eigen::Vector3d axis(0.15, 0.15, 0);
  const Pose along = look_at(axis + Eigen::Vector3d(0, 0, 4), axis, Eigen::Vector3d::UnitY());
  const Pose across = look_at(axis + Eigen::Vector3d(4, 0, 0), axis, Eigen::Vector3d::UnitZ());
  const auto reached = unobserved_ray_scores(c, {along, across}, {}, saturating(1e-3));
  const auto crossed = unobserved_ray_scores(c, {along, across}, {}, saturating(1e6));
  ASSERT_GT(reached[0], 0.0);
  ASSERT_GT(reached[1], 0.0);
  EXPECT_GT(1e6 * crossed[0] / reached[0], 3.0);  // down the rod: 3.19 cells by hand
  EXPECT_LE(1e6 * crossed[1] / reached[1], 2.0);  // across it: one cell, two at a corner
  EXPECT_GT(unobserved_ray_scores(g, {across}, {}, saturating(1e-3))[0], 0.0);  // the fine rod too
}

TEST(UnobservedRays, CoarsenedKeepsOccupiedThenUnobservedThenEmpty) {
  VoxelGrid g = cube_grid(4, VoxelState::kEmpty);  // 0.4 m, 0.1 m voxels
  set(g, 0, 0, 0, VoxelState::kFrontier);           // block (0, 0, 0): unobserved
  set(g, 2, 0, 0, VoxelState::kUnknown);            // block (1, 0, 0): Occupied wins
  set(g, 3, 1, 1, VoxelState::kOccupied);
  set(g, 0, 3, 3, VoxelState::kNone);               // block (0, 1, 1): unobserved
  const VoxelGrid c = coarsened(g, 2);
  EXPECT_EQ(c.dims, Eigen::Vector3i(2, 2, 2));
  EXPECT_DOUBLE_EQ(c.resolution_m, 0.2);
  EXPECT_EQ(c.origin_m, g.origin_m);
  EXPECT_EQ(c.at(0, 0, 0), VoxelState::kUnknown);
  EXPECT_EQ(c.at(1, 0, 0), VoxelState::kOccupied);
  EXPECT_EQ(c.at(0, 1, 1), VoxelState::kUnknown);
  EXPECT_EQ(c.at(1, 1, 1), VoxelState::kEmpty);
  EXPECT_EQ(coarsened(cube_grid(5, VoxelState::kEmpty), 2).dims, Eigen::Vector3i(3, 3, 3));  // partial blocks
  EXPECT_THROW(coarsened(g, 0), std::invalid_argument);
}

}  // namespace
}  // namespace pbnbv
