// The view scorer's conversions: a PLAN_REQUEST becomes the planner's input with every bad field
// named, a VOXEL_MAP's cells become the ray caster's grid, a planning step fills its VIEW_PLAN.
#include "bus/convert_planning.hpp"

#include <gtest/gtest.h>

#include "error_message.hpp"

#include <cmath>
#include <functional>
#include <string>

using namespace pbnbv;
using pbnbv::testing::expect_error;

namespace {

plan_request_t request() {
  plan_request_t r{};
  r.scan_id = "s";
  r.planner = "pbnbv";
  r.num_candidates = 800;
  r.num_parallels = 24;
  r.num_sectors = 4;
  r.full_sphere = true;
  r.working_distance_m = 0.6;
  r.num_alternatives = 5;
  r.spread_when_done = true;
  r.first_quality = std::nan("");
  r.width_px = 1280;
  r.height_px = 720;
  r.fx = r.fy = 696;
  r.cx = 640;
  r.cy = 360;
  r.depth_min_m = 0.1;
  r.depth_max_m = 3.0;
  return r;
}

}  // namespace

TEST(ConvertPlanning, ARequestBecomesThePlannersInput) {
  plan_request_t r = request();
  r.num_views_done = 1;
  r.views_done.resize(1);
  r.views_done[0].position_m[0] = 0.7;
  r.views_done[0].quat_wxyz[0] = 1;
  const PlanInput in = bus::plan_input_from_msg(r);
  EXPECT_EQ(in.candidates.num_views, 800);
  EXPECT_EQ(in.candidates.area, CandidateArea::kFullSphere);
  EXPECT_EQ(in.when_done, WhenDone::kSpread);
  EXPECT_EQ(in.beta, 4);
  ASSERT_EQ(in.views_done.size(), 1u);
  EXPECT_EQ(in.views_done[0].translation().x(), 0.7);
  EXPECT_TRUE(std::isnan(in.first_quality));
  EXPECT_EQ(in.depth_range.min_m, 0.1);  // the combined ranking's rays stop at the depth range
  EXPECT_EQ(in.depth_range.max_m, 3.0);
}

TEST(ConvertPlanning, BadRequestFieldsAreNamed) {
  plan_request_t r = request();
  r.num_candidates = 0;
  expect_error([&] { bus::plan_input_from_msg(r); }, "PLAN_REQUEST num_candidates");
  r = request();
  r.num_parallels = 900;  // more parallels than candidates
  expect_error([&] { bus::plan_input_from_msg(r); }, "num_parallels");
  r = request();
  r.num_excluded = 1;
  r.excluded.resize(1);
  r.excluded[0].quat_wxyz[0] = 2;  // not a unit quaternion
  expect_error([&] { bus::plan_input_from_msg(r); }, "PLAN_REQUEST excluded[0]");
  r = request();
  r.fx = -1;
  expect_error([&] { bus::plan_input_from_msg(r); }, "fx");
  r = request();
  r.depth_max_m = 0.05;  // below the minimum
  expect_error([&] { bus::plan_input_from_msg(r); }, "PLAN_REQUEST depth_min_m / depth_max_m");
}

TEST(ConvertPlanning, VoxelMapCellsBecomeTheGridAndABadStateIsNamed) {
  voxel_set_t m{};
  m.iteration = 3;
  m.resolution_m = 0.03;
  for (int k = 0; k < 3; ++k) {
    m.bbox_min_m[k] = -0.03;
    m.bbox_max_m[k] = 0.03;
    m.dims[k] = 2;
  }
  m.cells.assign(8, static_cast<int8_t>(VoxelState::kUnknown));
  m.cells[7] = static_cast<int8_t>(VoxelState::kOccupied);  // x = y = z = 1
  m.num_cells = 8;
  const VoxelGrid g = bus::grid_from_msg(m);
  EXPECT_EQ(g.at(1, 1, 1), VoxelState::kOccupied);
  EXPECT_EQ(g.at(0, 1, 1), VoxelState::kUnknown);
  EXPECT_EQ(g.bounds().max(), Eigen::Vector3d::Constant(0.03));
  m.cells[2] = 9;
  expect_error([&] { bus::grid_from_msg(m); }, "VOXEL_MAP of view 3");
  m.dims[0] = m.dims[1] = m.dims[2] = 0;
  m.cells.clear();
  expect_error([&] { bus::grid_from_msg(m); }, "carries no cells");
}

TEST(ConvertPlanning, AResultFillsItsAnswer) {
  PlanResult res;
  res.outcome = PlanResult::Outcome::kView;
  res.reason = "best F";
  res.candidates = {look_at_z_up(Eigen::Vector3d(0.8, 0, 0), Eigen::Vector3d::Zero()),
                    look_at_z_up(Eigen::Vector3d(0, 0.8, 0), Eigen::Vector3d::Zero())};
  res.scores.resize(2);
  res.scores[0].quality = 120;
  res.scores[1].quality = 80;
  res.chosen = 0;
  res.alternatives = {1};
  res.num_scored = 2;
  view_plan_t out = bus::empty_answer(request());
  bus::fill_answer(out, res);
  EXPECT_EQ(out.outcome, view_plan_t::kView);
  EXPECT_EQ(out.view_quality, 120);
  EXPECT_NEAR(out.object_T_camera.position_m[0], 0.8, 1e-12);
  ASSERT_EQ(out.num_alternatives, 1);
  EXPECT_NEAR(out.alternatives[0].position_m[1], 0.8, 1e-12);
  EXPECT_EQ(out.alternative_quality[0], 80);
  EXPECT_EQ(out.num_candidates, 2);
  EXPECT_EQ(out.ranking, "f_px");
  res.ranking = Ranking::kGapAngle;
  bus::fill_answer(out, res);
  EXPECT_EQ(out.ranking, "gap_deg");
}
