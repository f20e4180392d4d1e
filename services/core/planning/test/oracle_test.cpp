// The oracle (plan_oracle, planner.hpp) and its count (count_newly_visible, visibility.hpp) on a
// hand-countable case: a 0.3 m cube, whose faces a camera sees whole or not at all (a camera on
// an axis sees one face, one on a diagonal three), so every count is a sum of face counts.
#include "core/planning/planner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace pbnbv {
namespace {

constexpr double kHalf = 0.15;  // the cube's half edge, m

struct Cube {
  TriangleMesh mesh = make_box(Eigen::Vector3d::Constant(2 * kHalf));
  SurfaceSamples samples = sample_surface_with_normals(mesh, 6000, 1);
};

// Samples on the face with outward normal sign * e_axis.
int on_face(const Cube& c, int axis, int sign) {
  return static_cast<int>(std::count_if(c.samples.points.begin(), c.samples.points.end(), [&](const Eigen::Vector3d& p) {
    return std::abs(p[axis] - sign * kHalf) < 1e-9;
  }));
}

// Camera 0.8 m from the centre in direction d, looking at the centre.
Pose camera(const Eigen::Vector3d& d) { return look_at_z_up(0.8 * d.normalized(), Eigen::Vector3d::Zero()); }

VisibilityParams params() {
  VisibilityParams p;  // the default camera: 1280 x 720, fx 696 (the cube spans < 20 deg of 27)
  return p;
}

TEST(Oracle, EachSampleLiesOnOneFace) {
  const Cube c;
  int total = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      const int n = on_face(c, axis, sign);
      EXPECT_NEAR(n, 1000, 120) << "axis " << axis << " sign " << sign;  // by area: a sixth each
      total += n;
    }
  }
  EXPECT_EQ(total, 6000);
}

TEST(Oracle, AnAxisCameraSeesOneFaceADiagonalOneThree) {
  const Cube c;
  const std::vector<Pose> views = {camera({1, 0, 0}), camera({-1, 0, 0}), camera({0, 1, 0}), camera({0, 0, -1}),
                                   camera({1, 1, 1}), camera({-1, -1, -1}), camera({1, -1, 1})};
  const std::vector<int> n = count_newly_visible(c.mesh, c.samples.points, c.samples.normals, views, {}, params());
  const int px = on_face(c, 0, 1), mx = on_face(c, 0, -1), py = on_face(c, 1, 1), my = on_face(c, 1, -1);
  const int pz = on_face(c, 2, 1), mz = on_face(c, 2, -1);
  EXPECT_EQ(n, (std::vector<int>{px, mx, py, mz, px + py + pz, mx + my + mz, px + my + pz}));
}

TEST(Oracle, SamplesSeenBeforeDoNotCount) {
  const Cube c;
  const std::vector<uint8_t> seen = visible_from_any(c.mesh, c.samples.points, c.samples.normals, {camera({1, 0, 0})}, params());
  const int px = on_face(c, 0, 1), mx = on_face(c, 0, -1), py = on_face(c, 1, 1), my = on_face(c, 1, -1);
  const int pz = on_face(c, 2, 1), mz = on_face(c, 2, -1);
  EXPECT_EQ(std::count(seen.begin(), seen.end(), uint8_t{1}), px);
  const std::vector<Pose> views = {camera({1, 0, 0}), camera({-1, 0, 0}), camera({1, 1, 1}), camera({-1, -1, -1})};
  const std::vector<int> n = count_newly_visible(c.mesh, c.samples.points, c.samples.normals, views, seen, params());
  EXPECT_EQ(n, (std::vector<int>{0, mx, py + pz, mx + my + mz}));
  EXPECT_THROW(count_newly_visible(c.mesh, c.samples.points, c.samples.normals, views, std::vector<uint8_t>(3), params()),
               std::invalid_argument);
}

// The greedy choice among the planner's candidates (800 on the full sphere around the cube's
// box): first the corner whose three faces hold the most samples, then, after a view on +x,
// a corner on the -x side with the two most populated of the four side faces.
TEST(Oracle, ChoosesTheCandidateThatSeesTheMostNewSurface) {
  const Cube c;
  PlanInput in;
  in.bbox = Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-kHalf), Eigen::Vector3d::Constant(kHalf));
  in.candidates.area = CandidateArea::kFullSphere;
  const VisibilityParams p = params();

  int best_corner = 0;
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      for (int sz : {-1, 1}) best_corner = std::max(best_corner, on_face(c, 0, sx) + on_face(c, 1, sy) + on_face(c, 2, sz));
    }
  }
  const PlanResult first = plan_oracle(in, c.mesh, c.samples, p);
  ASSERT_EQ(first.outcome, PlanResult::Outcome::kView) << first.reason;
  EXPECT_EQ(first.num_scored, static_cast<int>(first.candidates.size()));
  EXPECT_EQ(first.scores[first.chosen].quality, best_corner);

  in.views_done = {look_at_z_up(Eigen::Vector3d(0.86, 0, 0), Eigen::Vector3d::Zero())};
  const PlanResult second = plan_oracle(in, c.mesh, c.samples, p);
  ASSERT_EQ(second.outcome, PlanResult::Outcome::kView) << second.reason;
  int best_pair = 0;
  for (int sy : {-1, 1}) {
    for (int sz : {-1, 1}) best_pair = std::max(best_pair, on_face(c, 1, sy) + on_face(c, 2, sz));
  }
  EXPECT_EQ(second.scores[second.chosen].quality, on_face(c, 0, -1) + best_pair);
  EXPECT_LT(second.candidates[second.chosen].translation().x(), 0.0);
  EXPECT_GT(second.num_excluded, 0);  // the candidates near the view taken (skip_revisits)
}

TEST(Oracle, StopsOrSpreadsWhenNothingNewIsVisible) {
  const Cube c;
  PlanInput in;
  in.bbox = Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-kHalf), Eigen::Vector3d::Constant(kHalf));
  in.candidates.area = CandidateArea::kFullSphere;
  in.views_done = {camera({1, 1, 1}), camera({-1, -1, -1}), camera({1, -1, -1}), camera({-1, 1, 1})};
  in.when_done = WhenDone::kStop;
  const PlanResult stop = plan_oracle(in, c.mesh, c.samples, params());
  EXPECT_EQ(stop.outcome, PlanResult::Outcome::kStop) << stop.reason;
  in.when_done = WhenDone::kSpread;
  const PlanResult spread = plan_oracle(in, c.mesh, c.samples, params());
  EXPECT_EQ(spread.outcome, PlanResult::Outcome::kView) << spread.reason;
}

}  // namespace
}  // namespace pbnbv
