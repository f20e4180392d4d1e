// The twin's contact check (twin/contact_monitor.hpp) on models/rig_arm.xml, with moves whose
// outcome is worked out by hand from the rig file:
//  - with a1 = a4 = a6 = 0 the joints a2, a3 and a5 turn about parallel axes (base y), so the tool
//    axis (flange x) points along the base's +x turned down by a2 + a3 + a5; a straight line in
//    joint space between two configurations with the same sum keeps that sum, so the tool keeps
//    its direction all along the move;
//  - the camera housing (a box 90 x 25 x 25 mm on body camera_optical) reaches furthest along the
//    tool axis: its centre 50 - 10.5 = 39.5 mm beyond the flange face, its half-depth 12.5 mm,
//    so its face is 52 mm beyond the flange face (the bracket reaches 29 mm, the flange 0 mm);
//    whatever lies ahead of the tool is touched first by the housing, when the flange face is
//    52 mm from it.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <unistd.h>

#include "core/base/units.hpp"
#include "core/geometry/mesh.hpp"
#include "core/io/mesh_file.hpp"
#include "core/rig/rig.hpp"
#include "twin/rig_sim.hpp"

using namespace pbnbv;

namespace {

constexpr double kHousingReachM = 0.052;  // the housing's face beyond the flange face, along the tool axis

std::filesystem::path temp_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

// a1 = a4 = a6 = 0, a5 chosen so that the tool points `down` rad below the base's +x.
Vector6d planar(double a2, double a3, double down) {
  Vector6d q;
  q << 0, a2, a3, 0, down - a2 - a3, 0;
  return q;
}

// Steps until the arm settles or `limit_s` of rig time passes, collecting the contacts; stops at
// the first contact when `stop_at_contact`.
std::vector<twin::RigContact> run(twin::RigSim& sim, double limit_s, bool stop_at_contact) {
  std::vector<twin::RigContact> found;
  const int steps = static_cast<int>(limit_s / sim.model()->opt.timestep);
  for (int i = 0; i < steps; ++i) {
    sim.step();
    for (const twin::RigContact& c : sim.take_contacts()) found.push_back(c);
    if (stop_at_contact && !found.empty()) break;
    if (!stop_at_contact && sim.settled(sim.arm())) break;
  }
  return found;
}

}  // namespace

// Tool straight down (a2 + a3 + a5 = 90 deg) 0.7 m from the turntable axis towards the arm, over
// the table: from the flange 0.25 m above the table top down to 0.0104 m (the housing 41.6 mm
// into the table). The housing touches the table when the flange face is 52 mm above it: counted
// once, named "camera_optical / table"; the rig stops there and holds; a command away moves it
// again, and the way back to the start touches nothing.
TEST(ContactMonitor, TheCameraDrivenIntoTheTableIsStoppedAtItsSurfaceAndCountedOnce) {
  const auto dir = temp_dir("contact_table");
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  const Vector6d above = planar(0.3234, 1.6223, kPi / 2), into = planar(0.78, 0.9, kPi / 2);
  // By forward kinematics: both at world y = -0.70 (0.40 m from the arm's A1 axis, which stands at
  // y = -1.1), x = 0, the tool along world -z, the flange face 0.25 m and 0.0104 m above the table.
  for (const auto& [q, z] : {std::pair{above, 0.25}, std::pair{into, 0.0104}}) {
    const Pose f = flange_in_world(rig, q);
    EXPECT_NEAR(f.translation().x(), 0.0, 1e-9);
    EXPECT_NEAR(f.translation().y(), -0.70, 2e-3);
    EXPECT_NEAR(f.translation().z(), z, 1e-3);
    EXPECT_NEAR(f.linear().col(0).z(), -1.0, 1e-9) << "the tool points straight down";
  }
  twin::RigSim sim(rig, twin::ObjectPlacement{}, (dir / "model.xml").string());
  EXPECT_EQ(sim.contact_events(), 0) << "home touches nothing";
  sim.command_arm(above, 1.0, 1);
  EXPECT_TRUE(run(sim, 20.0, false).empty()) << "home to 0.25 m above the table touches nothing";
  ASSERT_TRUE(sim.settled(sim.arm()));

  sim.command_arm(into, 1.0, 2);
  const std::vector<twin::RigContact> found = run(sim, 20.0, true);
  ASSERT_EQ(found.size(), 1u);
  const twin::RigContact& c = found[0];
  EXPECT_EQ(c.moving, "camera_optical");
  EXPECT_EQ(c.other, "table");
  EXPECT_EQ(c.command_seq, 2);
  EXPECT_GT(c.depth_m, 0.0);
  // The sweep checks states at most 2 mm apart: found at most 2 mm deep.
  EXPECT_LE(c.depth_m, twin::kMaxSweepStepM + 1e-6);
  EXPECT_EQ(c.text().rfind("camera_optical / table, ", 0), 0u) << c.text();
  EXPECT_NE(c.text().find("during command 2"), std::string::npos) << c.text();
  // Where it was found: the flange face 52 mm above the table top, less what the arm moved in
  // the step it was found in (the physics step's end; 2 ms at up to ~1.2 m/s here).
  const double z_found = flange_in_world(rig, sim.arm_position()).translation().z();
  EXPECT_LE(z_found, kHousingReachM + 1e-4);
  EXPECT_GE(z_found, kHousingReachM - 0.004);

  // The protective stop: it holds there (the table's push aside), one contact, never reaching the
  // target 41.6 mm further down.
  for (int i = 0; i < 1500; ++i) sim.step();  // 3 s (the soft contact and the servo settle in ~0.3 s)
  EXPECT_TRUE(sim.take_contacts().empty());
  EXPECT_EQ(sim.contact_events(), 1);
  EXPECT_EQ(sim.arm().command_seq, 2) << "held under the command it was executing";
  EXPECT_LT(sim.arm_velocity().cwiseAbs().maxCoeff(), 1e-4) << "holding still";
  const double z_held = flange_in_world(rig, sim.arm_position()).translation().z();
  std::printf("table: found %.4f mm deep with the flange %.2f mm above the table, held at %.2f mm; held %g rad off the "
              "hold target\n", c.depth_m * 1e3, z_found * 1e3, z_held * 1e3,
              (sim.arm_position() - Eigen::Map<const Vector6d>(sim.arm().target.data())).cwiseAbs().maxCoeff());
  EXPECT_NEAR(z_held, kHousingReachM, 0.006) << "the flange must stay near where the contact was found";
  ASSERT_TRUE(sim.last_contact().has_value());
  EXPECT_EQ(sim.last_contact()->other, "table");

  // Back up: separated, no new contact.
  sim.command_arm(above, 1.0, 3);
  EXPECT_TRUE(run(sim, 20.0, false).empty());
  EXPECT_TRUE(sim.settled(sim.arm()));
  EXPECT_EQ(sim.contact_events(), 1);
  EXPECT_TRUE(sim.contact_monitor().touching().empty());
  std::filesystem::remove_all(dir);
}

// The object has no say in the physics of the check (it counts by its convex hull, here a box):
// a 0.3 x 0.3 x 0.8 m box standing on the platter, its near face at world y = -0.15. The tool
// level (a2 + a3 + a5 = 0) pointing at it along world +y, 0.6 m above the table; a move from the
// flange 0.45 m to 0.15 m from the turntable axis touches the box when the flange face is at
// y = -0.15 - 0.052 = -0.202: "camera_optical / object", once. The rig holds there.
TEST(ContactMonitor, TheCameraDrivenIntoTheObjectIsStoppedAtItsFace) {
  const auto dir = temp_dir("contact_object");
  const std::string stl = (dir / "box.stl").string();
  write_stl_binary(make_box(Eigen::Vector3d(0.3, 0.3, 0.8)), stl);
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  const double object_z = 0.4;  // the box's centre 0.4 m above the platter top: it rests on it
  const Vector6d near = planar(-0.209, 1.8531, 0.0), into = planar(-0.0533, 1.1052, 0.0);
  for (const auto& [q, y] : {std::pair{near, -0.45}, std::pair{into, -0.15}}) {
    const Pose f = flange_in_world(rig, q);
    EXPECT_NEAR(f.translation().x(), 0.0, 1e-9);
    EXPECT_NEAR(f.translation().y(), y, 1e-3);
    EXPECT_NEAR(f.translation().z(), 0.6, 1e-3);
    EXPECT_NEAR(f.linear().col(0).y(), 1.0, 1e-9) << "the tool points along world +y";
  }
  twin::RigSim sim(rig, twin::ObjectPlacement{stl, object_z, 0, 0, {}}, (dir / "model.xml").string());
  EXPECT_EQ(sim.contact_events(), 0);
  sim.command_arm(near, 1.0, 1);
  EXPECT_TRUE(run(sim, 20.0, false).empty()) << "home to 0.45 m from the axis touches nothing";
  ASSERT_TRUE(sim.settled(sim.arm()));

  sim.command_arm(into, 1.0, 2);
  const std::vector<twin::RigContact> found = run(sim, 20.0, true);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].moving, "camera_optical");
  EXPECT_EQ(found[0].other, "object");
  EXPECT_LE(found[0].depth_m, twin::kMaxSweepStepM + 1e-6);
  const double y_found = flange_in_world(rig, sim.arm_position()).translation().y();
  EXPECT_GE(y_found, -0.15 - kHousingReachM - 1e-4);
  EXPECT_LE(y_found, -0.15 - kHousingReachM + 0.004);
  // Held: from 1 s to 3 s after the stop the flange moves less than 0.1 mm (the housing rests on
  // one point of the box's hull and the wrist trembles about it by ~1e-3 rad/s, in place).
  for (int i = 0; i < 500; ++i) sim.step();
  const Eigen::Vector3d at_1s = flange_in_world(rig, sim.arm_position()).translation();
  for (int i = 0; i < 1000; ++i) sim.step();
  EXPECT_EQ(sim.contact_events(), 1);
  EXPECT_LT((flange_in_world(rig, sim.arm_position()).translation() - at_1s).norm(), 1e-4) << "holding still";
  const double y_held = flange_in_world(rig, sim.arm_position()).translation().y();
  std::printf("object: found %.4f mm deep with the flange %.2f mm before the face, held at %.2f mm\n",
              found[0].depth_m * 1e3, (-0.15 - y_found) * 1e3, (-0.15 - y_held) * 1e3);
  EXPECT_NEAR(y_held, -0.15 - kHousingReachM, 0.006);
  std::filesystem::remove_all(dir);
}

// An object too wide for the rig, turned on the turntable, jams against the pedestal: on the UR5e
// rig the pedestal's near face is 0.60 m from the turntable axis (its centre 0.70 m along world
// -y, 0.10 m half-width), its corner (-0.10, -0.60) m 0.608 m from the axis. A box 1.4 x 0.2 m
// along the object's x (at turntable 0 along world x) turned counter-clockwise: the box's points
// 0.608 m from the axis lie within atan(0.1 / 0.6) = 9.5 deg of its -x end (polar 180 deg), so
// the leading ones reach the corner's polar angle, 260.5 deg, when the turntable has turned
// 260.5 - 189.5 = 71 deg. Counted as "object / pedestal"; the rig stops there (the turntable short
// of its 90 deg target), and the arm, standing still, touched nothing.
TEST(ContactMonitor, AnObjectTooWideForTheRigTurnedIntoThePedestalIsStoppedAndCounted) {
  const auto dir = temp_dir("contact_turning");
  const std::string stl = (dir / "slab.stl").string();
  write_stl_binary(make_box(Eigen::Vector3d(1.4, 0.2, 0.3)), stl);
  const RigModel rig = load_rig(model_file_path("rig_ur5e.xml"));
  twin::RigSim sim(rig, twin::ObjectPlacement{stl, 0.15, 0, 0, {}}, (dir / "model.xml").string());
  EXPECT_EQ(sim.contact_events(), 0) << "at turntable 0 the slab lies along world x, clear of the pedestal";
  sim.command_turntable(kPi / 2, 1.0, 1);
  std::vector<twin::RigContact> found;
  const int steps = static_cast<int>(20.0 / sim.model()->opt.timestep);
  for (int i = 0; i < steps && found.empty(); ++i) {
    sim.step();
    for (const twin::RigContact& c : sim.take_contacts()) found.push_back(c);
  }
  ASSERT_EQ(found.size(), 1u) << "no contact in 20 s; the turntable at " << sim.turntable_angle() / kPi * 180 << " deg";
  EXPECT_EQ(found[0].moving, "object");
  EXPECT_EQ(found[0].other, "pedestal");
  const double at_deg = sim.turntable_angle() / kPi * 180;
  std::printf("object / pedestal at turntable %.2f deg (by hand 71.0)\n", at_deg);
  EXPECT_NEAR(at_deg, 71.0, 1.0);
  for (int i = 0; i < 2000; ++i) sim.step();
  EXPECT_LT(sim.turntable_angle() / kPi * 180, 73.0) << "stopped, short of 90 deg";
  EXPECT_EQ(sim.contact_events(), 1);
  std::filesystem::remove_all(dir);
}

// Only the arm against the rest counts: the object resting on the platter (it stands on it) and
// the environment's parts among themselves are no contact; the moving side is the arm's links and
// the camera, the other side every solid geom of the rig plus the object.
TEST(ContactMonitor, TheSidesAreTheArmAndTheRest) {
  const auto dir = temp_dir("contact_sides");
  const std::string stl = (dir / "box.stl").string();
  write_stl_binary(make_box(Eigen::Vector3d(0.2, 0.2, 0.2)), stl);
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  // Sunk 5 mm into the platter: the object against the platter is not counted.
  twin::ObjectPlacement object{stl, 0.095, 0, 0, {}};
  object.calibration_sphere_radius_m = 0.025;
  object.calibration_sphere_offset_m = 0.15;
  twin::RigSim sim(rig, object, (dir / "model.xml").string());
  const mjModel* m = sim.model();
  auto names = [&](const std::vector<int>& geoms) {
    std::set<std::string> out;
    for (int g : geoms) out.insert(mj_id2name(m, mjOBJ_GEOM, g));
    return out;
  };
  EXPECT_EQ(names(sim.contact_monitor().moving_geoms()),
            (std::set<std::string>{"link_1_turret", "link_1_shoulder", "link_2_arm", "link_3_elbow", "link_3_housing",
                                   "link_4_forearm", "link_5_wrist", "link_6_flange", "camera_bracket",
                                   "camera_housing"}));
  // The table's legs, the platter's mark and the keep-out box do not collide in the rig file.
  EXPECT_EQ(names(sim.contact_monitor().other_geoms()),
            (std::set<std::string>{"floor", "table", "turntable_housing", "platter", "pedestal", "arm_base", "object",
                                   "calibration_sphere"}));
  for (int i = 0; i < 100; ++i) sim.step();
  EXPECT_EQ(sim.contact_events(), 0);
  std::filesystem::remove_all(dir);
}

// What the check costs: a full-speed move of a1 by 1 rad from home is swept in states at most
// 2 mm apart: the camera, r from the a1 axis, travels r x 1 rad, so at least r / 2 mm states, and
// in the fastest steps at least r x the ramp's peak speed (1.5 rad / its duration) x 2 ms / 2 mm.
TEST(ContactMonitor, AFullSpeedMoveIsSweptInStepsOfAtMostTwoMillimetres) {
  const auto dir = temp_dir("contact_cost");
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  const Eigen::Vector3d camera = rig.world_T_base.inverse() * camera_in_world(rig, rig.q_home).translation();
  const double r = std::hypot(camera.x(), camera.y());  // from the a1 axis (the base's z)
  twin::RigSim sim(rig, twin::ObjectPlacement{}, (dir / "model.xml").string());
  Vector6d target = rig.q_home;
  target[0] += 1.0;
  sim.command_arm(target, 1.0, 1);
  const twin::ContactCheckCost before = sim.contact_monitor().cost();
  const auto t0 = std::chrono::steady_clock::now();
  int steps = 0;
  int64_t most_per_step = 0;
  for (; steps < 5000 && !sim.settled(sim.arm()); ++steps) {
    const int64_t states = sim.contact_monitor().cost().states;
    sim.step();
    most_per_step = std::max(most_per_step, sim.contact_monitor().cost().states - states);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const twin::ContactCheckCost& after = sim.contact_monitor().cost();
  const int64_t states = after.states - before.states;
  const double check_s = after.seconds - before.seconds;
  std::printf("a1 +1 rad at full speed (camera %.2f m from the axis): %d steps, %lld states checked (at most %lld in one "
              "step), %.1f us per state, %.1f %% of the %.3f s the steps took\n",
              r, steps, static_cast<long long>(states), static_cast<long long>(most_per_step),
              1e6 * check_s / static_cast<double>(std::max<int64_t>(states, 1)), 100 * check_s / wall, wall);
  EXPECT_EQ(sim.contact_events(), 0);
  EXPECT_GE(static_cast<double>(states), r / twin::kMaxSweepStepM);
  const double peak = 1.5 / ramp_duration_s(1.0, rig.qd_max[0], rig.qdd_max[0]);
  EXPECT_GE(static_cast<double>(most_per_step), std::floor(r * peak * sim.model()->opt.timestep / twin::kMaxSweepStepM));
  EXPECT_GE(most_per_step, 2);
  std::filesystem::remove_all(dir);
}
