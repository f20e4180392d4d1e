// The ellipsoid fitter and the view scorer on a real bus: a voxel map with a frontier on one side
// gives ellipsoids and a plan that looks at that side; a repeated request gets the stored answer.
// Runs inside a private network namespace (see CMakeLists.txt).
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "service_suite.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

// The ellipsoid fitter and the view scorer (with the arm rig's reachability).
class PlanningServices : public ServiceSuite {
 protected:
  static void SetUpTestSuite() {
    const std::string bin = bin_dir();
    start_suite("planning-services", {
        {"ellipsoids", {bin + "/pbnbv-ellipsoids"}},
        {"scorer", {bin + "/pbnbv-scorer", "--rig", "arm"}},
    });
  }
  static void TearDownTestSuite() { stop_suite(); }
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

}  // namespace
