// The motion executor's sequencing with a fake clock and hand-made readings, on the real rig
// model (models/rig_arm.xml, models/rig_free.xml): every answer, the re-send time, the timeout
// reasons, the reached pose and its errors against geometry, and rig faults tied to their command
// by sequence number.
#include "core/acquisition/motion_sequencer.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "arm_views.hpp"
#include "core/base/units.hpp"

namespace pbnbv {
namespace {

using testing::arm_rig;
using testing::free_rig;
using testing::kObjectZ;

constexpr int64_t kFirstSeq = 1;

// A view the arm reaches (the one bad_input_test moves to): 0.75 m out, 0.35 m up.
MoveRequest reachable_request(int64_t id = 1) {
  MoveRequest r;
  r.scan_id = "test";
  r.iteration = 2;
  r.request_id = id;
  r.object_T_camera = look_at_z_up(Eigen::Vector3d(0.75, 0.0, 0.35), Eigen::Vector3d::Zero());
  r.object_z_m = kObjectZ;
  r.keepout = Eigen::AlignedBox3d(Eigen::Vector3d(-0.17, -0.17, -0.15), Eigen::Vector3d::Constant(0.17));
  r.timeout_s = 10.0;
  return r;
}

ArmReading arm_at(const Vector6d& q, int64_t command_seq, RigMode mode, int64_t utime) {
  ArmReading a;
  a.utime = utime;
  a.joint_position_rad = q;
  a.command_seq = command_seq;
  a.mode = mode;
  return a;
}

TurntableReading turntable_at(double angle, int64_t command_seq, RigMode mode, int64_t utime) {
  TurntableReading t;
  t.utime = utime;
  t.angle_rad = angle;
  t.command_seq = command_seq;
  t.mode = mode;
  return t;
}

// A sequencer on the arm rig with fresh readings at home (rig clock 5 s) received at now_s.
class ArmMotion : public ::testing::Test {
 protected:
  ArmMotion() : seq_(arm_rig(), kFirstSeq) { idle_readings(100.0); }

  void idle_readings(double now_s) {
    seq_.on_arm_status(arm_at(arm_rig().q_home, -1, RigMode::kIdle, 5000000), now_s);
    seq_.on_turntable_status(turntable_at(0.0, -1, RigMode::kIdle, 5000000), now_s);
  }

  // Starts reachable_request() at now_s = 100; returns the step (the first commands).
  MotionStep start() {
    MotionStep step = seq_.on_request(reachable_request(), 100.0);
    EXPECT_FALSE(step.result.has_value());
    EXPECT_TRUE(step.arm_command && step.turntable_command);
    if (step.arm_command) {
      arm_target_ = step.arm_command->joint_position_rad;
      turntable_target_ = step.turntable_command->angle_rad;
    }
    return step;
  }

  // Readings at the targets plus offsets, acknowledging command kFirstSeq, received at now_s.
  void readings_at_target(double now_s, int64_t utime, RigMode mode, const Vector6d& dq = Vector6d::Zero(),
                          double dt = 0.0) {
    seq_.on_arm_status(arm_at(arm_target_ + dq, kFirstSeq, mode, utime), now_s);
    seq_.on_turntable_status(turntable_at(turntable_target_ + dt, kFirstSeq, mode, utime), now_s);
  }

  MotionSequencer seq_;
  Vector6d arm_target_ = Vector6d::Zero();
  double turntable_target_ = 0;
};

TEST_F(ArmMotion, CommandsArmAndTurntableWithTheSameNewSequenceNumberAndTheRequestedSpeed) {
  MoveRequest r = reachable_request();
  r.speed_scale = 0.4;
  const MotionStep step = seq_.on_request(r, 100.0);
  ASSERT_TRUE(step.arm_command && step.turntable_command);
  EXPECT_EQ(step.arm_command->seq, kFirstSeq);
  EXPECT_EQ(step.turntable_command->seq, kFirstSeq);
  EXPECT_EQ(step.arm_command->speed_scale, 0.4);
  EXPECT_EQ(step.turntable_command->speed_scale, 0.4);
  // The commanded configuration puts the camera at the requested pose (forward kinematics).
  const Pose at = camera_in_object(arm_rig(), step.arm_command->joint_position_rad, step.turntable_command->angle_rad,
                                   kObjectZ);
  EXPECT_LT((at.translation() - r.object_T_camera.translation()).norm(), 1e-6);
  EXPECT_LT(rotation_angle_rad(at.linear(), r.object_T_camera.linear()), 1e-6);
  EXPECT_TRUE(seq_.moving());
}

TEST_F(ArmMotion, ReachedWhenAcknowledgedWithinToleranceAndSettledWithTheMoveTimes) {
  start();
  // Plan time is real compute time; the commands leave at 100 + plan_s.
  EXPECT_FALSE(seq_.tick(101.0).result);
  // At 102 s: acknowledged and within tolerance but still moving: not yet.
  readings_at_target(102.0, 7000000, RigMode::kMoving);
  EXPECT_FALSE(seq_.tick(102.0).result);
  // At 102.5 s: settled.
  readings_at_target(102.5, 7500000, RigMode::kSettled);
  const MotionStep done = seq_.tick(102.5);
  ASSERT_TRUE(done.result);
  const MoveResult& m = *done.result;
  EXPECT_EQ(m.status, MoveStatus::kReached) << m.reason;
  EXPECT_TRUE(done.keep_result);
  EXPECT_EQ(m.scan_id, "test");
  EXPECT_EQ(m.iteration, 2);
  EXPECT_EQ(m.request_id, 1);
  EXPECT_GE(m.plan_s, 0.0);
  EXPECT_NEAR(m.move_s, 2.0 - m.plan_s, 1e-9);   // from the commands to within tolerance
  EXPECT_NEAR(m.settle_s, 0.5, 1e-9);            // from within tolerance to settled
  EXPECT_NEAR(m.rig_motion_s, 2.5, 1e-9);        // rig clock 5.0 s -> 7.5 s
  EXPECT_EQ(m.settled_utime, 7500000);
  EXPECT_EQ(m.within_tolerance_utime, 7000000);  // rig clock when first within tolerance
  EXPECT_LT(m.position_error_m, 1e-6);
  EXPECT_LT(m.angle_error_rad, 1e-6);
  EXPECT_EQ(m.joint_target_rad, arm_target_);
  EXPECT_EQ(m.joint_position_rad, arm_target_);
  EXPECT_FALSE(seq_.moving());
}

TEST_F(ArmMotion, ReachedPoseIsTheForwardKinematicsOfTheReadings) {
  start();
  // A1 0.8 mrad short of its target (within the 1 mrad tolerance): the camera turns about the
  // A1 axis (world z through the arm base), so it moves a chord 2 r sin(0.4 mrad), r its
  // distance from that axis, and turns by 0.8 mrad.
  Vector6d dq = Vector6d::Zero();
  dq[0] = -0.8e-3;
  readings_at_target(102.0, 7000000, RigMode::kSettled, dq);
  const MotionStep done = seq_.tick(102.0);
  ASSERT_TRUE(done.result);
  const MoveResult& m = *done.result;
  ASSERT_EQ(m.status, MoveStatus::kReached) << m.reason;
  const Eigen::Vector3d c = camera_in_world(arm_rig(), arm_target_).translation() -
                            arm_rig().world_T_base.translation();
  const double r_m = std::hypot(c.x(), c.y());
  EXPECT_NEAR(m.position_error_m, 2 * r_m * std::sin(0.4e-3), 1e-8);
  EXPECT_NEAR(m.angle_error_rad, 0.8e-3, 1e-8);
  const Pose expected = camera_in_object(arm_rig(), arm_target_ + dq, turntable_target_, kObjectZ);
  EXPECT_LT((m.reached_object_T_camera.translation() - expected.translation()).norm(), 1e-12);
  EXPECT_EQ(m.joint_position_rad, arm_target_ + dq);
}

TEST_F(ArmMotion, TurntableOffsetMovesTheReachedPoseAboutTheTurntableAxis) {
  start();
  // The turntable 0.9 mrad past its target: in the object frame the camera turns -0.9 mrad
  // about the object's z axis (the turntable axis): a chord 2 r sin(0.45 mrad).
  readings_at_target(102.0, 7000000, RigMode::kSettled, Vector6d::Zero(), 0.9e-3);
  const MotionStep done = seq_.tick(102.0);
  ASSERT_TRUE(done.result);
  ASSERT_EQ(done.result->status, MoveStatus::kReached) << done.result->reason;
  const double r_m = std::hypot(0.75, 0.0);
  EXPECT_NEAR(done.result->position_error_m, 2 * r_m * std::sin(0.45e-3), 1e-8);
  EXPECT_NEAR(done.result->angle_error_rad, 0.9e-3, 1e-8);
  EXPECT_NEAR(done.result->turntable_angle_rad - done.result->turntable_target_rad, 0.9e-3, 1e-12);
}

TEST_F(ArmMotion, OutsideTheToleranceItIsNotReachedAndTimesOutNamingTheFurthestJoint) {
  start();
  Vector6d dq = Vector6d::Zero();
  dq[1] = 2e-3;    // a2: 2 mrad off
  dq[2] = -0.25;   // a3: 0.25 rad off, the furthest
  dq[4] = 0.1;
  readings_at_target(105.0, 10000000, RigMode::kSettled, dq, 0.003);
  EXPECT_FALSE(seq_.tick(105.0).result);
  // Fresh readings keep arriving; the deadline is 100 + plan_s + 10 s.
  readings_at_target(110.05, 15050000, RigMode::kSettled, dq, 0.003);
  EXPECT_FALSE(seq_.tick(110.0 - 0.001).result);
  const MotionStep done = seq_.tick(110.2);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kTimedOut);
  EXPECT_TRUE(done.keep_result);
  EXPECT_EQ(done.result->reason,
            "not settled after 10 s: joint a3 is 0.25 rad from its target, turntable 0.003 rad from its target")
      << done.result->reason;
}

TEST_F(ArmMotion, ReSendsAnUnacknowledgedCommandEveryHalfSecond) {
  const MotionStep first = start();
  // The status keeps reporting the old command (-1): not acknowledged.
  EXPECT_FALSE(seq_.tick(100.0).arm_command);  // no re-send at once
  idle_readings(100.3);
  EXPECT_FALSE(seq_.tick(100.49).arm_command);  // 0.49 s after (plus the plan time): not yet
  idle_readings(100.6);
  const MotionStep again = seq_.tick(100.6);
  ASSERT_TRUE(again.arm_command && again.turntable_command);
  EXPECT_EQ(again.arm_command->seq, first.arm_command->seq);  // the same command again
  EXPECT_EQ(again.arm_command->joint_position_rad, first.arm_command->joint_position_rad);
  EXPECT_EQ(again.turntable_command->angle_rad, first.turntable_command->angle_rad);
  ASSERT_EQ(again.warnings.size(), 1u);
  EXPECT_NE(again.warnings[0].find("command seq 1"), std::string::npos) << again.warnings[0];
  // The next re-send is 0.5 s after this one.
  EXPECT_FALSE(seq_.tick(101.09).arm_command);
  EXPECT_TRUE(seq_.tick(101.11).arm_command);
  // Once both acknowledge, no more re-sends.
  readings_at_target(101.2, 6200000, RigMode::kMoving, Vector6d::Constant(0.1));
  EXPECT_FALSE(seq_.tick(102.0).arm_command);
}

TEST_F(ArmMotion, ReSendsWhenOnlyTheTurntableHasNotAcknowledged) {
  start();
  seq_.on_arm_status(arm_at(arm_target_, kFirstSeq, RigMode::kSettled, 6000000), 100.4);
  seq_.on_turntable_status(turntable_at(0.0, -1, RigMode::kIdle, 6000000), 100.4);
  const MotionStep again = seq_.tick(100.8);
  EXPECT_TRUE(again.arm_command && again.turntable_command);
  EXPECT_FALSE(again.result);
}

TEST_F(ArmMotion, TimesOutNamingASilentStatus) {
  start();
  // The last readings were received at 100 s; nothing since.
  const MotionStep done = seq_.tick(110.5);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kTimedOut);
  EXPECT_EQ(done.result->reason, "not settled after 10 s: no ARM_STATUS for 10.50 s");
}

TEST_F(ArmMotion, TimesOutNamingASilentTurntable) {
  start();
  seq_.on_arm_status(arm_at(arm_target_, kFirstSeq, RigMode::kSettled, 6000000), 110.3);
  const MotionStep done = seq_.tick(110.5);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->reason, "not settled after 10 s: no TURNTABLE_STATUS for 10.50 s");
}

TEST_F(ArmMotion, TimesOutNamingTheCommandNeverAcknowledged) {
  start();
  idle_readings(110.4);
  const MotionStep done = seq_.tick(110.5);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kTimedOut);
  EXPECT_EQ(done.result->reason, "not settled after 10 s: ARM_STATUS never acknowledged command seq 1");
  // The answer carries the readings: nothing moved, so the reached pose is the home pose's.
  const Pose home = camera_in_object(arm_rig(), arm_rig().q_home, 0.0, kObjectZ);
  EXPECT_LT((done.result->reached_object_T_camera.translation() - home.translation()).norm(), 1e-12);
  EXPECT_NEAR(done.result->move_s, 110.5 - 100.0 - done.result->plan_s, 1e-9);  // never within
  EXPECT_EQ(done.result->settle_s, 0.0);
}

TEST_F(ArmMotion, TimesOutNamingTheTurntableThatNeverAcknowledged) {
  start();
  seq_.on_arm_status(arm_at(arm_target_, kFirstSeq, RigMode::kSettled, 6000000), 110.4);
  seq_.on_turntable_status(turntable_at(0.0, -1, RigMode::kIdle, 6000000), 110.4);
  const MotionStep done = seq_.tick(110.5);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->reason, "not settled after 10 s: TURNTABLE_STATUS never acknowledged command seq 1");
}

TEST_F(ArmMotion, AnotherRequestWhileMovingIsBusyAndTheSameOneIsIgnored) {
  start();
  const MotionStep same = seq_.on_request(reachable_request(1), 100.1);
  EXPECT_FALSE(same.result || same.arm_command);
  const MotionStep other = seq_.on_request(reachable_request(2), 100.1);
  ASSERT_TRUE(other.result);
  EXPECT_EQ(other.result->status, MoveStatus::kBusy);
  EXPECT_EQ(other.result->request_id, 2);
  EXPECT_EQ(other.result->reason, "busy with request 1");
  EXPECT_FALSE(other.keep_result);  // re-sent later, it may be executed
  EXPECT_FALSE(other.arm_command);
}

TEST_F(ArmMotion, UnreachableViewIsAnsweredAtOnceWithTheReason) {
  MoveRequest r = reachable_request();
  r.object_T_camera = look_at_z_up(Eigen::Vector3d(3.0, 0, 0.5), Eigen::Vector3d::Zero());  // 3 m away
  const MotionStep step = seq_.on_request(r, 100.0);
  ASSERT_TRUE(step.result);
  EXPECT_EQ(step.result->status, MoveStatus::kUnreachable);
  EXPECT_NE(step.result->reason.find("reach"), std::string::npos) << step.result->reason;
  EXPECT_TRUE(step.keep_result);
  EXPECT_FALSE(step.arm_command || step.turntable_command);
  EXPECT_FALSE(seq_.moving());
  // Nothing moved: targets and positions are the current readings.
  EXPECT_EQ(step.result->joint_target_rad, arm_rig().q_home);
}

TEST_F(ArmMotion, PlanOnlyAnswersTheTargetsWithoutMoving) {
  MoveRequest r = reachable_request();
  r.plan_only = true;
  const MotionStep step = seq_.on_request(r, 100.0);
  ASSERT_TRUE(step.result);
  EXPECT_EQ(step.result->status, MoveStatus::kPlanned);
  EXPECT_TRUE(step.keep_result);
  EXPECT_FALSE(step.arm_command || step.turntable_command);
  const Pose at = camera_in_object(arm_rig(), step.result->joint_target_rad, step.result->turntable_target_rad, kObjectZ);
  EXPECT_LT((at.translation() - r.object_T_camera.translation()).norm(), 1e-6);
  EXPECT_EQ(step.result->joint_position_rad, arm_rig().q_home);
  // The next request gets the first command sequence number: planning used none.
  EXPECT_EQ(seq_.on_request(reachable_request(2), 100.0).arm_command->seq, kFirstSeq);
}

TEST_F(ArmMotion, WithoutRecentStatusTheRequestIsAnsweredRigSilentAtOnceAndIsNotKept) {
  // Readings received at 100 s; a request at 101.01 s finds them stale (> 1 s).
  const MotionStep step = seq_.on_request(reachable_request(), 101.01);
  ASSERT_TRUE(step.result);
  EXPECT_EQ(step.result->status, MoveStatus::kRigSilent);
  EXPECT_NE(step.result->reason.find("no recent ARM_STATUS/TURNTABLE_STATUS"), std::string::npos);
  EXPECT_FALSE(step.keep_result);
  EXPECT_FALSE(seq_.moving());
  // The turntable alone silent is enough.
  seq_.on_arm_status(arm_at(arm_rig().q_home, -1, RigMode::kIdle, 6000000), 101.5);
  EXPECT_EQ(seq_.on_request(reachable_request(), 101.5).result->status, MoveStatus::kRigSilent);
  // Fresh readings: it moves.
  idle_readings(101.6);
  EXPECT_TRUE(seq_.on_request(reachable_request(), 101.6).arm_command);
}

TEST_F(ArmMotion, RejectedAnswerNamesTheReasonAtTheCurrentReadings) {
  const MoveResult m = seq_.rejected("s", 4, 77, "MOVE_REQUEST speed_scale = 0 is outside [0.001, 1]");
  EXPECT_EQ(m.status, MoveStatus::kRejected);
  EXPECT_EQ(m.scan_id, "s");
  EXPECT_EQ(m.iteration, 4);
  EXPECT_EQ(m.request_id, 77);
  EXPECT_EQ(m.reason, "MOVE_REQUEST speed_scale = 0 is outside [0.001, 1]");
  EXPECT_EQ(m.joint_position_rad, arm_rig().q_home);
}

TEST_F(ArmMotion, ANewMoveUsesTheNextSequenceNumber) {
  start();
  readings_at_target(102.0, 7000000, RigMode::kSettled);
  ASSERT_EQ(seq_.tick(102.0).result->status, MoveStatus::kReached);
  const MotionStep next = seq_.on_request(reachable_request(2), 103.0);
  ASSERT_TRUE(next.arm_command);
  EXPECT_EQ(next.arm_command->seq, kFirstSeq + 1);
  EXPECT_EQ(next.turntable_command->seq, kFirstSeq + 1);
}

// --- rig faults, tied to their command by fault_command_seq ---------------------------------

TEST_F(ArmMotion, ArmRejectingTheCommandEndsTheMoveAsUnreachable) {
  start();
  ArmReading a = arm_at(arm_rig().q_home, -1, RigMode::kFault, 6000000);
  a.fault_code = RigFault::kCommandRejected;
  a.fault_command_seq = kFirstSeq;
  a.fault = "rejected ARM_COMMAND seq 1: joint a3 target nan is not finite";
  seq_.on_arm_status(a, 100.2);
  const MotionStep done = seq_.tick(100.2);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kUnreachable);
  EXPECT_EQ(done.result->reason, "the rig rejected the command: " + a.fault);
  EXPECT_FALSE(done.arm_command);  // no re-send of a refused command
}

TEST_F(ArmMotion, ArmRefusingATargetOutsideItsLimitsEndsTheMoveAsUnreachable) {
  start();
  ArmReading a = arm_at(arm_rig().q_home, -1, RigMode::kFault, 6000000);
  a.fault_code = RigFault::kOutOfLimits;
  a.fault_command_seq = kFirstSeq;
  a.fault = "rejected ARM_COMMAND seq 1: joint a3 target 10 is outside its limits [-2.09, 2.72]";
  seq_.on_arm_status(a, 100.2);
  const MotionStep done = seq_.tick(100.2);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kUnreachable);
  EXPECT_EQ(done.result->reason, "the rig rejected the command: " + a.fault);
}

// A contact stops the arm under the move's command: the move ends with the fault's text, and its
// answer carries the contacts counted since the command (7 - 5 = 2) and the last one's text.
TEST_F(ArmMotion, AContactEndsTheMoveWithTheContactsCountedSinceTheCommand) {
  ArmReading before = arm_at(arm_rig().q_home, -1, RigMode::kIdle, 5000000);
  before.contacts = 5;
  before.last_contact = "link_2 / pedestal, 0.2 mm deep, at rig time 1.000 s, during command 0";
  seq_.on_arm_status(before, 100.0);
  start();
  ArmReading a = arm_at(arm_rig().q_home, kFirstSeq, RigMode::kFault, 6000000);
  a.fault_code = RigFault::kContact;
  a.fault_command_seq = kFirstSeq;
  a.contacts = 7;
  a.last_contact = "camera_optical / object, 1.1 mm deep, at rig time 6.000 s, during command 1";
  a.fault = "contact: " + a.last_contact;
  seq_.on_arm_status(a, 100.2);
  const MotionStep done = seq_.tick(100.2);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kTimedOut);
  EXPECT_EQ(done.result->reason, "the arm driver reported a contact fault on command seq 1: " + a.fault);
  EXPECT_EQ(done.result->contacts, 2);
  EXPECT_EQ(done.result->contact, a.last_contact);
}

// A move reached with no contact counted: 0 and no text; a rig that cannot tell (-1) at the
// command or at the answer: -1.
TEST_F(ArmMotion, AMoveCarriesNoContactOrMinusOneWhenTheRigCannotTell) {
  for (const int32_t at_answer : {3, -1}) {
    SCOPED_TRACE(at_answer);
    ArmReading before = arm_at(arm_rig().q_home, -1, RigMode::kIdle, 5000000);
    before.contacts = 3;
    seq_.on_arm_status(before, 100.0);
    const int64_t command = start().arm_command->seq;  // kFirstSeq, then the next
    ArmReading a = arm_at(arm_target_, command, RigMode::kSettled, 6000000);
    a.contacts = at_answer;
    seq_.on_arm_status(a, 100.5);
    seq_.on_turntable_status(turntable_at(turntable_target_, command, RigMode::kSettled, 6000000), 100.5);
    const MotionStep done = seq_.tick(100.5);
    ASSERT_TRUE(done.result);
    EXPECT_EQ(done.result->status, MoveStatus::kReached);
    EXPECT_EQ(done.result->contacts, at_answer < 0 ? -1 : 0);
    EXPECT_EQ(done.result->contact, "");
  }
}

TEST_F(ArmMotion, TurntableRejectingTheCommandEndsTheMoveAsUnreachable) {
  // Defect: turntable faults were ignored (the move waited for its deadline).
  start();
  seq_.on_arm_status(arm_at(arm_target_, kFirstSeq, RigMode::kSettled, 6000000), 100.2);
  TurntableReading t = turntable_at(0.0, -1, RigMode::kFault, 6000000);
  t.fault_code = RigFault::kCommandRejected;
  t.fault_command_seq = kFirstSeq;
  t.fault = "rejected TURNTABLE_COMMAND seq 1: speed_scale 0 is outside (0, 1]";
  seq_.on_turntable_status(t, 100.2);
  const MotionStep done = seq_.tick(100.2);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kUnreachable);
  EXPECT_EQ(done.result->reason, "the rig rejected the command: " + t.fault);
}

TEST_F(ArmMotion, AFaultAboutAnotherCommandDoesNotEndTheMove) {
  // Defect: the fault was tied to the command by finding "seq 1" in its text, which also
  // matches "seq 15" (here an old command the driver still reports having refused).
  start();
  ArmReading a = arm_at(arm_target_, kFirstSeq, RigMode::kFault, 6000000);
  a.fault_code = RigFault::kCommandRejected;
  a.fault_command_seq = 15;
  a.fault = "rejected ARM_COMMAND seq 15: joint a3 target 10 is outside its limits [-2.09, 2.72]";
  seq_.on_arm_status(a, 100.2);
  seq_.on_turntable_status(turntable_at(turntable_target_, kFirstSeq, RigMode::kSettled, 6000000), 100.2);
  EXPECT_FALSE(seq_.tick(100.2).result);
  // The driver then accepts command 1 and settles: reached.
  readings_at_target(101.0, 7000000, RigMode::kSettled);
  const MotionStep done = seq_.tick(101.0);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kReached) << done.result->reason;
}

TEST_F(ArmMotion, ADriverFaultOnTheCommandEndsTheMoveNamingIt) {
  start();
  readings_at_target(100.5, 5500000, RigMode::kMoving, Vector6d::Constant(0.2));
  ArmReading a = arm_at(arm_target_ + Vector6d::Constant(0.2), kFirstSeq, RigMode::kFault, 5600000);
  a.fault_code = RigFault::kDriver;
  a.fault_command_seq = kFirstSeq;
  a.fault = "following error on a2";
  seq_.on_arm_status(a, 100.6);
  const MotionStep done = seq_.tick(100.6);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kTimedOut);
  EXPECT_EQ(done.result->reason, "the arm driver reported a driver fault on command seq 1: following error on a2");
}

TEST_F(ArmMotion, AFaultTiedToNoCommandIsNamedWhenTheMoveTimesOut) {
  start();
  ArmReading a = arm_at(arm_rig().q_home, kFirstSeq, RigMode::kFault, 6000000);
  a.fault_code = RigFault::kDriver;
  a.fault_command_seq = -1;
  a.fault = "emergency stop pressed";
  seq_.on_arm_status(a, 110.4);
  seq_.on_turntable_status(turntable_at(turntable_target_, kFirstSeq, RigMode::kSettled, 6000000), 110.4);
  EXPECT_FALSE(seq_.tick(110.0).result);
  const MotionStep done = seq_.tick(110.5);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kTimedOut);
  EXPECT_NE(done.result->reason.find("arm not settled; arm fault: emergency stop pressed"), std::string::npos)
      << done.result->reason;
}

// --- the free rig: a gantry, no turntable ------------------------------------------------------

TEST(FreeMotion, NoTurntableCommandAndNoTurntableStatusNeeded) {
  MotionSequencer seq(free_rig(), 40);
  seq.on_arm_status(arm_at(free_rig().q_home, -1, RigMode::kIdle, 1000000), 10.0);
  MoveRequest r = reachable_request();
  r.object_z_m = 0;
  r.keepout = Eigen::AlignedBox3d();
  const MotionStep step = seq.on_request(r, 10.0);
  ASSERT_TRUE(step.arm_command) << (step.result ? step.result->reason : "");
  EXPECT_FALSE(step.turntable_command);
  EXPECT_EQ(step.arm_command->seq, 40);
  seq.on_arm_status(arm_at(step.arm_command->joint_position_rad, 40, RigMode::kSettled, 3000000), 12.0);
  const MotionStep done = seq.tick(12.0);
  ASSERT_TRUE(done.result);
  EXPECT_EQ(done.result->status, MoveStatus::kReached) << done.result->reason;
  EXPECT_LT(done.result->position_error_m, 1e-6);
  EXPECT_NEAR(done.result->rig_motion_s, 2.0, 1e-9);
}

}  // namespace
}  // namespace pbnbv

namespace pbnbv {
namespace {

// STOP mid-move: the arm is told to hold where it is, the turntable to stay at its last reading,
// each with a new sequence number, and the move is answered kRejected naming why.
TEST_F(ArmMotion, HaltHoldsTheRigWhereItIsAndEndsTheMoveInProgress) {
  start();
  const Vector6d halfway = 0.5 * (arm_rig().q_home + arm_target_);
  seq_.on_arm_status(arm_at(halfway, kFirstSeq, RigMode::kMoving, 6000000), 101.0);
  seq_.on_turntable_status(turntable_at(0.25, kFirstSeq, RigMode::kMoving, 6000000), 101.0);
  const MotionStep step = seq_.halt("STOP (operator abort)", 101.0);
  ASSERT_TRUE(step.arm_command && step.turntable_command);
  EXPECT_TRUE(step.arm_command->hold);
  EXPECT_EQ(step.arm_command->joint_position_rad, halfway);
  EXPECT_EQ(step.turntable_command->angle_rad, 0.25);
  EXPECT_GT(step.arm_command->seq, kFirstSeq);
  EXPECT_GT(step.turntable_command->seq, step.arm_command->seq);
  ASSERT_TRUE(step.result);
  EXPECT_EQ(step.result->status, MoveStatus::kRejected);
  EXPECT_EQ(step.result->reason, "halted: STOP (operator abort)");
  EXPECT_FALSE(seq_.moving());
  // Idle, a halt still holds the rig (and answers nothing).
  const MotionStep again = seq_.halt("STOP", 102.0);
  EXPECT_TRUE(again.arm_command && again.arm_command->hold);
  EXPECT_FALSE(again.result);
}

// STOP is latched: the held scan's next move requests (a coordinator that re-sends, a forged
// request) are answered kRejected and move nothing; a request of another scan (a new scan)
// releases the rig and moves. (Before: the next request moved the rig again.)
TEST_F(ArmMotion, StopHoldsTheScanUntilAnotherScanAsks) {
  start();
  seq_.halt("STOP (operator abort)", 101.0, "test");
  ASSERT_NE(seq_.held_scan(), nullptr);
  EXPECT_EQ(*seq_.held_scan(), "test");
  idle_readings(102.0);
  for (int64_t id : {2, 3}) {
    const MotionStep refused = seq_.on_request(reachable_request(id), 102.0);
    ASSERT_TRUE(refused.result);
    EXPECT_EQ(refused.result->status, MoveStatus::kRejected);
    EXPECT_NE(refused.result->reason.find("the rig is held: STOP (operator abort)"), std::string::npos) << refused.result->reason;
    EXPECT_FALSE(refused.arm_command);
    EXPECT_FALSE(refused.turntable_command);
  }
  MoveRequest next = reachable_request(1);
  next.scan_id = "another";
  const MotionStep moved = seq_.on_request(next, 103.0);
  EXPECT_FALSE(moved.result) << moved.result->reason;
  EXPECT_TRUE(moved.arm_command);
  EXPECT_EQ(seq_.held_scan(), nullptr);
}

// STOP for every scan ("") holds the scan of the last request.
TEST_F(ArmMotion, AStopForEveryScanHoldsTheScanInProgress) {
  start();
  seq_.halt("STOP (everyone)", 101.0);
  ASSERT_NE(seq_.held_scan(), nullptr);
  EXPECT_EQ(*seq_.held_scan(), "test");
  idle_readings(102.0);
  const MotionStep refused = seq_.on_request(reachable_request(5), 102.0);
  ASSERT_TRUE(refused.result);
  EXPECT_EQ(refused.result->status, MoveStatus::kRejected);
}


TEST(ArmMotionDetour, ADirectMoveThatCollidesIsDrivenThroughTheDetoursStopsOneCommandEach) {
  const RigModel& rig = arm_rig();
  ReachabilityChecker checker(rig);
  // A tall object (keep-out box 0.3 x 0.3 x 0.5 m); the arm sees its front left corner from 0.55 m
  // at 50 deg left of its base's direction, 0.2 m up, and is asked for the same view on the right.
  // With the least turn the turntable stays (the view lies 50 deg off the preferred azimuth) and
  // the straight move (mostly A1) carries the camera through the box (core/rig's rig_path_test).
  MoveRequest r = reachable_request();
  const double side = 0.55 * std::sin(50 * kPi / 180), front = -0.55 * std::cos(50 * kPi / 180);
  r.object_T_camera = look_at_z_up(Eigen::Vector3d(side, front, 0.2), Eigen::Vector3d::Zero());
  r.keepout = Eigen::AlignedBox3d(Eigen::Vector3d(-0.15, -0.15, -0.15), Eigen::Vector3d(0.15, 0.15, 0.35));
  r.turntable_choice = TurntableChoice::kLeastTurn;
  checker.set_turntable_choice(TurntableChoice::kLeastTurn);
  const RigState from{testing::config_seeing_from(arm_rig(), Eigen::Vector3d(-side, front, 0.2), kObjectZ), 0};
  const ViewSolution sol = checker.solve(r.object_T_camera, from.q, 0, r.keepout, kObjectZ);
  ASSERT_TRUE(sol.reachable) << sol.reason;
  EXPECT_EQ(sol.turntable_rad, 0.0);
  const RigPath path = checker.plan_path(from, {sol.q, sol.turntable_rad}, r.keepout, kObjectZ);
  ASSERT_TRUE(path.clear) << path.reason;
  ASSERT_NE(path.route, "direct") << "the direct move is clear: the test's premise is gone";
  ASSERT_GE(path.stops.size(), 2u);

  MotionSequencer seq(rig, kFirstSeq);
  seq.on_arm_status(arm_at(from.q, -1, RigMode::kIdle, 5000000), 100.0);
  seq.on_turntable_status(turntable_at(0, -1, RigMode::kIdle, 5000000), 100.0);
  MotionStep step = seq.on_request(r, 100.0);
  ASSERT_FALSE(step.result) << step.result->reason;
  double now = 100.0;
  int64_t utime = 5000000;
  for (std::size_t i = 0; i < path.stops.size(); ++i) {
    // Stop i commanded with its own sequence number; the rig acknowledges it and gets there.
    ASSERT_TRUE(step.arm_command && step.turntable_command) << "stop " << i;
    EXPECT_EQ(step.arm_command->seq, kFirstSeq + static_cast<int64_t>(i));
    EXPECT_EQ(step.arm_command->joint_position_rad, path.stops[i].q);
    EXPECT_EQ(step.turntable_command->angle_rad, path.stops[i].turntable_rad);
    const int64_t seq_i = step.arm_command->seq;
    now += 1.0;
    utime += 1000000;
    // On its way (acknowledged, not there): nothing new.
    seq.on_arm_status(arm_at(0.5 * (path.stops[i].q + (i ? path.stops[i - 1].q : from.q)), seq_i, RigMode::kMoving, utime), now);
    seq.on_turntable_status(turntable_at(path.stops[i].turntable_rad, seq_i, RigMode::kMoving, utime), now);
    step = seq.tick(now);
    EXPECT_FALSE(step.arm_command || step.result) << "stop " << i;
    now += 1.0;
    utime += 1000000;
    seq.on_arm_status(arm_at(path.stops[i].q, seq_i, RigMode::kSettled, utime), now);
    seq.on_turntable_status(turntable_at(path.stops[i].turntable_rad, seq_i, RigMode::kSettled, utime), now);
    step = seq.tick(now);
  }
  ASSERT_TRUE(step.result);
  EXPECT_EQ(step.result->status, MoveStatus::kReached) << step.result->reason;
  EXPECT_EQ(step.result->route, path.route);
  EXPECT_NEAR(step.result->path_s, path.time_s, 1e-9);   // at speed scale 1
  EXPECT_NEAR(step.result->rig_motion_s, 2.0 * path.stops.size(), 1e-9);
  EXPECT_EQ(step.result->joint_target_rad, sol.q);
  EXPECT_LT(step.result->position_error_m, 1e-6);
}

TEST(ArmMotionDetour, AViewWithNoCollisionFreePathIsUnreachableNamingEachRoutesContact) {
  const RigModel& rig = arm_rig();
  // Standing with the camera inside the keep-out box (a box grown to take in where the camera
  // stands, as a keep-out box changed under a standing arm would): every way out starts in the box.
  const double side = 0.55 * std::sin(50 * kPi / 180), front = -0.55 * std::cos(50 * kPi / 180);
  const Vector6d q = testing::config_seeing_from(arm_rig(), Eigen::Vector3d(-side, front, 0.2), kObjectZ);
  const Eigen::Vector3d cam = (object_in_world(rig, 0, kObjectZ).inverse() * camera_in_world(rig, q)).translation();
  ASSERT_LT((cam - Eigen::Vector3d(-side, front, 0.2)).norm(), 1e-6);
  MoveRequest r = reachable_request();
  r.keepout = Eigen::AlignedBox3d(Eigen::Vector3d(-0.15, -0.15, -0.15), Eigen::Vector3d(0.15, 0.15, 0.15));
  r.keepout.extend(cam - Eigen::Vector3d::Constant(0.05));
  r.keepout.extend(cam + Eigen::Vector3d::Constant(0.05));
  MotionSequencer seq(rig, kFirstSeq);
  seq.on_arm_status(arm_at(q, -1, RigMode::kIdle, 5000000), 100.0);
  seq.on_turntable_status(turntable_at(0, -1, RigMode::kIdle, 5000000), 100.0);
  const MotionStep step = seq.on_request(r, 100.0);
  ASSERT_TRUE(step.result);
  EXPECT_EQ(step.result->status, MoveStatus::kUnreachable);
  EXPECT_NE(step.result->reason.find("no collision-free path"), std::string::npos) << step.result->reason;
  EXPECT_NE(step.result->reason.find("direct: "), std::string::npos) << step.result->reason;
  EXPECT_NE(step.result->reason.find("via home: "), std::string::npos) << step.result->reason;
  EXPECT_FALSE(step.arm_command);
  EXPECT_FALSE(seq.moving());
}

}  // namespace
}  // namespace pbnbv
