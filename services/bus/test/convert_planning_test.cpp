// The view scorer's conversions: a PLAN_REQUEST becomes the planner's input with every bad field
// named, a VOXEL_MAP's cells become the ray caster's grid, a planning step fills its VIEW_PLAN.
#include "bus/convert_planning.hpp"

#include <gtest/gtest.h>

#include "error_message.hpp"

#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <utility>

#include "bus/message_schema.hpp"

using namespace pbnbv;
using pbnbv::testing::expect_error;

namespace {

plan_request_t request() {
  plan_request_t r{};
  r.scan_id = "s";
  r.planner = plan_request_t::kPlannerPbnbv;
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
  EXPECT_EQ(out.ranking, view_plan_t::kRankingF);
  res.ranking = Ranking::kGapAngle;
  bus::fill_answer(out, res);
  EXPECT_EQ(out.ranking, view_plan_t::kRankingGapAngle);
}

// Every field of PLAN_REQUEST (its schema, generated from lcmtypes/plan_request_t.lcm) changed in
// turn: the reachability key changes with each field the reachable set depends on and stays with
// each of the others, listed with why it does not matter. A field added to the contract fails
// here until it is classified: the scorer's cache cannot go stale on a field nobody thought of.
TEST(ConvertPlanning, TheReachabilityKeyCoversEveryFieldItDependsOn) {
  using Change = std::function<void(plan_request_t&)>;
  plan_request_t base = request();
  base.check_reachability = true;
  base.object_z_m = 0.05;
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.1, -0.1, 0), Eigen::Vector3d(0.1, 0.1, 0.2));
  const std::map<std::string, Change> depends = {
      {"scan_id", [](plan_request_t& r) { r.scan_id += "2"; }},
      {"num_candidates", [](plan_request_t& r) { r.num_candidates += 1; }},
      {"num_parallels", [](plan_request_t& r) { r.num_parallels += 1; }},
      {"full_sphere", [](plan_request_t& r) { r.full_sphere = !r.full_sphere; }},
      {"working_distance_m", [](plan_request_t& r) { r.working_distance_m += 1e-9; }},
      {"joint_position_rad", [](plan_request_t& r) { r.joint_position_rad[5] += 1e-9; }},
      {"turntable_angle_rad", [](plan_request_t& r) { r.turntable_angle_rad += 1e-9; }},
      {"object_z_m", [](plan_request_t& r) { r.object_z_m += 1e-9; }},
      {"keepout_min_m", [](plan_request_t& r) { r.keepout_min_m[2] -= 1e-9; }},
      {"keepout_max_m", [](plan_request_t& r) { r.keepout_max_m[1] += 1e-9; }},
      {"turntable_choice", [](plan_request_t& r) { r.turntable_choice = 1 - r.turntable_choice; }},
  };
  const char* const kChosenAfter = "the planner chooses among the reachable candidates after the check";
  const char* const kRigCamera = "the check's line of sight runs from the rig file's camera, not the request's intrinsics";
  const std::map<std::string, std::pair<Change, const char*>> ignores = {
      {"utime", {[](plan_request_t& r) { r.utime += 1; }, "a publish time"}},
      {"iteration", {[](plan_request_t& r) { r.iteration += 1; }, "which view is planned: the state and B say the rest"}},
      {"request_id", {[](plan_request_t& r) { r.request_id += 1; }, "an answer's id"}},
      {"map_iteration", {[](plan_request_t& r) { r.map_iteration += 1; }, "the map enters the key as B"}},
      {"map_request_id", {[](plan_request_t& r) { r.map_request_id += 1; }, "the map enters the key as B"}},
      {"planner", {[](plan_request_t& r) { r.planner = plan_request_t::kPlannerRaycast; }, kChosenAfter}},
      {"seed", {[](plan_request_t& r) { r.seed += 1; }, kChosenAfter}},
      {"num_views_done", {[](plan_request_t& r) { r.num_views_done = 1; r.views_done.resize(1); }, kChosenAfter}},
      {"views_done", {[](plan_request_t& r) { r.views_done.resize(1); r.views_done[0].position_m[0] = 1; }, kChosenAfter}},
      {"num_excluded", {[](plan_request_t& r) { r.num_excluded = 1; r.excluded.resize(1); }, kChosenAfter}},
      {"excluded", {[](plan_request_t& r) { r.excluded.resize(1); r.excluded[0].position_m[1] = 1; }, kChosenAfter}},
      {"num_sectors", {[](plan_request_t& r) { r.num_sectors += 1; }, kChosenAfter}},
      {"num_alternatives", {[](plan_request_t& r) { r.num_alternatives += 1; }, kChosenAfter}},
      {"stop_fraction", {[](plan_request_t& r) { r.stop_fraction += 0.1; }, kChosenAfter}},
      {"spread_when_done", {[](plan_request_t& r) { r.spread_when_done = !r.spread_when_done; }, kChosenAfter}},
      {"first_quality", {[](plan_request_t& r) { r.first_quality = 3; }, kChosenAfter}},
      {"seconds_per_point", {[](plan_request_t& r) { r.seconds_per_point += 1; }, kChosenAfter}},
      {"depth_min_m", {[](plan_request_t& r) { r.depth_min_m += 0.01; }, kRigCamera}},
      {"depth_max_m", {[](plan_request_t& r) { r.depth_max_m += 0.01; }, kRigCamera}},
      {"width_px", {[](plan_request_t& r) { r.width_px += 2; }, kRigCamera}},
      {"height_px", {[](plan_request_t& r) { r.height_px += 2; }, kRigCamera}},
      {"fx", {[](plan_request_t& r) { r.fx += 1; }, kRigCamera}},
      {"fy", {[](plan_request_t& r) { r.fy += 1; }, kRigCamera}},
      {"cx", {[](plan_request_t& r) { r.cx += 1; }, kRigCamera}},
      {"cy", {[](plan_request_t& r) { r.cy += 1; }, kRigCamera}},
      {"check_reachability", {[](plan_request_t& r) { r.check_reachability = false; }, "false: nothing is checked or kept"}},
  };
  const bus::MessageSchema* schema = bus::find_schema("plan_request_t");
  ASSERT_NE(schema, nullptr);
  for (const bus::FieldSchema& f : schema->fields) {
    const std::string name(f.name);
    EXPECT_EQ(depends.count(name) + ignores.count(name), 1u)
        << "PLAN_REQUEST." << name << " is not classified: does the reachable set depend on it?";
  }
  EXPECT_EQ(depends.size() + ignores.size(), schema->fields.size()) << "a classified field is not in the contract";
  const std::string key = bus::reachability_key(base, box);
  for (const auto& [name, change] : depends) {
    plan_request_t r = base;
    change(r);
    EXPECT_NE(bus::reachability_key(r, box), key) << name << " changed and the key did not";
  }
  for (const auto& [name, change_why] : ignores) {
    plan_request_t r = base;
    change_why.first(r);
    EXPECT_EQ(bus::reachability_key(r, box), key) << name << " is in the key although " << change_why.second;
  }
  const Eigen::AlignedBox3d grown(box.min(), box.max() + Eigen::Vector3d(0, 0, 0.03));
  EXPECT_NE(bus::reachability_key(base, grown), key) << "B grew and the key did not";
  // A scan id that ends in a digit is not another scan's id with the number moved into it.
  plan_request_t a = base, b = base;
  a.scan_id = "s1";
  b.scan_id = "s";
  EXPECT_NE(bus::reachability_key(a, box), bus::reachability_key(b, box));
}
