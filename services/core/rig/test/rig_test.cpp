// Rig model, kinematics and reachability: models/rig_arm.xml (KUKA, analytic IK, and the general
// IK forced), models/rig_ur5e.xml (UR5e, general IK) and models/rig_free.xml.
#include "core/rig/rig.hpp"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>

#include "core/geometry/views.hpp"
#include "core/base/units.hpp"
#include "arm_views.hpp"
#include "file_test_util.hpp"

namespace pbnbv {
namespace {

using testing::cube_keepout;
using testing::file_text;
using testing::kObjectZ;


std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

double hemisphere_radius() { return 0.6 + 0.5 * std::sqrt(3.0) * 0.3; }  // d_c + half diagonal

Vector6d random_q(const RigModel& rig, std::mt19937& rng) {
  Vector6d q;
  for (int i = 0; i < 6; ++i) {
    std::uniform_real_distribution<double> u(rig.q_lower[i], rig.q_upper[i]);
    q[i] = u(rng);
  }
  return q;
}

Pose mj_body_pose(const mjModel* m, const mjData* d, const char* name) {
  const int b = mj_name2id(m, mjOBJ_BODY, name);
  EXPECT_GE(b, 0) << name;
  Pose p = Pose::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.linear()(r, c) = d->xmat[9 * b + 3 * r + c];
    p.translation()[r] = d->xpos[3 * b + r];
  }
  return p;
}

void expect_pose_near(const Pose& a, const Pose& b, double tol, const std::string& what) {
  EXPECT_LT((a.translation() - b.translation()).norm(), tol) << what;
  EXPECT_LT((a.linear() - b.linear()).cwiseAbs().maxCoeff(), tol) << what;
}

// Turntable angle equivalent (mod 2 pi) check.
double angle_diff(double a, double b) { return std::abs(wrap_angle_rad(a - b)); }

class ArmRig : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { rig_ = new RigModel(load_rig(default_rig_path(RigKind::kArm))); }
  static void TearDownTestSuite() {
    delete rig_;
    rig_ = nullptr;
  }
  static RigModel* rig_;
};
RigModel* ArmRig::rig_ = nullptr;

TEST_F(ArmRig, LoadsPublishedParameters) {
  const RigModel& rig = *rig_;
  EXPECT_EQ(rig.kind, RigKind::kArm);
  EXPECT_EQ(rig.arm_name, "KUKA KR 10 R1100 sixx");
  ASSERT_EQ(rig.joint_names.size(), 6u);
  EXPECT_EQ(rig.joint_names[0], "a1");
  EXPECT_EQ(rig.joint_names[5], "a6");
  EXPECT_DOUBLE_EQ(rig.arm.a1, 0.025);
  EXPECT_DOUBLE_EQ(rig.arm.d1, 0.400);
  EXPECT_DOUBLE_EQ(rig.arm.a2, 0.560);
  EXPECT_DOUBLE_EQ(rig.arm.a3, 0.035);
  EXPECT_DOUBLE_EQ(rig.arm.d4, 0.515);
  EXPECT_DOUBLE_EQ(rig.arm.d6, 0.080);
  EXPECT_TRUE(rig.spherical_wrist);
  EXPECT_EQ(rig.ik, IkMethod::kAnalytic);
  EXPECT_NEAR(rig.q_lower[0] * 180 / kPi, -170, 1e-9);
  EXPECT_NEAR(rig.q_upper[1] * 180 / kPi, 45, 1e-9);
  EXPECT_NEAR(rig.q_lower[1] * 180 / kPi, -190, 1e-9);
  EXPECT_NEAR(rig.q_upper[2] * 180 / kPi, 156, 1e-9);
  EXPECT_NEAR(rig.q_upper[5] * 180 / kPi, 350, 1e-9);
  EXPECT_NEAR(rig.qd_max[0] * 180 / kPi, 360, 1e-9);
  EXPECT_NEAR(rig.qd_max[5] * 180 / kPi, 615, 1e-9);
  EXPECT_NEAR(rig.turntable_qd_max * 180 / kPi, 60, 1e-9);
  EXPECT_TRUE(rig.has_turntable);
  // Base on the pedestal at (0, -1.1, 0.6), facing +y (the turntable axis).
  EXPECT_LT((rig.world_T_base.translation() - Eigen::Vector3d(0, -1.1, 0.6)).norm(), 1e-12);
  EXPECT_LT((rig.world_T_base.linear().col(0) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-12);
  EXPECT_NEAR(rig.preferred_azimuth_rad, -kPi / 2, 1e-12);
  // Platter top at z = 0.065 on the axis.
  EXPECT_LT((rig.world_T_turntable.translation() - Eigen::Vector3d(0, 0, 0.065)).norm(), 1e-12);
  // Hand-eye: optical centre 0.05 m along the tool axis, 0.04 m above it; optical z = flange x.
  EXPECT_LT((rig.flange_T_camera.translation() - Eigen::Vector3d(0.05, 0, 0.04)).norm(), 1e-12);
  EXPECT_LT((rig.flange_T_camera.linear().col(2) - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((rig.flange_T_camera.linear().col(1) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
}

TEST_F(ArmRig, ZeroConfigurationByHand) {
  // q = 0: arm stretched along base +x = world +y. Flange in the base frame at
  // (a1 + a2 + d4 + d6, 0, d1 + a3) = (1.18, 0, 0.435) -> world (0, -1.1 + 1.18, 0.6 + 0.435).
  const Pose f = flange_in_world(*rig_, Vector6d::Zero());
  EXPECT_LT((f.translation() - Eigen::Vector3d(0, 0.08, 1.035)).norm(), 1e-12);
  EXPECT_LT((f.linear().col(0) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-12);
  // Camera: 0.05 further along +y, 0.04 up; looking along +y with image down = -z.
  const Pose c = camera_in_world(*rig_, Vector6d::Zero());
  EXPECT_LT((c.translation() - Eigen::Vector3d(0, 0.13, 1.075)).norm(), 1e-12);
  EXPECT_LT((c.linear().col(2) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-12);
  EXPECT_LT((c.linear().col(1) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  // a2 = -90 deg lifts the arm vertical: the A4 offset a3 then points backwards, so the flange
  // is at base (0.025 - 0.035, 0, 0.4 + 0.56 + 0.515 + 0.08) = (-0.01, 0, 1.555).
  Vector6d q = Vector6d::Zero();
  q[1] = -kPi / 2;
  const Pose f2 = rig_->world_T_base.inverse() * flange_in_world(*rig_, q);
  EXPECT_LT((f2.translation() - Eigen::Vector3d(-0.01, 0, 1.555)).norm(), 1e-12);
}

TEST_F(ArmRig, ForwardKinematicsMatchesMuJoCo) {
  char err[1000] = {0};
  mjModel* m = mj_loadXML(rig_->model_path.c_str(), nullptr, err, sizeof(err));
  ASSERT_NE(m, nullptr) << err;
  mjData* d = mj_makeData(m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> tt(-4.0, 4.0);
  const int tadr = m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, "turntable")];
  double worst = 0;
  for (int n = 0; n < 200; ++n) {
    const Vector6d q = random_q(*rig_, rng);
    const double t = tt(rng);
    for (int i = 0; i < 6; ++i) {
      d->qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, rig_->joint_names[i].c_str())]] = q[i];
    }
    d->qpos[tadr] = t;
    mj_kinematics(m, d);
    const Pose f_mj = mj_body_pose(m, d, "flange");
    const Pose c_mj = mj_body_pose(m, d, "camera_optical");
    const Pose o_mj = mj_body_pose(m, d, "object_mount");
    expect_pose_near(flange_in_world(*rig_, q), f_mj, 1e-9, "flange");
    expect_pose_near(camera_in_world(*rig_, q), c_mj, 1e-9, "camera_optical");
    expect_pose_near(object_in_world(*rig_, t, 0.0), o_mj, 1e-9, "object_mount");
    Pose o_lift = o_mj;
    o_lift.translation() += o_mj.linear().col(2) * kObjectZ;
    expect_pose_near(object_in_world(*rig_, t, kObjectZ), o_lift, 1e-9, "object frame");
    // camera_in_object is the composition of the two.
    expect_pose_near(camera_in_object(*rig_, q, t, kObjectZ), o_lift.inverse() * c_mj, 1e-9,
                     "camera_in_object");
    worst = std::max(worst, (camera_in_world(*rig_, q).translation() - c_mj.translation()).norm());
  }
  std::cout << "FK vs mj_kinematics, worst camera position difference: " << worst << " m\n";
  mj_deleteData(d);
  mj_deleteModel(m);
}

TEST_F(ArmRig, InverseKinematicsRoundTrip) {
  std::mt19937 rng(11);
  int with_original = 0;
  double worst_pos = 0, worst_rot = 0;
  for (int n = 0; n < 1000; ++n) {
    const Vector6d q = random_q(*rig_, rng);
    const Pose target = flange_in_world(*rig_, q);
    std::string why;
    const std::vector<Vector6d> sols = inverse_kinematics(*rig_, target, &why);
    ASSERT_FALSE(sols.empty()) << "q = " << q.transpose() << ": " << why;
    bool found_original = false;
    double best_pos = 1e9, best_rot = 1e9;
    for (const Vector6d& s : sols) {
      for (int i = 0; i < 6; ++i) {
        EXPECT_GE(s[i], rig_->q_lower[i] - 1e-9);
        EXPECT_LE(s[i], rig_->q_upper[i] + 1e-9);
      }
      const Pose f = flange_in_world(*rig_, s);
      const double ep = (f.translation() - target.translation()).norm();
      const double er = rotation_angle_rad(f.linear(), target.linear());
      best_pos = std::min(best_pos, ep);
      best_rot = std::min(best_rot, er);
      // Every returned solution is verified.
      EXPECT_LT(ep, 1e-6);
      EXPECT_LT(er, 1e-6);
      bool same = true;
      for (int i = 0; i < 6; ++i) same = same && angle_diff(s[i], q[i]) < 1e-6;
      found_original = found_original || same;
    }
    EXPECT_LT(best_pos, 0.5e-3);
    EXPECT_LT(best_rot, 0.1 * kPi / 180);
    worst_pos = std::max(worst_pos, best_pos);
    worst_rot = std::max(worst_rot, best_rot);
    EXPECT_TRUE(found_original) << "q = " << q.transpose();
    with_original += found_original;
  }
  std::cout << "IK round trip: original among solutions " << with_original
            << "/1000, worst error " << worst_pos << " m, " << worst_rot << " rad\n";
}

TEST_F(ArmRig, InverseKinematicsCountsAndVariants) {
  // A generic pose in front of the arm: 4 arm postures (front/back x elbow) are cut down by
  // the limits, but the wrist flip always pairs up, and a6 (+-350 deg) doubles each solution.
  Vector6d q;
  q << 0.3, -0.9, 1.2, 0.4, 0.8, 0.5;
  const std::vector<Vector6d> sols = inverse_kinematics(*rig_, flange_in_world(*rig_, q));
  ASSERT_GE(sols.size(), 4u);
  int with_a6_shift = 0;
  for (const Vector6d& s : sols) {
    for (const Vector6d& t : sols) {
      if (std::abs(t[5] - s[5] - 2 * kPi) < 1e-9 && (t.head<5>() - s.head<5>()).norm() < 1e-9) {
        ++with_a6_shift;
      }
    }
  }
  EXPECT_GE(with_a6_shift, 2);
}

TEST_F(ArmRig, InverseKinematicsReasons) {
  // 3 m away from everything: out of reach.
  Pose far = Pose::Identity();
  far.translation() = Eigen::Vector3d(3.0, 0, 1.0);
  std::string why;
  EXPECT_TRUE(inverse_kinematics(*rig_, far, &why).empty());
  EXPECT_NE(why.find("reach"), std::string::npos) << why;
  EXPECT_NE(why.find("m from the shoulder"), std::string::npos) << why;
  // Reachable position, but the tool pointing straight back at the arm: flange at base
  // (0.9, 0, 0.435) with x_flange = -x_base puts the wrist centre at (0.98, 0, 0.435), in front
  // of the shoulder, and a5 would have to fold the tool back by ~150 deg (limit 120 deg); the
  // shoulder-back postures need a1 = 180 deg (limit 170 deg).
  Pose back = rig_->world_T_base;
  back.translation() = rig_->world_T_base * Eigen::Vector3d(0.9, 0, 0.435);
  back.linear() = rig_->world_T_base.linear() * Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitZ());
  why.clear();
  EXPECT_TRUE(inverse_kinematics(*rig_, back, &why).empty());
  EXPECT_NE(why.find("solutions violate joint limits (e.g. a"), std::string::npos) << why;
  std::cout << "tool pointing back: " << why << "\n";
}

TEST_F(ArmRig, LinkOneNeverCollidesWithPedestalOrBase) {
  ReachabilityChecker checker(*rig_);
  Vector6d q = rig_->q_home;
  for (int k = 0; k <= 68; ++k) {
    q[0] = rig_->q_lower[0] + (rig_->q_upper[0] - rig_->q_lower[0]) * k / 68.0;
    for (double a2 : {-1.5, -0.8, 0.0}) {
      q[1] = a2;
      for (const std::string& c : checker.collisions(q, 0.3, cube_keepout(), kObjectZ)) {
        EXPECT_EQ(c.find("link_1"), std::string::npos) << c;
      }
    }
  }
  // The lowest the arm gets in front of the pedestal: upper arm 45 deg down (a2's limit),
  // forearm vertical. The flange face is then ~9 mm above the table top and the camera, 0.05 m
  // further down the tool axis, below it: reported as camera / table.
  Vector6d down;
  down << 0, kPi / 4, kPi / 4, 0, 0, 0;
  ASSERT_GT(flange_in_world(*rig_, down).translation().z(), 0.0);
  ASSERT_LT(camera_in_world(*rig_, down).translation().z(), 0.0);
  const auto col = checker.collisions(down, 0.0, cube_keepout(), kObjectZ);
  EXPECT_NE(std::find(col.begin(), col.end(), "camera_optical / table"), col.end());
  for (const std::string& c : col) EXPECT_NE(c.find("/ table"), std::string::npos) << c;
  // Home is collision-free and looks at the object centre (within 1 deg) from ~0.86 m.
  EXPECT_TRUE(checker.collisions(rig_->q_home, 0.0, cube_keepout(), kObjectZ).empty());
  const Pose c = camera_in_object(*rig_, rig_->q_home, 0.0, kObjectZ);
  const Eigen::Vector3d to_centre = -c.translation();
  EXPECT_NEAR(to_centre.norm(), hemisphere_radius(), 0.01);
  EXPECT_LT(std::acos(c.linear().col(2).dot(to_centre.normalized())), kPi / 180);
}

TEST_F(ArmRig, DecompositionReproducesRequestedViews) {
  ReachabilityChecker checker(*rig_);
  const double r = hemisphere_radius();
  std::vector<Pose> views;
  for (double el_deg : {0.0, 15.0, 30.0, 45.0, 60.0, 75.0}) {
    for (const Pose& p : ring_views(8, r, el_deg * kPi / 180, 0.1, Eigen::Vector3d::Zero())) {
      views.push_back(p);
    }
  }
  const std::vector<Pose> hemi = sphere_band_views(60, 6, r, Eigen::Vector3d::Zero(), 0, kPi / 2);
  views.insert(views.end(), hemi.begin(), hemi.end());
  int at_preferred = 0;
  for (const Pose& v : views) {
    const ViewSolution s = checker.solve(v, rig_->q_home, 0.2, cube_keepout(), kObjectZ);
    ASSERT_TRUE(s.reachable) << s.reason;
    const Pose back = camera_in_object(*rig_, s.q, s.turntable_rad, kObjectZ);
    EXPECT_LT((back.translation() - v.translation()).norm(), 1e-6);
    EXPECT_LT(rotation_angle_rad(back.linear(), v.linear()), 1e-6);
    expect_pose_near(s.world_T_camera, camera_in_world(*rig_, s.q), 1e-12, "world_T_camera");
    // Turntable angle: the nearest equivalent to the current angle.
    EXPECT_LE(std::abs(s.turntable_rad - 0.2), kPi + 1e-9);
    // The camera's world azimuth is the preferred one, or one of the tried offsets.
    const Eigen::Vector3d cw = s.world_T_camera.translation();
    if (std::hypot(cw.x(), cw.y()) > 1e-3) {
      const double off_deg =
          wrap_angle_rad(std::atan2(cw.y(), cw.x()) - rig_->preferred_azimuth_rad) * 180 / kPi;
      EXPECT_NEAR(off_deg, 15.0 * std::round(off_deg / 15.0), 1e-6);
      EXPECT_LE(std::abs(off_deg), 90.0 + 1e-6);
      if (std::abs(off_deg) < 1e-6) ++at_preferred;
    }
  }
  // Views from 30 deg elevation up are taken at the preferred azimuth.
  for (double el_deg : {30.0, 45.0, 60.0}) {
    const Pose v = ring_views(1, r, el_deg * kPi / 180, 1.0, Eigen::Vector3d::Zero())[0];
    const ViewSolution s = checker.solve(v, rig_->q_home, 0.0, cube_keepout(), kObjectZ);
    ASSERT_TRUE(s.reachable) << s.reason;
    // Object azimuth of the view is 1.0 rad; turntable = preferred - 1.0.
    EXPECT_LT(angle_diff(s.turntable_rad, -kPi / 2 - 1.0), 1e-12);
    const Eigen::Vector3d cw = s.world_T_camera.translation();
    EXPECT_LT(angle_diff(std::atan2(cw.y(), cw.x()), rig_->preferred_azimuth_rad), 1e-9);
  }
  std::cout << "decomposition: " << at_preferred << "/" << views.size()
            << " views at the preferred azimuth\n";
  EXPECT_GT(at_preferred, static_cast<int>(views.size()) / 2);
}

TEST_F(ArmRig, TopViewKeepsTurntable) {
  ReachabilityChecker checker(*rig_);
  const Pose top = look_at_z_up(Eigen::Vector3d(0, 0, hemisphere_radius()), Eigen::Vector3d::Zero());
  const ViewSolution s = checker.solve(top, rig_->q_home, 0.7, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s.reachable) << s.reason;
  // Straight above the centre there is no azimuth to bring round: the current angle is kept
  // unless that fails, then offsets of 15 deg steps are tried.
  const double off_deg = (s.turntable_rad - 0.7) * 180 / kPi;
  EXPECT_NEAR(off_deg, 15.0 * std::round(off_deg / 15.0), 1e-9);
  const Pose back = camera_in_object(*rig_, s.q, s.turntable_rad, kObjectZ);
  EXPECT_LT((back.translation() - top.translation()).norm(), 1e-6);
  EXPECT_LT(rotation_angle_rad(back.linear(), top.linear()), 1e-6);
}

// The least-turn choice turns the turntable no farther than it must. The first clear angle on the
// grid of 15 deg azimuth offsets (solve_batch, as the view scorer ranks) can stand up to 15 deg past
// the least clear turn; one view's solve (the motion executor's move) bisects that step three times.
// 24 views round the object at 20 deg elevation, from home with the turntable at 0: each solved the
// same way round, no farther, less by whole steps of 15 / 8 deg, clear and reaching its view; one
// step nearer its view is not clear (from there the least turn turns the turntable again).
// kLeastTurnOnGrid (a scan recorded before the narrowing, replayed) solves every view at the grid's
// angle, exactly, as it was moved then.
TEST_F(ArmRig, LeastTurnBisectsTheGridsTurnToWithinAnEighthOfItsStep) {
  ReachabilityChecker checker(*rig_, TurntableChoice::kLeastTurn);
  ReachabilityChecker on_grid(*rig_, TurntableChoice::kLeastTurnOnGrid);
  const std::vector<Pose> views = ring_views(24, hemisphere_radius(), 20 * kPi / 180, 0.0, Eigen::Vector3d::Zero());
  const std::vector<ViewSolution> grid = checker.solve_batch(views, rig_->q_home, 0.0, cube_keepout(), kObjectZ);
  const double step = 15.0 / 8 * kPi / 180;
  int turned = 0, refined = 0;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const ViewSolution s = checker.solve(views[i], rig_->q_home, 0.0, cube_keepout(), kObjectZ);
    ASSERT_EQ(s.reachable, grid[i].reachable) << i;
    const ViewSolution old = on_grid.solve(views[i], rig_->q_home, 0.0, cube_keepout(), kObjectZ);
    ASSERT_EQ(old.reachable, grid[i].reachable) << i;
    if (old.reachable) {
      EXPECT_EQ(old.turntable_rad, grid[i].turntable_rad) << i;
      EXPECT_LT((old.q - grid[i].q).cwiseAbs().maxCoeff(), 1e-12) << i;
    }
    if (!s.reachable) continue;
    const Pose back = camera_in_object(*rig_, s.q, s.turntable_rad, kObjectZ);
    EXPECT_LT((back.translation() - views[i].translation()).norm(), 1e-6) << i;
    EXPECT_TRUE(checker.collisions(s.q, s.turntable_rad, cube_keepout(), kObjectZ).empty()) << i;
    const double g = grid[i].turntable_rad, t = s.turntable_rad;
    if (g == 0.0) {
      EXPECT_EQ(t, 0.0) << i;  // no turn: nothing to refine
      continue;
    }
    ++turned;
    EXPECT_GT(t * g, 0.0) << i;
    EXPECT_LE(std::abs(t), std::abs(g) + 1e-12) << i;
    const double k = (std::abs(g) - std::abs(t)) / step;
    EXPECT_NEAR(k, std::round(k), 1e-9) << i;
    EXPECT_LE(std::round(k), 7.0) << i;
    if (std::round(k) > 0) ++refined;
    if (std::abs(t) > step) {
      const double nearer = t - (t > 0 ? step : -step);
      const ViewSolution again = checker.solve_batch({views[i]}, rig_->q_home, nearer, cube_keepout(), kObjectZ)[0];
      EXPECT_NE(again.turntable_rad, nearer) << i << ": clear " << 180 / kPi * step << " deg nearer";
    }
  }
  std::cout << "least turn: " << refined << " of " << turned << " turned views refined\n";
  EXPECT_GT(turned, 6);
  EXPECT_GT(refined, turned / 2);
}

TEST_F(ArmRig, UnreachableViewsGiveReasons) {
  ReachabilityChecker checker(*rig_);
  // 3 m away: out of reach at every azimuth.
  const Pose far = look_at_z_up(Eigen::Vector3d(3.0, 0, 0.5), Eigen::Vector3d::Zero());
  ViewSolution s = checker.solve(far, rig_->q_home, 0, cube_keepout(), kObjectZ);
  EXPECT_FALSE(s.reachable);
  EXPECT_NE(s.reason.find("reach"), std::string::npos) << s.reason;

  // Inside the keep-out box: a normal hemisphere view, but with a 1.4 m box around the object.
  const Pose hemi = ring_views(1, hemisphere_radius(), 45 * kPi / 180, 0.0, Eigen::Vector3d::Zero())[0];
  const Eigen::AlignedBox3d big(Eigen::Vector3d(-0.7, -0.7, -0.15), Eigen::Vector3d(0.7, 0.7, 1.0));
  s = checker.solve(hemi, rig_->q_home, 0, big, kObjectZ);
  EXPECT_FALSE(s.reachable);
  EXPECT_NE(s.reason.find("/ keepout"), std::string::npos) << s.reason;
  // With the cube-sized box the same view is reachable (the box is what blocks it).
  s = checker.solve(hemi, rig_->q_home, 0, cube_keepout(), kObjectZ);
  EXPECT_TRUE(s.reachable) << s.reason;
  // An empty box (Eigen's default) and a flat one (no volume) are no box: reachable too.
  EXPECT_TRUE(checker.solve(hemi, rig_->q_home, 0, Eigen::AlignedBox3d(), kObjectZ).reachable);
  Eigen::AlignedBox3d flat = big;
  flat.max().z() = flat.min().z();
  EXPECT_TRUE(checker.solve(hemi, rig_->q_home, 0, flat, kObjectZ).reachable);

  // Below the table top: camera 0.75 m from the axis at world z = -0.05 (object frame
  // z = -0.05 - 0.215), looking straight down. With the shoulder 1 m above the table, reaching
  // there needs the upper arm 90 deg down, beyond a2's +45 deg.
  const Eigen::Vector3d eye(0.75, 0, -0.265);
  const Pose below = look_at_z_up(eye, eye - Eigen::Vector3d::UnitZ());
  s = checker.solve(below, rig_->q_home, 0, cube_keepout(), kObjectZ);
  EXPECT_FALSE(s.reachable);
  EXPECT_NE(s.reason.find("violate joint limits (e.g. a2 = "), std::string::npos) << s.reason;
  std::cout << "below the table: " << s.reason << "\n";
}

TEST_F(ArmRig, SolveReturnsTheSolutionNearestTheCurrentOne) {
  ReachabilityChecker checker(*rig_);
  // A view at 50 deg elevation, the image rolled by 1.2 rad about the optical axis.
  Pose v = ring_views(1, hemisphere_radius(), 50 * kPi / 180, 0.4, Eigen::Vector3d::Zero())[0];
  v.linear() = v.linear() * Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const ViewSolution s1 = checker.solve(v, rig_->q_home, 0.0, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s1.reachable) << s1.reason;
  // Starting from that solution, solve returns it unchanged.
  const ViewSolution s2 = checker.solve(v, s1.q, s1.turntable_rad, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s2.reachable);
  EXPECT_LT((s2.q - s1.q).norm(), 1e-12);
  EXPECT_NEAR(s2.turntable_rad, s1.turntable_rad, 1e-12);
  // The same pose with a6 turned by a full revolution is another exact solution (identical
  // geometry): when the robot is there, solve must pick it rather than unwinding a6.
  Vector6d alt = s1.q;
  alt[5] += alt[5] > 0 ? -2 * kPi : 2 * kPi;
  ASSERT_GE(alt[5], rig_->q_lower[5]);
  ASSERT_LE(alt[5], rig_->q_upper[5]);
  const ViewSolution s3 = checker.solve(v, alt, s1.turntable_rad, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s3.reachable);
  EXPECT_LT((s3.q - alt).norm(), 1e-9) << s3.q.transpose() << " vs " << alt.transpose();
  // Turntable: with the current angle 2 pi further on, the same view keeps that winding.
  const ViewSolution s4 =
      checker.solve(v, s1.q, s1.turntable_rad + 2 * kPi, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s4.reachable);
  EXPECT_NEAR(s4.turntable_rad, s1.turntable_rad + 2 * kPi, 1e-9);
}

TEST_F(ArmRig, HemisphereReachableShare) {
  ReachabilityChecker checker(*rig_);
  const std::vector<Pose> views =
      sphere_band_views(800, 24, hemisphere_radius(), Eigen::Vector3d::Zero(), 0, kPi / 2);
  ASSERT_EQ(views.size(), 800u);
  const std::vector<ViewSolution> sols =
      checker.solve_batch(views, rig_->q_home, 0.0, cube_keepout(), kObjectZ);
  ASSERT_EQ(sols.size(), views.size());
  int reachable = 0, at_preferred = 0;
  std::map<std::string, int> reasons;
  for (size_t i = 0; i < sols.size(); ++i) {
    if (!sols[i].reachable) {
      ++reasons[sols[i].reason];
      continue;
    }
    ++reachable;
    const Pose back = camera_in_object(*rig_, sols[i].q, sols[i].turntable_rad, kObjectZ);
    EXPECT_LT((back.translation() - views[i].translation()).norm(), 1e-6);
    const Eigen::Vector3d cw = sols[i].world_T_camera.translation();
    if (angle_diff(std::atan2(cw.y(), cw.x()), rig_->preferred_azimuth_rad) < 1e-6) ++at_preferred;
  }
  const double share = reachable / 800.0;
  std::cout << "hemisphere (800 views, R = " << hemisphere_radius() << " m): reachable "
            << reachable << "/800 = " << share << ", at the preferred azimuth " << at_preferred
            << "\n";
  for (const auto& [r, n] : reasons) std::cout << "  " << n << " x " << r << "\n";
  EXPECT_GE(share, 0.90);

  // A ring at 0..45 deg elevation at that radius is fully reachable.
  for (int el = 0; el <= 45; el += 5) {
    const auto ring = ring_views(36, hemisphere_radius(), el * kPi / 180, 0.0, Eigen::Vector3d::Zero());
    for (const ViewSolution& s : checker.solve_batch(ring, rig_->q_home, 0, cube_keepout(), kObjectZ)) {
      EXPECT_TRUE(s.reachable) << "elevation " << el << ": " << s.reason;
    }
  }
}

TEST(RigLoad, MissingFileNamesPath) {
  const std::string path = "/nonexistent/dir/rig_missing.xml";
  try {
    load_rig(path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(RigLoad, MalformedFileNamesPath) {
  const std::string path = write_temp("rig_malformed.xml", "<mujoco><worldbody><body></mujoco>");
  try {
    load_rig(path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// models/rig_arm.xml with each needle replaced (each must occur), written to a temporary file.
std::string edited_rig(const std::string& file, const std::vector<std::pair<std::string, std::string>>& edits) {
  std::string text = file_text(default_rig_path(RigKind::kArm));
  for (const auto& [needle, with] : edits) {
    const size_t at = text.find(needle);
    EXPECT_NE(at, std::string::npos) << needle;
    if (at != std::string::npos) text.replace(at, needle.size(), with);
  }
  return write_temp(file, text);
}
std::string edited_rig(const std::string& file, const std::string& needle, const std::string& with) {
  return edited_rig(file, {{needle, with}});
}

// load_rig must throw naming the file and containing every one of `fault`.
void expect_load_error(const std::string& path, const std::vector<std::string>& fault) {
  try {
    load_rig(path);
    ADD_FAILURE() << "no exception for " << path;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    for (const std::string& f : fault) EXPECT_NE(what.find(f), std::string::npos) << what;
    std::cout << "load error: " << what << "\n";
  }
}

// `set` holds q: one of its configurations has every joint within 1e-6 rad of q's (angle_diff).
bool holds(const std::vector<Vector6d>& set, const Vector6d& q) {
  return std::any_of(set.begin(), set.end(), [&](const Vector6d& x) {
    for (int i = 0; i < 6; ++i) {
      if (!(angle_diff(x[i], q[i]) < 1e-6)) return false;
    }
    return true;
  });
}

// Round trip of the flange pose at q through inverse_kinematics (reference q_ref): every
// solution within limits and verified; returns whether q itself (up to whole turns) is among them.
// (Same q: every joint within 1e-5 rad; near a singularity, e.g. a stretched elbow, a pose
// error of 1e-12 still leaves joint differences of ~1e-6 rad.)
bool round_trip(const RigModel& rig, const Vector6d& q, const Vector6d& q_ref, double* best_pos,
                double* best_rot) {
  const Pose target = flange_in_world(rig, q);
  std::string why;
  const std::vector<Vector6d> sols = inverse_kinematics(rig, target, &why, q_ref);
  EXPECT_FALSE(sols.empty()) << "q = " << q.transpose() << ": " << why;
  bool found = false;
  *best_pos = *best_rot = 1e9;
  for (const Vector6d& s : sols) {
    for (int i = 0; i < 6; ++i) {
      EXPECT_GE(s[i], rig.q_lower[i] - 1e-9);
      EXPECT_LE(s[i], rig.q_upper[i] + 1e-9);
    }
    const Pose f = flange_in_world(rig, s);
    const double ep = (f.translation() - target.translation()).norm();
    const double er = rotation_angle_rad(f.linear(), target.linear());
    EXPECT_LT(ep, 1e-6);
    EXPECT_LT(er, 1e-6);
    *best_pos = std::min(*best_pos, ep);
    *best_rot = std::min(*best_rot, er);
    bool same = true;
    for (int i = 0; i < 6; ++i) same = same && angle_diff(s[i], q[i]) < 1e-5;
    found = found || same;
  }
  return found;
}

Vector6d near_q(const RigModel& rig, const Vector6d& q, std::mt19937& rng, double spread_rad) {
  std::uniform_real_distribution<double> u(-spread_rad, spread_rad);
  Vector6d r = q;
  for (int i = 0; i < 6; ++i) r[i] = std::clamp(q[i] + u(rng), rig.q_lower[i], rig.q_upper[i]);
  return r;
}

// IK round trip over n random configurations within the limits: every pose solved within
// 0.5 mm / 0.1 deg (all solutions verified to 1e-6); with a reference 0.2 rad away from q (the
// current configuration near the target) q itself found and the returned solution nearest the
// reference; with a zero reference (all solutions searched from spread seeds) the share of q
// found is returned.
double ik_round_trip_test(const RigModel& rig, int n, unsigned seed) {
  std::mt19937 rng(seed);
  double worst_pos = 0, worst_rot = 0;
  int found_zero_ref = 0, tried_zero_ref = 0, nearest_is_q = 0, found_near_ref = 0;
  for (int k = 0; k < n; ++k) {
    const Vector6d q = random_q(rig, rng);
    const Vector6d ref = near_q(rig, q, rng, 0.2);
    double ep = 0, er = 0;
    const bool found = round_trip(rig, q, ref, &ep, &er);
    found_near_ref += found;
    worst_pos = std::max(worst_pos, ep);
    worst_rot = std::max(worst_rot, er);
    // The solution nearest the reference (max joint difference) is q itself, unless q is near
    // a singularity where another solution lies as close (counted).
    const std::vector<Vector6d> sols = inverse_kinematics(rig, flange_in_world(rig, q), nullptr, ref);
    if (!sols.empty()) {
      const auto nearest = std::min_element(sols.begin(), sols.end(), [&](const Vector6d& a, const Vector6d& b) {
        return (a - ref).cwiseAbs().maxCoeff() < (b - ref).cwiseAbs().maxCoeff();
      });
      nearest_is_q += (*nearest - q).cwiseAbs().maxCoeff() < 1e-5;
      // Never farther from the reference than q is.
      if (found) EXPECT_LE((*nearest - ref).cwiseAbs().maxCoeff(), (q - ref).cwiseAbs().maxCoeff() + 1e-5);
    }
    if (k % 5 == 0) {
      ++tried_zero_ref;
      found_zero_ref += round_trip(rig, q, Vector6d::Zero(), &ep, &er);
    }
  }
  EXPECT_LT(worst_pos, 0.5e-3);
  EXPECT_LT(worst_rot, 0.1 * kPi / 180);
  const double share = static_cast<double>(found_zero_ref) / tried_zero_ref;
  const char* method = rig.ik == IkMethod::kAnalytic ? "analytic" : rig.ik == IkMethod::kParallelAxes ? "parallel-axes" : "general";
  std::cout << rig.arm_name << " " << method << " IK round trip over " << n << " poses: worst error " << worst_pos
            << " m, " << worst_rot << " rad; with a reference 0.2 rad away q found in " << found_near_ref << "/" << n
            << ", the solution nearest the reference is q in " << nearest_is_q << "/" << n
            << "; with a zero reference q found in " << found_zero_ref << "/" << tried_zero_ref << "\n";
  // Misses are configurations at a singularity (a wrist at 0 or pi, a stretched elbow), where
  // the seed converges to another solution of the same pose.
  EXPECT_GE(found_near_ref, 0.99 * n);
  EXPECT_GE(nearest_is_q, 0.95 * n);
  return share;
}

// Reachable share of the 800 hemisphere candidates (as the scorer asks), every reachable view
// reproduced by forward kinematics; prints the share and the reasons.
double hemisphere_share(const RigModel& rig, const std::string& what) {
  ReachabilityChecker checker(rig);
  const std::vector<Pose> views =
      sphere_band_views(800, 24, hemisphere_radius(), Eigen::Vector3d::Zero(), 0, kPi / 2);
  const std::vector<ViewSolution> sols = checker.solve_batch(views, rig.q_home, 0.0, cube_keepout(), kObjectZ);
  int reachable = 0;
  std::map<std::string, int> reasons;
  for (size_t i = 0; i < sols.size(); ++i) {
    if (!sols[i].reachable) {
      ++reasons[sols[i].reason];
      continue;
    }
    ++reachable;
    const Pose back = camera_in_object(rig, sols[i].q, sols[i].turntable_rad, kObjectZ);
    EXPECT_LT((back.translation() - views[i].translation()).norm(), 1e-6);
    EXPECT_LT(rotation_angle_rad(back.linear(), views[i].linear()), 1e-6);
    EXPECT_TRUE(checker.collisions(sols[i].q, sols[i].turntable_rad, cube_keepout(), kObjectZ).empty());
  }
  std::cout << what << ": hemisphere reachable " << reachable << "/800\n";
  for (const auto& [r, n] : reasons) std::cout << "  " << n << " x " << r << "\n";
  return reachable / 800.0;
}

TEST_F(ArmRig, GeneralIkSolvesTheKukaToo) {
  RigModel rig = *rig_;
  rig.ik = IkMethod::kGeneral;
  const double share = ik_round_trip_test(rig, 1000, 11);
  EXPECT_GE(share, 0.85);
  // Where the analytic IK finds solutions, the general IK's full search finds them too (up to
  // whole turns) for most poses.
  std::mt19937 rng(13);
  int analytic = 0, general_found = 0;
  for (int k = 0; k < 100; ++k) {
    const Pose target = flange_in_world(*rig_, random_q(*rig_, rng));
    const std::vector<Vector6d> a = inverse_kinematics(*rig_, target);
    const std::vector<Vector6d> g = inverse_kinematics(rig, target);
    for (const Vector6d& x : a) {
      ++analytic;
      general_found += holds(g, x);
    }
  }
  std::cout << "KUKA: the general IK finds " << general_found << " of the analytic IK's " << analytic
            << " solutions\n";
  EXPECT_GE(general_found, 0.8 * analytic);
}

TEST_F(ArmRig, HemisphereReachableShareGeneralIk) {
  RigModel rig = *rig_;
  rig.ik = IkMethod::kGeneral;
  const double analytic = hemisphere_share(*rig_, "KUKA, analytic IK");
  const double general = hemisphere_share(rig, "KUKA, general IK");
  // The general IK stops at the first clear solution from its seeds; it may miss a view only
  // where every solution it finds is blocked: at most 1 % of the analytic share.
  EXPECT_GE(general, analytic - 0.01);
  EXPECT_GE(general, 0.90);
}

// ---------------------------------------------------------------------------------------------
// UR5e rig (parallel-axes IK).

class Ur5eRig : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { rig_ = new RigModel(load_rig(model_file_path("rig_ur5e.xml"))); }
  static void TearDownTestSuite() {
    delete rig_;
    rig_ = nullptr;
  }
  static RigModel* rig_;
};
RigModel* Ur5eRig::rig_ = nullptr;

TEST_F(Ur5eRig, LoadsPublishedParameters) {
  const RigModel& rig = *rig_;
  EXPECT_EQ(rig.kind, RigKind::kArm);
  EXPECT_EQ(rig.arm_name, "Universal Robots UR5e");
  EXPECT_EQ(rig.joint_names, (std::vector<std::string>{"shoulder_pan", "shoulder_lift", "elbow", "wrist_1",
                                                       "wrist_2", "wrist_3"}));
  EXPECT_FALSE(rig.spherical_wrist);
  EXPECT_EQ(rig.ik, IkMethod::kParallelAxes);
  for (int i = 0; i < 6; ++i) {
    const double limit_deg = i == 2 ? 180 : 360;  // elbow narrowed against self-collision
    EXPECT_NEAR(rad_to_deg(rig.q_lower[i]), -limit_deg, 1e-9) << i;
    EXPECT_NEAR(rad_to_deg(rig.q_upper[i]), limit_deg, 1e-9) << i;
    EXPECT_NEAR(rad_to_deg(rig.qd_max[i]), 180, 1e-9) << i;
  }
  // DH lengths as body offsets: d1 up, a2 and a3 along the links, d4, d5, d6 along the wrist axes.
  EXPECT_LT((rig.chain[1].parent_T_body.translation() - Eigen::Vector3d(0, 0, 0.1625)).norm(), 1e-12);
  EXPECT_LT((rig.chain[2].parent_T_body.translation() - Eigen::Vector3d(-0.425, 0, 0)).norm(), 1e-12);
  EXPECT_LT((rig.chain[3].parent_T_body.translation() - Eigen::Vector3d(-0.3922, 0, 0)).norm(), 1e-12);
  EXPECT_LT((rig.chain[4].parent_T_body.translation() - Eigen::Vector3d(0, 0, 0.1333)).norm(), 1e-12);
  EXPECT_LT((rig.chain[5].parent_T_body.translation() - Eigen::Vector3d(0, 0, 0.0997)).norm(), 1e-12);
  EXPECT_LT((rig.last_T_flange.translation() - Eigen::Vector3d(0, 0, 0.0996)).norm(), 1e-12);
  // Same world as the KUKA rig: turntable, hand-eye.
  const RigModel kuka = load_rig(default_rig_path(RigKind::kArm));
  EXPECT_TRUE(rig.world_T_turntable.isApprox(kuka.world_T_turntable, 1e-12));
  EXPECT_TRUE(rig.flange_T_camera.isApprox(kuka.flange_T_camera, 1e-12));
  EXPECT_NEAR(rig.turntable_qd_max, kuka.turntable_qd_max, 1e-12);
  EXPECT_LT((rig.world_T_base.translation() - Eigen::Vector3d(0, -0.7, 0.5)).norm(), 1e-12);
  EXPECT_NEAR(rig.preferred_azimuth_rad, -kPi / 2, 1e-12);
}

TEST_F(Ur5eRig, ZeroConfigurationByHand) {
  // UR's zero: arm stretched along base -x; flange in the base frame at
  // (a2 + a3, -(d4 + d6), d1 - d5) = (-0.8172, -0.2329, 0.0628), tool axis along base -y.
  const Pose f = rig_->world_T_base.inverse() * flange_in_world(*rig_, Vector6d::Zero());
  EXPECT_LT((f.translation() - Eigen::Vector3d(-0.8172, -0.2329, 0.0628)).norm(), 1e-12);
  EXPECT_LT((f.linear().col(0) - Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
  // shoulder_lift -90 deg lifts the arm vertical: (a2 + a3) then points up, d5 along base -x:
  // (-d5, -(d4 + d6), d1 - a2 - a3) = (-0.0997, -0.2329, 0.9797).
  Vector6d q = Vector6d::Zero();
  q[1] = -kPi / 2;
  const Pose f2 = rig_->world_T_base.inverse() * flange_in_world(*rig_, q);
  EXPECT_LT((f2.translation() - Eigen::Vector3d(-0.0997, -0.2329, 0.9797)).norm(), 1e-12);
}

TEST_F(Ur5eRig, ForwardKinematicsMatchesMuJoCo) {
  char err[1000] = {0};
  mjModel* m = mj_loadXML(rig_->model_path.c_str(), nullptr, err, sizeof(err));
  ASSERT_NE(m, nullptr) << err;
  mjData* d = mj_makeData(m);
  std::mt19937 rng(7);
  double worst = 0;
  for (int n = 0; n < 200; ++n) {
    const Vector6d q = random_q(*rig_, rng);
    for (int i = 0; i < 6; ++i) {
      d->qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, rig_->joint_names[i].c_str())]] = q[i];
    }
    mj_kinematics(m, d);
    expect_pose_near(flange_in_world(*rig_, q), mj_body_pose(m, d, "flange"), 1e-9, "flange");
    expect_pose_near(camera_in_world(*rig_, q), mj_body_pose(m, d, "camera_optical"), 1e-9, "camera_optical");
    worst = std::max(worst, (flange_in_world(*rig_, q).translation() - mj_body_pose(m, d, "flange").translation()).norm());
  }
  std::cout << "UR5e FK vs mj_kinematics, worst flange position difference: " << worst << " m\n";
  mj_deleteData(d);
  mj_deleteModel(m);
}

TEST_F(Ur5eRig, InverseKinematicsRoundTrip) {
  // 1,000 random configurations within the limits -> FK -> IK -> FK.
  const double share = ik_round_trip_test(*rig_, 1000, 17);
  EXPECT_GE(share, 0.85);
  // A generic pose has the UR's 8 solutions (shoulder, elbow, wrist each two ways): the full
  // search finds all 8 distinct ones.
  Vector6d q;
  q << 0.4, -1.1, 1.3, -1.5, 1.2, 0.3;
  std::vector<Vector6d> distinct;
  for (const Vector6d& s : inverse_kinematics(*rig_, flange_in_world(*rig_, q))) {
    if (!holds(distinct, s)) distinct.push_back(s);
  }
  EXPECT_EQ(distinct.size(), 8u);
}

TEST_F(Ur5eRig, HomeIsFreeAndLooksAtTheObject) {
  ReachabilityChecker checker(*rig_);
  EXPECT_TRUE(checker.collisions(rig_->q_home, 0.0, cube_keepout(), kObjectZ).empty());
  const Pose c = camera_in_object(*rig_, rig_->q_home, 0.0, kObjectZ);
  const Eigen::Vector3d to_centre = -c.translation();
  EXPECT_NEAR(to_centre.norm(), hemisphere_radius(), 0.01);
  EXPECT_LT(std::acos(std::min(1.0, c.linear().col(2).dot(to_centre.normalized()))), kPi / 180);
  // 60 deg above the object centre.
  EXPECT_NEAR(std::asin(c.translation().z() / c.translation().norm()), kPi / 3, 1e-6);
}

TEST_F(Ur5eRig, HemisphereReachableShare) {
  // Measured 800/800. The floor, 95 %, leaves room for a change of link geometry but not for a
  // solver that loses a band of views (a band of the 24 parallels is >= 4 % of the candidates).
  EXPECT_GE(hemisphere_share(*rig_, "UR5e, parallel-axes IK"), 0.95);
  RigModel general = *rig_;
  general.ik = IkMethod::kGeneral;
  EXPECT_GE(hemisphere_share(general, "UR5e, general IK"), 0.95);
}

TEST_F(Ur5eRig, ParallelAxesIkFindsEverySolutionTheGeneralIkFinds) {
  RigModel general = *rig_;
  general.ik = IkMethod::kGeneral;
  std::mt19937 rng(29);
  int from_general = 0, found = 0, closed_form = 0;
  for (int k = 0; k < 100; ++k) {
    const Pose target = flange_in_world(*rig_, random_q(*rig_, rng));
    const std::vector<Vector6d> p = inverse_kinematics(*rig_, target);
    closed_form += static_cast<int>(p.size());
    for (const Vector6d& x : inverse_kinematics(general, target)) {
      ++from_general;
      found += holds(p, x);
    }
  }
  std::cout << "UR5e over 100 poses: the parallel-axes IK gives " << closed_form << " solutions and holds "
            << found << " of the general IK's " << from_general << "\n";
  EXPECT_EQ(found, from_general);
  EXPECT_GE(closed_form, from_general);
}

TEST_F(Ur5eRig, ParallelAxesIkByHand) {
  // At q = 0 the wrist point (where axes 5 and 6 meet) is at (a2 + a3, -d4, d1 - d5) in the base
  // frame: the zero configuration's flange moved by an offset moves that point by the same offset.
  const RigModel& rig = *rig_;
  const Pose f0 = rig.world_T_base.inverse() * flange_in_world(rig, Vector6d::Zero());
  const Eigen::Vector3d wrist0(-0.8172, -0.1333, 0.1625 - 0.0997);
  const auto flange_with_wrist_at = [&](const Eigen::Vector3d& wrist) {
    Pose f = f0;
    f.translation() += wrist - wrist0;
    return rig.world_T_base * f;
  };
  // The zero configuration itself is among the solutions.
  bool zero = false;
  for (const Vector6d& q : inverse_kinematics(rig, flange_with_wrist_at(wrist0))) zero = zero || q.norm() < 1e-9;
  EXPECT_TRUE(zero);
  // Every plane through the shoulder_pan axis holds the arm 0.1333 m (d4) off it: a wrist 0.05 m
  // from the axis is out of reach.
  std::string why;
  EXPECT_TRUE(inverse_kinematics(rig, flange_with_wrist_at(Eigen::Vector3d(0.05, 0, 0.5)), &why).empty());
  EXPECT_NE(why.find("the wrist (axes 5-6) is 0.050 m from the shoulder_pan axis"), std::string::npos) << why;
  // The stretched arm 1 m further out: its wrist (axes 4-5) 1 m beyond the links' a2 + a3 (the
  // other wrist branch, 2 d5 higher, misses by more).
  why.clear();
  EXPECT_TRUE(inverse_kinematics(rig, flange_with_wrist_at(wrist0 - Eigen::Vector3d(1.0, 0, 0)), &why).empty());
  EXPECT_NE(why.find("the wrist (axes 4-5) is 1.000 m beyond what the shoulder_lift and elbow links reach"),
            std::string::npos) << why;
  // The KUKA's axes 2-4 are not parallel: the method is refused on it, naming the file.
  RigModel kuka = load_rig(default_rig_path(RigKind::kArm));
  kuka.ik = IkMethod::kParallelAxes;
  EXPECT_THROW(inverse_kinematics(kuka, flange_in_world(kuka, kuka.q_home)), std::invalid_argument);
}

TEST(RigLoad, Ur5eMovedOffItsLayoutUsesGeneralIk) {
  // A calibration that tilts the elbow axis by 1 mrad leaves joints 2-4 no longer parallel.
  std::string text = file_text(model_file_path("rig_ur5e.xml"));
  const std::string needle = "<joint name=\"elbow\" class=\"arm\" axis=\"0 0 1\"";
  const size_t at = text.find(needle);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, needle.size(), "<joint name=\"elbow\" class=\"arm\" axis=\"0 0.001 1\"");
  const RigModel rig = load_rig(write_temp("rig_ur5e_tilted.xml", text));
  EXPECT_EQ(rig.ik, IkMethod::kGeneral);
  Vector6d q;
  q << 0.4, -1.1, 1.3, -1.5, 1.2, 0.3;
  double ep = 0, er = 0;
  EXPECT_TRUE(round_trip(rig, q, q, &ep, &er));
}

TEST_F(Ur5eRig, SolveReturnsTheSolutionNearestTheCurrentOne) {
  ReachabilityChecker checker(*rig_);
  Pose v = ring_views(1, hemisphere_radius(), 50 * kPi / 180, 0.4, Eigen::Vector3d::Zero())[0];
  v.linear() = v.linear() * Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const ViewSolution s1 = checker.solve(v, rig_->q_home, 0.0, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s1.reachable) << s1.reason;
  const Pose back = camera_in_object(*rig_, s1.q, s1.turntable_rad, kObjectZ);
  EXPECT_LT((back.translation() - v.translation()).norm(), 1e-6);
  EXPECT_LT(rotation_angle_rad(back.linear(), v.linear()), 1e-6);
  // From that solution, solve returns it unchanged.
  const ViewSolution s2 = checker.solve(v, s1.q, s1.turntable_rad, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s2.reachable);
  EXPECT_LT((s2.q - s1.q).norm(), 1e-9);
  EXPECT_NEAR(s2.turntable_rad, s1.turntable_rad, 1e-12);
  // With wrist_3 a full turn further on (the same geometry), solve keeps that turn.
  Vector6d alt = s1.q;
  alt[5] += alt[5] > 0 ? -2 * kPi : 2 * kPi;
  const ViewSolution s3 = checker.solve(v, alt, s1.turntable_rad, cube_keepout(), kObjectZ);
  ASSERT_TRUE(s3.reachable);
  EXPECT_LT((s3.q - alt).norm(), 1e-9) << s3.q.transpose() << " vs " << alt.transpose();
}

// The quickest move (TurntableChoice::kQuickest) against the least turn, on the UR5e, whose arm
// (180 deg/s) is the slower part of more moves. The camera sees the cube from 50 deg left of the
// arm's side and is asked for the same view 50 deg right, the turntable at 0: the least turn
// leaves the turntable where it stands and swings the shoulder round the object; the quickest
// turns the turntable towards the arm so that the shoulder swings less, and the move is quicker.
// Over 24 views round the cube from there, the quickest move is never slower than the least turn
// (the least turn is the first move it considers), a view it turns differently is strictly
// quicker, and a view whose least turn is the turntable's slower part keeps the least turn.
TEST_F(Ur5eRig, TheQuickestMoveTurnsFurtherWhenTheArmIsTheSlowerPart) {
  ReachabilityChecker least(*rig_, TurntableChoice::kLeastTurn);
  ReachabilityChecker quickest(*rig_, TurntableChoice::kQuickest);
  const double side = 0.55 * std::sin(50 * kPi / 180), front = -0.55 * std::cos(50 * kPi / 180);
  const RigState from{testing::config_seeing_from(*rig_, Eigen::Vector3d(-side, front, 0.2), kObjectZ), 0};
  const Pose right = look_at_z_up(Eigen::Vector3d(side, front, 0.2), Eigen::Vector3d::Zero());
  const ViewSolution l = least.solve(right, from.q, from.turntable_rad, cube_keepout(), kObjectZ);
  const ViewSolution q = quickest.solve(right, from.q, from.turntable_rad, cube_keepout(), kObjectZ);
  ASSERT_TRUE(l.reachable) << l.reason;
  ASSERT_TRUE(q.reachable) << q.reason;
  EXPECT_EQ(l.turntable_rad, 0.0);  // the arm reaches round: no turn
  const double arm_l = arm_move_s(*rig_, from.q, l.q);
  const double arm_q = arm_move_s(*rig_, from.q, q.q), turn_q = turntable_move_s(*rig_, 0.0, q.turntable_rad);
  std::cout << "least turn: 0 deg, arm " << arm_l << " s; quickest: " << rad_to_deg(q.turntable_rad) << " deg ("
            << turn_q << " s), arm " << arm_q << " s\n";
  EXPECT_GT(std::abs(q.turntable_rad), 0.0);
  // The turn's time by hand: the smoothstep ramp's peak speed 1.5 d / T and peak acceleration
  // 6 d / T^2 within 60 deg/s and 240 deg/s^2.
  const double d = std::abs(q.turntable_rad);
  EXPECT_NEAR(turn_q, std::max(1.5 * d / deg_to_rad(60), std::sqrt(6 * d / deg_to_rad(240))), 1e-12);
  EXPECT_LT(arm_q, arm_l);
  EXPECT_LT(std::max(arm_q, turn_q), arm_l);
  EXPECT_DOUBLE_EQ(move_s(*rig_, from, {q.q, q.turntable_rad}), std::max(arm_q, turn_q));
  EXPECT_TRUE(quickest.collisions(q.q, q.turntable_rad, cube_keepout(), kObjectZ).empty());
  const Pose back = camera_in_object(*rig_, q.q, q.turntable_rad, kObjectZ);
  EXPECT_LT((back.translation() - right.translation()).norm(), 1e-6);
  EXPECT_LT(rotation_angle_rad(back.linear(), right.linear()), 1e-6);

  const std::vector<Pose> views = ring_views(24, hemisphere_radius(), 20 * kPi / 180, 0.0, Eigen::Vector3d::Zero());
  int quicker = 0, kept = 0;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const ViewSolution a = least.solve(views[i], from.q, 0.0, cube_keepout(), kObjectZ);
    const ViewSolution b = quickest.solve(views[i], from.q, 0.0, cube_keepout(), kObjectZ);
    ASSERT_EQ(a.reachable, b.reachable) << i;
    if (!a.reachable) continue;
    const double ta = move_s(*rig_, from, {a.q, a.turntable_rad}), tb = move_s(*rig_, from, {b.q, b.turntable_rad});
    EXPECT_LE(tb, ta + 1e-12) << i;
    if (b.turntable_rad != a.turntable_rad) {
      EXPECT_LT(tb, ta) << i;
      ++quicker;
    }
    if (turntable_move_s(*rig_, 0.0, a.turntable_rad) > arm_move_s(*rig_, from.q, a.q)) {
      EXPECT_EQ(b.turntable_rad, a.turntable_rad) << i;
      EXPECT_LT((b.q - a.q).cwiseAbs().maxCoeff(), 1e-12) << i;
      ++kept;
    }
  }
  std::cout << "24 views: " << quicker << " turned otherwise and quicker, " << kept
            << " kept the least turn (the turntable the slower part)\n";
  EXPECT_GT(quicker, 0);
  EXPECT_GT(kept, 0);
}

TEST(RigLoad, ChangedJointAxisUsesGeneralIk) {
  // a2 turned about z instead of y: no longer the spherical-wrist layout, still a 6R chain.
  const std::string path = edited_rig("rig_axis_z.xml", "<joint name=\"a2\" class=\"arm\" axis=\"0 1 0\"",
                                      "<joint name=\"a2\" class=\"arm\" axis=\"0 0 1\"");
  const RigModel rig = load_rig(path);
  EXPECT_FALSE(rig.spherical_wrist);
  EXPECT_EQ(rig.ik, IkMethod::kGeneral);
  EXPECT_LT((rig.chain[1].axis - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  Vector6d q;
  q << 0.3, -0.9, 1.2, 0.4, 0.8, 0.5;
  double ep = 0, er = 0;
  EXPECT_TRUE(round_trip(rig, q, q, &ep, &er));
  // Forcing the analytic IK on it is refused, naming the file.
  RigModel forced = rig;
  forced.ik = IkMethod::kAnalytic;
  EXPECT_THROW(inverse_kinematics(forced, flange_in_world(rig, q)), std::invalid_argument);
}

TEST(RigLoad, NonSphericalWristUsesGeneralIk) {
  const std::string path = edited_rig("rig_offset_wrist.xml", "<body name=\"link_6\" pos=\"0.08 0 0\">",
                                      "<body name=\"link_6\" pos=\"0.08 0.01 0\">");
  const RigModel rig = load_rig(path);
  EXPECT_FALSE(rig.spherical_wrist);
  EXPECT_EQ(rig.ik, IkMethod::kGeneral);
  EXPECT_LT((rig.chain[5].parent_T_body.translation() - Eigen::Vector3d(0.08, 0.01, 0)).norm(), 1e-12);
}

TEST(RigLoad, BadChainsAreNamed) {
  // Five joints: a6 removed.
  expect_load_error(edited_rig("rig_five.xml",
                               {{"<joint name=\"a6\" class=\"wrist\" axis=\"1 0 0\" range=\"-6.1086523819801535 6.1086523819801535\"\n"
                                 "                         damping=\"25\" armature=\"0.1\"/>",
                                 ""},
                                {"<position name=\"a6\" joint=\"a6\" kp=\"1000\" ctrlrange=\"-6.1086523819801535 6.1086523819801535\"/>", ""}}),
                    {"has 5 hinge joints", "a1, a2, a3, a4, a5", "needs 6"});
  // A slide joint on the chain.
  expect_load_error(edited_rig("rig_slide.xml", "<joint name=\"a3\" class=\"arm\" axis=\"0 1 0\"",
                               "<joint name=\"a3\" class=\"arm\" type=\"slide\" axis=\"0 1 0\""),
                    {"joint \"a3\"", "slide joint", "hinge joints only"});
  // No flange body.
  expect_load_error(edited_rig("rig_no_flange.xml", "<body name=\"flange\" pos=\"0 0 0\">",
                               "<body name=\"tool0\" pos=\"0 0 0\">"),
                    {"missing body \"flange\""});
  // A joint without a range.
  expect_load_error(edited_rig("rig_no_range.xml",
                               "<joint name=\"a5\" class=\"wrist\" axis=\"0 1 0\" range=\"-2.0943951023931953 2.0943951023931953\"/>",
                               "<joint name=\"a5\" axis=\"0 1 0\" limited=\"false\"/>"),
                    {"joint \"a5\" has no range"});
}

TEST(RigKindNames, RoundTrip) {
  EXPECT_EQ(to_string(RigKind::kArm), "arm");
  EXPECT_EQ(parse_rig_kind("free"), RigKind::kFree);
  EXPECT_THROW(parse_rig_kind("crane"), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Free rig.

class FreeRig : public ::testing::Test {
 protected:
  void SetUp() override { rig_ = load_rig(default_rig_path(RigKind::kFree)); }
  RigModel rig_;
};

TEST_F(FreeRig, Loads) {
  EXPECT_EQ(rig_.kind, RigKind::kFree);
  EXPECT_FALSE(rig_.has_turntable);
  EXPECT_EQ(rig_.joint_names[4], "gantry_pitch");
  EXPECT_NEAR(rig_.q_upper[4], kPi / 2, 1e-12);
  EXPECT_TRUE(rig_.flange_T_camera.translation().isZero(1e-12));
  EXPECT_LT((rig_.flange_T_camera.linear().col(2) - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  expect_pose_near(object_in_world(rig_, 1.0, 0.2), Pose::Identity(), 1e-15, "object frame");
}

TEST_F(FreeRig, ForwardKinematicsMatchesMuJoCo) {
  char err[1000] = {0};
  mjModel* m = mj_loadXML(rig_.model_path.c_str(), nullptr, err, sizeof(err));
  ASSERT_NE(m, nullptr) << err;
  mjData* d = mj_makeData(m);
  std::mt19937 rng(3);
  for (int n = 0; n < 200; ++n) {
    const Vector6d q = random_q(rig_, rng);
    for (int i = 0; i < 6; ++i) {
      d->qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, rig_.joint_names[i].c_str())]] = q[i];
    }
    mj_kinematics(m, d);
    expect_pose_near(flange_in_world(rig_, q), mj_body_pose(m, d, "flange"), 1e-9, "flange");
    expect_pose_near(camera_in_world(rig_, q), mj_body_pose(m, d, "camera_optical"), 1e-9,
                     "camera");
  }
  mj_deleteData(d);
  mj_deleteModel(m);
}

TEST_F(FreeRig, RoundTripIncludingStraightDown) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(-2.0, 2.0);
  std::vector<Pose> poses;
  for (int n = 0; n < 500; ++n) {
    const Eigen::Vector3d eye(pos(rng), pos(rng), pos(rng));
    const Eigen::Vector3d target(pos(rng), pos(rng), pos(rng));
    if ((eye - target).norm() < 0.1) continue;
    poses.push_back(look_at_z_up(eye, target));
  }
  // Straight down and straight up (pitch = +-pi/2, gimbal lock), and a rolled camera.
  poses.push_back(look_at_z_up(Eigen::Vector3d(0.1, -0.2, 0.86), Eigen::Vector3d(0.1, -0.2, 0)));
  poses.push_back(look_at_z_up(Eigen::Vector3d(0, 0, -0.86), Eigen::Vector3d::Zero()));
  Pose rolled = look_at_z_up(Eigen::Vector3d(0, 0, 0.86), Eigen::Vector3d::Zero());
  rolled.linear() = rolled.linear() * Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ());
  poses.push_back(rolled);
  ReachabilityChecker checker(rig_);
  for (const Pose& cam : poses) {
    const Pose flange = cam * rig_.flange_T_camera.inverse();
    std::string why;
    const auto sols = inverse_kinematics(rig_, flange, &why);
    ASSERT_FALSE(sols.empty()) << why;
    for (const Vector6d& s : sols) {
      const Pose c = camera_in_world(rig_, s);
      EXPECT_LT((c.translation() - cam.translation()).norm(), 1e-9);
      EXPECT_LT((c.linear() - cam.linear()).cwiseAbs().maxCoeff(), 1e-9);
    }
    // solve(): object frame = world, turntable 0, camera pose = request.
    const ViewSolution v = checker.solve(cam, rig_.q_home, 0.0, Eigen::AlignedBox3d(), 0.0);
    ASSERT_TRUE(v.reachable) << v.reason;
    EXPECT_EQ(v.turntable_rad, 0.0);
    EXPECT_LT((v.world_T_camera.translation() - cam.translation()).norm(), 1e-9);
    EXPECT_LT((v.world_T_camera.linear() - cam.linear()).cwiseAbs().maxCoeff(), 1e-9);
  }
  // Straight down: the gimbal case keeps yaw at the current value.
  Vector6d cur = rig_.q_home;
  cur[3] = 0.9;
  const Pose down = look_at_z_up(Eigen::Vector3d(0, 0, 0.86), Eigen::Vector3d::Zero());
  const ViewSolution v = checker.solve(down, cur, 0.0, Eigen::AlignedBox3d(), 0.0);
  ASSERT_TRUE(v.reachable) << v.reason;
  EXPECT_NEAR(v.q[3], 0.9, 1e-9);
  EXPECT_NEAR(v.q[4], kPi / 2, 1e-9);
}

TEST_F(FreeRig, KeepoutAndRange) {
  ReachabilityChecker checker(rig_);
  // The camera inside the keep-out box collides with it.
  const Pose inside = look_at_z_up(Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d::Zero());
  ViewSolution s = checker.solve(inside, rig_.q_home, 0, cube_keepout(), 0);
  EXPECT_FALSE(s.reachable);
  EXPECT_NE(s.reason.find("keepout"), std::string::npos) << s.reason;
  // Outside the slide range (+-3 m).
  const Pose far = look_at_z_up(Eigen::Vector3d(3.5, 0, 0), Eigen::Vector3d::Zero());
  s = checker.solve(far, rig_.q_home, 0, cube_keepout(), 0);
  EXPECT_FALSE(s.reachable);
  EXPECT_NE(s.reason.find("gantry_x"), std::string::npos) << s.reason;
  // The hemisphere is fully reachable.
  const auto views = sphere_band_views(800, 24, hemisphere_radius(), Eigen::Vector3d::Zero(), 0, kPi / 2);
  int ok = 0;
  for (const auto& v : checker.solve_batch(views, rig_.q_home, 0, cube_keepout(), 0)) ok += v.reachable;
  EXPECT_EQ(ok, 800);
}

}  // namespace
}  // namespace pbnbv
