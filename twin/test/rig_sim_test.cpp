// The twin's physics: commanded joints move no faster than their speed limits, all joints of a
// command arrive together, the arm settles on its target under gravity, and a target outside
// a joint's limits is refused with the joint named.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/geometry/mesh.hpp"
#include "core/io/mesh_file.hpp"
#include "core/rig/rig.hpp"
#include "twin/rig_sim.hpp"
#include "core/base/units.hpp"

using namespace pbnbv;

namespace {

std::string model_out() {
  return (std::filesystem::temp_directory_path() / ("rig_sim_test_" + std::to_string(::getpid()) + ".xml")).string();
}

// Steps until the group settles or `limit_s` of rig time passes; returns rig time taken.
// (Counts steps: MuJoCo resets the clock if the simulation ever went unstable.)
double run_until_settled(twin::RigSim& sim, const twin::JointGroup& g, double limit_s,
                         Vector6d* max_speed = nullptr) {
  const double t0 = sim.time_s();
  const int max_steps = static_cast<int>(limit_s / sim.model()->opt.timestep);
  for (int i = 0; i < max_steps; ++i) {
    sim.step();
    if (max_speed) *max_speed = max_speed->cwiseMax(sim.arm_velocity().cwiseAbs());
    if (sim.settled(g)) break;
  }
  return sim.time_s() - t0;
}

}  // namespace

TEST(RigSim, ArmMovesWithinSpeedLimitsArrivesTogetherAndSettles) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out());
  // Move a1 by 0.6 rad and a3 by 0.2 rad: a1 sets the duration, a3 is slowed to arrive with it.
  Vector6d target = rig.q_home;
  target[0] += 0.6;
  target[2] += 0.2;
  sim.command_arm(target, 1.0, 1);
  Vector6d max_speed = Vector6d::Zero();
  const double t = run_until_settled(sim, sim.arm(), 30.0, &max_speed);
  ASSERT_TRUE(sim.settled(sim.arm())) << "not settled after " << t << " s";
  // The smooth ramp's duration is set by a1 (the longer move): by its speed limit (peak speed
  // 1.5 x mean) or its acceleration limit (peak 6 x distance / T^2), whichever is slower.
  const double ramp = ramp_duration_s(0.6, rig.qd_max[0], rig.qdd_max[0]);
  EXPECT_GE(t, ramp) << "arrived faster than a1's limits allow";
  EXPECT_LE(t, ramp + 0.3) << "took far longer than the ramp: the servo lags";
  EXPECT_LE(max_speed[0], rig.qd_max[0] * 1.05);
  EXPECT_NEAR(max_speed[0], 1.5 * 0.6 / ramp, 0.1 * 1.5 * 0.6 / ramp);
  // a3 ramps over the same duration: its peak speed is 1.5 x 0.2 / ramp.
  EXPECT_NEAR(max_speed[2], 1.5 * 0.2 / ramp, 0.15 * 1.5 * 0.2 / ramp);
  EXPECT_LT((sim.arm_position() - target).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(RigSim, HalfSpeedTakesTwiceAsLong) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim full(rig, twin::ObjectPlacement{}, model_out());
  twin::RigSim half(rig, twin::ObjectPlacement{}, model_out());
  Vector6d target = rig.q_home;
  target[0] += 1.0;
  full.command_arm(target, 1.0, 1);
  half.command_arm(target, 0.5, 1);
  const double t_full = run_until_settled(full, full.arm(), 30.0);
  const double t_half = run_until_settled(half, half.arm(), 30.0);
  const double v = rig.qd_max[0], a = rig.qdd_max[0];
  EXPECT_NEAR(t_half - t_full, ramp_duration_s(1.0, v / 2, a / 2) - ramp_duration_s(1.0, v, a), 0.05);
}

// One command turns the turntable at most one full turn from its setpoint: 1e6 rad (eleven days
// of turning at 60 deg/s, which the twin used to start) is refused as out of limits; 2 pi is taken.
TEST(RigSim, OneTurntableCommandTurnsAtMostOneFullTurn) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out());
  EXPECT_THROW(sim.command_turntable(1e6, 1.0, 1), twin::OutOfLimits);
  EXPECT_THROW(sim.command_turntable(-2 * kPi - 0.01, 1.0, 2), twin::OutOfLimits);
  EXPECT_NO_THROW(sim.command_turntable(2 * kPi, 1.0, 3));
}

TEST(RigSim, TurntableTurnsAtItsSpeedLimit) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out());
  ASSERT_TRUE(sim.has_turntable());
  // Half a turn is long enough to be limited by speed, not acceleration: the peak speed is the
  // limit and the ramp takes 1.5 x distance / limit.
  sim.command_turntable(kPi, 1.0, 1);
  const double ramp = ramp_duration_s(kPi, rig.turntable_qd_max, rig.turntable_qdd_max);
  EXPECT_DOUBLE_EQ(ramp, 1.5 * kPi / rig.turntable_qd_max);
  double max_speed = 0;
  const double t0 = sim.time_s();
  while (sim.time_s() - t0 < 30 && !sim.settled(sim.turntable())) {
    sim.step();
    max_speed = std::max(max_speed, std::abs(sim.turntable_velocity()));
  }
  const double t = sim.time_s() - t0;
  EXPECT_GE(t, ramp);
  EXPECT_LE(t, ramp + 0.3);
  EXPECT_LE(max_speed, rig.turntable_qd_max * 1.05);
  EXPECT_GE(max_speed, rig.turntable_qd_max * 0.95);
  EXPECT_NEAR(sim.turntable_angle(), kPi, 1e-4);
}

// Backlash 0.2 deg: turning up to 30 deg the platter stops 0.1 deg short (true 29.9, encoder 30);
// turning back down to 10 deg it stops 0.1 deg above (10.1); a second command in the same
// direction keeps the same side.
TEST(RigSim, TheTurntableStopsHalfItsBacklashShortAgainstItsDirection) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::PoseErrorModel errors;
  errors.turntable_backlash_rad = 0.2 * kPi / 180;
  twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out(), errors);
  const auto turn_to = [&](double deg, long seq) {
    sim.command_turntable(deg * kPi / 180, 1.0, seq);
    for (int i = 0; i < 20000 && !sim.settled(sim.turntable()); ++i) sim.step();
    ASSERT_TRUE(sim.settled(sim.turntable()));
  };
  // The encoder minus the platter: exactly half the backlash; the platter where that puts it
  // (within the 1e-4 rad a settled turntable may still be off its setpoint).
  const auto lag_deg = [&] { return (sim.turntable_angle_reported() - sim.turntable_angle()) * 180 / kPi; };
  turn_to(30, 1);
  EXPECT_NEAR(lag_deg(), 0.1, 1e-9);
  EXPECT_NEAR(sim.turntable_angle() * 180 / kPi, 29.9, 0.006);
  turn_to(10, 2);
  EXPECT_NEAR(lag_deg(), -0.1, 1e-9);
  EXPECT_NEAR(sim.turntable_angle() * 180 / kPi, 10.1, 0.006);
  turn_to(5, 3);
  EXPECT_NEAR(lag_deg(), -0.1, 1e-9);
  EXPECT_NEAR(sim.turntable_angle() * 180 / kPi, 5.1, 0.006);
}

TEST(RigSim, TargetOutsideAJointLimitIsRefusedAndTheArmHolds) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out());
  Vector6d target = rig.q_home;
  target[4] = rig.q_upper[4] + 0.1;
  try {
    sim.command_arm(target, 1.0, 7);
    FAIL() << "a target beyond a5's limit must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(rig.joint_names[4]), std::string::npos) << e.what();
  }
  target = rig.q_home;
  target[1] = std::nan("");
  EXPECT_THROW(sim.command_arm(target, 1.0, 8), std::invalid_argument);
  EXPECT_THROW(sim.command_arm(rig.q_home, 0.0, 9), std::invalid_argument);  // speed scale 0
  for (int i = 0; i < 500; ++i) sim.step();
  EXPECT_LT((sim.arm_position() - rig.q_home).cwiseAbs().maxCoeff(), 1e-4) << "the arm must hold at home";
}

// The free rig teleports through the object (the paper's setup teleports the camera): from 0.8 m
// on -x to 0.8 m on +x through a 0.4 m cube floating at the origin, one step after the command
// its joints are exactly the target (the camera pose is the commanded one to the bit).
TEST(RigSim, TheFreeRigsCameraTeleportsThroughTheObject) {
  const auto dir = std::filesystem::temp_directory_path() / ("rig_sim_free_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string stl = (dir / "cube.stl").string();
  write_stl_binary(make_box(Eigen::Vector3d(0.4, 0.4, 0.4)), stl);
  const RigModel rig = load_rig(default_rig_path(RigKind::kFree));
  twin::RigSim sim(rig, twin::ObjectPlacement{stl, 0.0}, (dir / "model.xml").string());
  // To (-0.8, 0, 0) first (home is above the cube's top), looking along +x at the cube.
  Vector6d start = rig.q_home;
  start[0] = -0.8;
  start[2] = 0.0;
  start[4] = 0.0;
  sim.command_arm(start, 1.0, 1);
  run_until_settled(sim, sim.arm(), 30.0);
  ASSERT_TRUE(sim.settled(sim.arm()));
  Vector6d target = start;
  target[0] = 0.8;
  sim.command_arm(target, 1.0, 2);
  sim.step();
  ASSERT_TRUE(sim.settled(sim.arm()));
  for (int i = 0; i < 6; ++i) EXPECT_EQ(sim.arm_position()[i], target[i]) << "joint " << i;
  for (int k = 0; k < 100; ++k) sim.step();  // and it stays there, to the bit
  for (int i = 0; i < 6; ++i) EXPECT_EQ(sim.arm_position()[i], target[i]) << "joint " << i;
  std::filesystem::remove_all(dir);
}

TEST(RigSim, ObjectIsInsertedAtTheMarkersAndAMissingMarkerIsNamed) {
  const auto dir = std::filesystem::temp_directory_path() / ("rig_sim_obj_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string stl = (dir / "cube.stl").string();
  write_stl_binary(make_box(Eigen::Vector3d(0.2, 0.2, 0.2)), stl);
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim sim(rig, twin::ObjectPlacement{stl, 0.1}, (dir / "model.xml").string());
  const int geom = mj_name2id(sim.model(), mjOBJ_GEOM, "object");
  ASSERT_GE(geom, 0);
  // The cube's centre sits 0.1 m above the turntable top.
  const Pose object = object_in_world(rig, 0.0, 0.1);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sim.data()->geom_xpos[3 * geom + k], object.translation()[k], 1e-9);
  // A rig file without the markers.
  const std::string bad = (dir / "bad.xml").string();
  {
    std::ofstream out(bad);
    out << "<mujoco><worldbody/></mujoco>";
  }
  try {
    twin::compose_model_xml(bad, twin::ObjectPlacement{stl, 0.1});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.xml"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("PBNBV_OBJECT"), std::string::npos);
  }
}

// The composed model names the object's mesh relative to itself: a scan folder copied elsewhere
// (and the original removed) loads in MuJoCo with the object's 12 triangles; a mesh from outside
// the model's folder is copied beside it first.
// A mesh with a colour per vertex (two unit boxes side by side, red and blue) is drawn as one part
// per colour: 12 triangles each, the box's colour, written beside the model, and the composed model
// loads with the whole mesh colliding (group 3) and the parts drawn (group 0) without colliding.
TEST(RigSim, AColouredMeshIsDrawnInItsColours) {
  const auto dir = std::filesystem::temp_directory_path() / ("rig_sim_colour_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  TriangleMesh mesh = make_box(Eigen::Vector3d(0.05, 0.05, 0.05));
  const std::size_t n = mesh.vertices.size();
  TriangleMesh other = make_box(Eigen::Vector3d(0.05, 0.05, 0.05));
  for (auto& v : mesh.vertices) v.x() += 0.025;
  for (auto& v : other.vertices) v.x() -= 0.025;
  mesh.vertices.insert(mesh.vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const auto& t : other.triangles) mesh.triangles.push_back(t + Eigen::Vector3i::Constant(static_cast<int>(n)));
  std::vector<Rgb> colours(n, Rgb{230, 20, 20});
  colours.resize(2 * n, Rgb{20, 20, 230});
  const std::vector<twin::ObjectColourPart> parts = twin::split_by_colour(mesh, colours, dir.string(), "object");
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].triangles, 12u);
  EXPECT_EQ(parts[1].triangles, 12u);
  const auto is = [](const twin::ObjectColourPart& p, double r, double b) {
    return std::abs(p.rgb[0] - r / 255) < 1e-9 && std::abs(p.rgb[2] - b / 255) < 1e-9;
  };
  EXPECT_TRUE((is(parts[0], 230, 20) && is(parts[1], 20, 230)) || (is(parts[0], 20, 230) && is(parts[1], 230, 20)));
  EXPECT_EQ(load_mesh((dir / parts[0].mesh_path).string()).triangles.size(), 12u);
  const std::string stl = (dir / "object.stl").string();
  write_stl_binary(mesh, stl);
  twin::ObjectPlacement placement{stl, 0.1};
  placement.colour_parts = parts;
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim sim(rig, placement, (dir / "model.xml").string());
  const int whole = mj_name2id(sim.model(), mjOBJ_GEOM, "object");
  const int part = mj_name2id(sim.model(), mjOBJ_GEOM, "object_colour_1");
  ASSERT_GE(whole, 0);
  ASSERT_GE(part, 0);
  EXPECT_EQ(sim.model()->geom_group[whole], 3);
  EXPECT_EQ(sim.model()->geom_group[part], 0);
  EXPECT_EQ(sim.model()->geom_contype[part], 0);
  EXPECT_EQ(sim.model()->geom_conaffinity[part], 0);
  EXPECT_THROW(twin::split_by_colour(mesh, {Rgb{1, 2, 3}}, dir.string(), "object"), std::invalid_argument);
  std::filesystem::remove_all(dir);
}

TEST(RigSim, TheModelLoadsFromACopiedFolder) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("rig_sim_copy_" + std::to_string(::getpid()));
  const fs::path scan = root / "scan", moved = root / "elsewhere" / "moved";
  fs::create_directories(scan);
  write_stl_binary(make_box(Eigen::Vector3d(0.2, 0.2, 0.2)), (scan / "object.stl").string());
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  { twin::RigSim sim(rig, twin::ObjectPlacement{(scan / "object.stl").string(), 0.1}, (scan / "twin_model.xml").string()); }
  std::ifstream in(scan / "twin_model.xml");
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(xml.find("file=\"object.stl\""), std::string::npos) << "the mesh is named relative to the model";
  EXPECT_EQ(xml.find(root.string()), std::string::npos) << "no absolute path in the model";
  fs::create_directories(moved.parent_path());
  fs::copy(scan, moved, fs::copy_options::recursive);
  fs::remove_all(scan);
  char error[1000] = "";
  mjModel* m = mj_loadXML((moved / "twin_model.xml").c_str(), nullptr, error, sizeof(error));
  ASSERT_NE(m, nullptr) << error;
  const int mesh = mj_name2id(m, mjOBJ_MESH, "pbnbv_object");
  ASSERT_GE(mesh, 0);
  EXPECT_EQ(m->mesh_facenum[mesh], 12);  // a box: 6 faces of 2 triangles
  mj_deleteModel(m);
  // A mesh from elsewhere: copied beside the model as <model>_object.stl.
  const fs::path other = root / "other";
  fs::create_directories(other);
  { twin::RigSim sim(rig, twin::ObjectPlacement{(moved / "object.stl").string(), 0.1}, (other / "rig.xml").string()); }
  EXPECT_TRUE(fs::exists(other / "rig_object.stl"));
  m = mj_loadXML((other / "rig.xml").c_str(), nullptr, error, sizeof(error));
  EXPECT_NE(m, nullptr) << error;
  if (m) mj_deleteModel(m);
  fs::remove_all(root);
}

TEST(RigSim, TheCalibrationSphereRestsOnTheMarkAndTurnsWithThePlatter) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::ObjectPlacement placement;
  placement.calibration_sphere_radius_m = 0.05;
  placement.calibration_sphere_offset_m = 0.1;
  twin::RigSim sim(rig, placement, model_out());
  const int geom = mj_name2id(sim.model(), mjOBJ_GEOM, "calibration_sphere");
  ASSERT_GE(geom, 0);
  EXPECT_EQ(sim.model()->geom_type[geom], mjGEOM_SPHERE);
  EXPECT_DOUBLE_EQ(sim.model()->geom_size[3 * geom], 0.05);
  // A quarter turn of the platter takes the centre from (0.1, 0, top + 0.05) to (0, 0.1, ...):
  // the platter top is z = 0.065 (models/rig_arm.xml).
  sim.command_turntable(kPi / 2, 1.0, 1);
  for (int i = 0; i < 5000 && !sim.settled(sim.turntable()); ++i) sim.step();
  mj_forward(sim.model(), sim.data());
  const Eigen::Vector3d c(sim.data()->geom_xpos[3 * geom], sim.data()->geom_xpos[3 * geom + 1],
                          sim.data()->geom_xpos[3 * geom + 2]);
  EXPECT_LT((c - Eigen::Vector3d(0, 0.1, 0.065 + 0.05)).norm(), 1e-5);  // settled within 1e-4 rad
  EXPECT_LT((c - object_in_world(rig, sim.turntable_angle_reported(), 0) * Eigen::Vector3d(0.1, 0, 0.05)).norm(), 1e-12);
}

// Moves between views around the hemisphere, each solved by the rig's ReachabilityChecker from
// where the twin's arm is: every move within the speed limits, settled within 0.3 s of its
// ramp, on target; the twin's true camera pose is the model's forward kinematics.
void moves_between_hemisphere_views(const RigModel& rig) {
  twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out());
  ReachabilityChecker checker(rig);
  const Eigen::AlignedBox3d keepout(Eigen::Vector3d(-0.17, -0.17, -0.15), Eigen::Vector3d::Constant(0.17));
  const double radius = 0.6 + std::sqrt(3.0) * 0.15;
  int moves = 0;
  for (double polar_deg : {20.0, 45.0, 70.0, 85.0}) {
    for (double azimuth_deg : {0.0, 130.0, 250.0}) {
      const double p = polar_deg * kPi / 180, a = azimuth_deg * kPi / 180;
      const Eigen::Vector3d eye = radius * Eigen::Vector3d(std::sin(p) * std::cos(a), std::sin(p) * std::sin(a), std::cos(p));
      const ViewSolution sol = checker.solve(look_at_z_up(eye, Eigen::Vector3d::Zero()), sim.arm_position(),
                                             sim.turntable_angle(), keepout, 0.15);
      ASSERT_TRUE(sol.reachable) << sol.reason;
      double ramp = 0;
      for (int j = 0; j < 6; ++j) {
        ramp = std::max(ramp, ramp_duration_s(std::abs(sol.q[j] - sim.arm().setpoint[j]), rig.qd_max[j],
                                                    rig.qdd_max[j]));
      }
      // The same target twice: no motion, no instability.
      if (moves % 4 == 3) sim.command_arm(sim.arm_position(), 1.0, ++moves);
      sim.command_arm(sol.q, 1.0, ++moves);
      Vector6d max_speed = Vector6d::Zero();
      const double t = run_until_settled(sim, sim.arm(), 30.0, &max_speed);
      ASSERT_TRUE(sim.settled(sim.arm())) << "move " << moves << " not settled after " << t << " s";
      EXPECT_LE(t, ramp + 0.3) << "move " << moves;
      for (int j = 0; j < 6; ++j) EXPECT_LE(max_speed[j], rig.qd_max[j] * 1.05) << rig.joint_names[j];
      // On target: the camera is where forward kinematics of the target puts it.
      const Pose reached = camera_in_world(rig, sim.arm_position());
      EXPECT_LT((reached.translation() - camera_in_world(rig, sol.q).translation()).norm(), 1e-3);
      // (MuJoCo's body poses are those of the step's start: the settled arm's residual motion
      // in one 2 ms step, ~1e-6 m, separates them from the joint readings.)
      const Pose truth = sim.true_camera_in_object(0.15);
      const Pose model = camera_in_object(rig, sim.arm_position(), sim.turntable_angle(), 0.15);
      EXPECT_LT((truth.translation() - model.translation()).norm(), 2e-5);
      EXPECT_LT(rotation_angle_rad(truth.linear(), model.linear()), 2e-5);
    }
  }
}

TEST(RigSim, MovesBetweenHemisphereViewsStayWithinLimitsAndSettleQuickly) {
  moves_between_hemisphere_views(load_rig(default_rig_path(RigKind::kArm)));
}

// The twin plays the UR5e rig (models/rig_ur5e.xml, parallel-axes IK) the same way.
TEST(RigSim, PlaysTheUr5eRig) {
  const RigModel rig = load_rig(model_file_path("rig_ur5e.xml"));
  ASSERT_EQ(rig.ik, IkMethod::kParallelAxes);
  {
    twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out());
    EXPECT_LT((sim.arm_position() - rig.q_home).cwiseAbs().maxCoeff(), 1e-12) << "starts at home";
    for (int i = 0; i < 500; ++i) sim.step();
    EXPECT_LT((sim.arm_position() - rig.q_home).cwiseAbs().maxCoeff(), 1e-4) << "holds home under gravity";
  }
  moves_between_hemisphere_views(rig);
}

// A rig at rest is held without physics steps: once a move has settled and every joint is still,
// a step advances the clock by one timestep and leaves every joint exactly where it was; the next
// command wakes it and it moves again at its limits.
TEST(RigSim, ARigAtRestIsHeldWithoutPhysicsAndTheNextCommandWakesIt) {
  const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  twin::RigSim sim(rig, twin::ObjectPlacement{}, model_out());
  Vector6d target = rig.q_home;
  target[0] += 0.3;
  sim.command_arm(target, 1.0, 1);
  EXPECT_FALSE(sim.at_rest());  // a ramp is running
  run_until_settled(sim, sim.arm(), 30.0);
  ASSERT_TRUE(sim.settled(sim.arm()));
  // Settled (within 2 mrad/s) is not yet still (1 urad/s): the servo's last motion dies out.
  const double dt = sim.model()->opt.timestep;
  for (int i = 0; i < static_cast<int>(10.0 / dt) && !sim.at_rest(); ++i) sim.step();
  ASSERT_TRUE(sim.at_rest()) << "still moving after 10 s: " << sim.arm_velocity().transpose();
  const Vector6d held = sim.arm_position();
  const double table = sim.turntable_angle();
  const double t0 = sim.time_s();
  const int64_t rest0 = sim.rest_steps();
  for (int i = 0; i < 1000; ++i) sim.step();
  EXPECT_EQ(sim.rest_steps() - rest0, 1000);
  EXPECT_NEAR(sim.time_s() - t0, 1000 * dt, 1e-9);  // 2 s of rig time
  EXPECT_EQ(sim.arm_position(), held);             // to the bit
  EXPECT_EQ(sim.turntable_angle(), table);
  EXPECT_LT((held - target).cwiseAbs().maxCoeff(), 1e-4);
  // A command wakes it: the turntable's quarter turn takes its ramp at 60 deg/s, as from rest.
  sim.command_turntable(table + kPi / 2, 1.0, 2);
  EXPECT_FALSE(sim.at_rest());
  const double t = run_until_settled(sim, sim.turntable(), 30.0);
  ASSERT_TRUE(sim.settled(sim.turntable()));
  const double ramp = ramp_duration_s(kPi / 2, rig.turntable_qd_max, rig.turntable_qdd_max);
  EXPECT_GE(t, ramp);
  EXPECT_LE(t, ramp + 0.3);
  EXPECT_NEAR(sim.turntable_angle(), table + kPi / 2, 1e-3);
}
