// The ellipsoid fitter and the view scorer on a real bus: a voxel map with a frontier on one side
// gives ellipsoids and a plan that looks at that side; a repeated request gets the stored answer;
// the plan figures go where the scorer's --out says, named by view, and nowhere else.
// Runs inside a private network namespace (see CMakeLists.txt).
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "service_suite.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

// The ellipsoid fitter and the view scorer (with the arm rig's reachability), the scorer serving
// scan "planning" with its figures in figures_.
class PlanningServices : public ServiceSuite {
 protected:
  static void SetUpTestSuite() {
    const std::string bin = bin_dir();
    figures_ = fresh_dir("planning-figures");
    start_suite("planning-services", {
        {"ellipsoids", {bin + "/pbnbv-ellipsoids"}},
        {"scorer", {bin + "/pbnbv-scorer", "--rig", "arm", "--scan", "planning", "--out", figures_.string()}},
    });
  }
  static void TearDownTestSuite() { stop_suite(); }
  // Every file under figures_, relative to it.
  static std::set<std::string> figure_files() {
    std::set<std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(figures_)) {
      if (e.is_regular_file()) files.insert(fs::relative(e.path(), figures_).string());
    }
    return files;
  }
  inline static fs::path figures_;
};

TEST_F(PlanningServices, EllipsoidFitterAndViewScorerPlanTowardsTheFrontier) {
  // A map on the bus -> the fitter's ellipsoids -> a plan request -> the scorer's view, which
  // must look at the frontier side (+y); asked again, the same answer (idempotent).
  lcm::LCM& lcm = listener_->lcm();
  const voxel_set_t map = synthetic_map("planning", 0);
  lcm.publish("VOXEL_MAP", &map);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->ellipsoids.count({"planning", 0}) > 0; }, 20.0));
  const ellipsoid_set_t& e = listener_->ellipsoids[{"planning", 0}];
  EXPECT_GE(e.occupied_components, 1);
  EXPECT_EQ(e.frontier_components, 1) << "one flat slab of frontier voxels";
  int frontier = 0;
  for (const auto& el : e.ellipsoids) {
    if (el.cls != ellipsoid_t::kFrontier) continue;
    ++frontier;
    EXPECT_NEAR(el.centre_m[1], 0.18, 0.01);
    // One voxel thin: the thinnest semi-axis is about half a voxel (fitted to voxel corners).
    const double thin = std::min({el.semi_axes_m[0], el.semi_axes_m[1], el.semi_axes_m[2]});
    EXPECT_GT(thin, 0.01);
    EXPECT_LT(thin, 0.04);
  }
  EXPECT_EQ(frontier, 1);

  const plan_request_t r = plan_request("planning", 1, 0);
  lcm.publish("PLAN_REQUEST", &r);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->plans.count({"planning", 1}) > 0; }, 30.0));
  const view_plan_t p = listener_->plans[{"planning", 1}];
  ASSERT_EQ(p.outcome, view_plan_t::kView) << p.reason;
  EXPECT_EQ(p.num_candidates, 800);
  EXPECT_EQ(p.num_scored + p.num_unreachable, 800);
  EXPECT_GT(p.view_quality, 0);
  EXPECT_EQ(p.num_alternatives, 3);
  EXPECT_GT(p.object_T_camera.position_m[1], 0.3) << "the view should face the frontier side (+y)";
  const int answers = listener_->plan_answers;
  lcm.publish("PLAN_REQUEST", &r);
  ASSERT_TRUE(listener_->spin_until([&] { return listener_->plan_answers > answers; }, 10.0));
  const view_plan_t again = listener_->plans[{"planning", 1}];
  EXPECT_EQ(again.utime, p.utime) << "a repeated request gets the stored answer";
  EXPECT_TRUE(all_running());
}

// The scorer draws each plan of its scan into its own --out: plans/view_NNN.png and .svg, NNN the
// request's view counted from 1 (no path comes from the bus). A request for a view outside
// 0..999 is refused with the reason and draws nothing; another scan's request is not answered and
// draws nothing.
TEST_F(PlanningServices, PlanFiguresGoUnderTheScorersOutNamedByView) {
  lcm::LCM& lcm = listener_->lcm();
  const voxel_set_t map = synthetic_map("planning", 0);
  lcm.publish("VOXEL_MAP", &map);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->ellipsoids.count({"planning", 0}) > 0; }, 20.0));
  plan_request_t r = plan_request("planning", 11, 0);
  r.iteration = 4;
  lcm.publish("PLAN_REQUEST", &r);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->plans.count({"planning", 11}) > 0; }, 30.0));
  const view_plan_t& planned = listener_->plans[{"planning", 11}];
  ASSERT_EQ(planned.outcome, view_plan_t::kView) << planned.reason;
  const fs::path png = figures_ / "plans" / "view_005.png";
  ASSERT_TRUE(listener_->spin_until([&] { return fs::exists(fs::path(png).replace_extension(".svg")); }, 20.0))
      << "no figure of view 5 under " << figures_;
  std::ifstream in(png, std::ios::binary);
  std::string magic(8, '\0');
  in.read(magic.data(), 8);
  EXPECT_EQ(magic, std::string("\x89PNG\r\n\x1a\n", 8)) << png << " is not a PNG";
  const std::set<std::string> drawn = figure_files();
  EXPECT_TRUE(drawn.count("plans/view_005.png") && drawn.count("plans/view_005.svg"));

  int64_t id = 12;
  for (const int bad : {1000, -1}) {
    plan_request_t out_of_range = plan_request("planning", id, 0);
    out_of_range.iteration = bad;
    lcm.publish("PLAN_REQUEST", &out_of_range);
    ASSERT_TRUE(listener_->spin_until([&] { return listener_->plans.count({"planning", id}) > 0; }, 10.0)) << bad;
    const view_plan_t& refused = listener_->plans[{"planning", id}];
    EXPECT_EQ(refused.outcome, view_plan_t::kFailed) << bad;
    EXPECT_EQ(refused.reason, "bad request: PLAN_REQUEST iteration = " + std::to_string(bad) + " is outside [0, 999]");
    ++id;
  }
  const voxel_set_t other_map = synthetic_map("another-scan", 0);
  lcm.publish("VOXEL_MAP", &other_map);
  plan_request_t other = plan_request("another-scan", id, 0);
  other.iteration = 6;
  lcm.publish("PLAN_REQUEST", &other);
  listener_->spin_until([] { return false; }, 3.0);
  EXPECT_EQ(listener_->plans.count({"another-scan", id}), 0u) << "the scorer serves scan \"planning\" only";
  EXPECT_EQ(figure_files(), drawn) << "a refused or foreign request drew something";
  EXPECT_TRUE(all_running());
}

}  // namespace
