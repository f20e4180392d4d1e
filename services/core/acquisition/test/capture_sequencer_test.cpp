// The camera service's sequencing with a fake clock and hand-made readings and frames, on the
// real arm rig model: the reading chosen for a frame's exposure, the 50 ms rule, the wait for
// readings after the exposure, the retries and the failure message, the not_before rule, and a
// flat depth frame at a known pose giving points on the plane it shows.
#include "core/acquisition/capture_sequencer.hpp"

#include <gtest/gtest.h>

#include "small_camera.hpp"

#include <cmath>

#include "core/base/units.hpp"
#include "arm_views.hpp"

namespace pbnbv {
namespace {

using testing::arm_rig;
using testing::kObjectZ;

constexpr int64_t kFirstTrigger = 500;
constexpr int64_t kExposure = 20000000;  // rig clock, us

CaptureRequest request(int64_t id = 7) {
  CaptureRequest r;
  r.scan_id = "test";
  r.iteration = 3;
  r.request_id = id;
  r.object_z_m = kObjectZ;
  r.ground_clearance_m = 0.004;
  r.voxel_m = 0;
  r.timeout_s = 10;
  return r;
}

using pbnbv::testing::small_camera;

DepthFrame flat_frame(int64_t trigger_seq, int64_t utime, float depth_m) {
  DepthFrame f;
  f.utime = utime;
  f.seq = 90;
  f.trigger_seq = trigger_seq;
  f.intrinsics = small_camera();
  f.range = DepthRange{0.1, 3.0};
  f.depth_m.assign(64 * 48, depth_m);
  return f;
}

ArmReading arm_at(const Vector6d& q, int64_t utime, double speed = 0) {
  ArmReading a;
  a.utime = utime;
  a.joint_position_rad = q;
  a.joint_velocity_rad_s = Vector6d::Constant(speed);
  return a;
}

TurntableReading turntable_at(double angle, int64_t utime, double speed = 0) {
  TurntableReading t;
  t.utime = utime;
  t.angle_rad = angle;
  t.velocity_rad_s = speed;
  return t;
}

Vector6d q_plus(double dq) { return arm_rig().q_home + Vector6d::Constant(dq); }

class Capture : public ::testing::Test {
 protected:
  Capture() : seq_(arm_rig(), kFirstTrigger) {}

  // Queues request(id) and starts it at now_s: the trigger's seq.
  int64_t start(double now_s, const CaptureRequest& r = request()) {
    seq_.on_request(r);
    const CaptureStep step = seq_.tick(now_s);
    EXPECT_TRUE(step.trigger_seq.has_value());
    EXPECT_FALSE(step.result.has_value());
    return step.trigger_seq.value_or(-1);
  }

  CaptureSequencer seq_;
};

TEST_F(Capture, TriggersWithFreshSequenceNumbersOneRequestAtATime) {
  EXPECT_FALSE(seq_.tick(1.0).trigger_seq);  // nothing queued
  seq_.on_request(request(7));
  seq_.on_request(request(7));  // repeated while queued: once
  seq_.on_request(request(8));
  const CaptureStep first = seq_.tick(1.0);
  ASSERT_TRUE(first.trigger_seq);
  EXPECT_EQ(*first.trigger_seq, kFirstTrigger);
  EXPECT_TRUE(seq_.busy());
  seq_.on_request(request(7));  // repeated while in progress: ignored
  EXPECT_FALSE(seq_.tick(1.1).trigger_seq);  // 8 waits for 7
  EXPECT_TRUE(seq_.awaits_frame(kFirstTrigger));
  EXPECT_FALSE(seq_.awaits_frame(kFirstTrigger + 1));
  // A frame for another trigger (a late answer) is not ours.
  EXPECT_FALSE(seq_.on_frame(flat_frame(kFirstTrigger - 1, kExposure, 1.0f), 1.2).result);
  // 7's frame has no readings at its exposure: 1 s later it is triggered again (the statuses may
  // have been lost), and at its 10 s timeout it fails naming that frame; then 8 starts.
  ASSERT_TRUE(seq_.on_frame(flat_frame(kFirstTrigger, kExposure, 1.0f), 1.2).trigger_seq == std::nullopt);
  const CaptureStep again = seq_.tick(2.3);  // 1 s without readings after the exposure
  EXPECT_FALSE(again.result);
  ASSERT_TRUE(again.trigger_seq);
  EXPECT_EQ(*again.trigger_seq, kFirstTrigger + 1);
  ASSERT_EQ(again.warnings.size(), 1u);
  EXPECT_EQ(again.warnings[0], "frame 90 unusable: no ARM_STATUS within 50 ms of the frame's exposure time (none "
                               "received): triggering again");
  const CaptureStep answered = seq_.tick(11.1);  // past 1.0 + 10 s
  ASSERT_TRUE(answered.result);
  EXPECT_EQ(answered.result->request_id, 7);
  EXPECT_NE(answered.result->message.find("(the last: frame 90 unusable: no ARM_STATUS within 50 ms of the frame's "
                                          "exposure time (none received))"),
            std::string::npos)
      << answered.result->message;
  const CaptureStep second = seq_.tick(11.2);
  ASSERT_TRUE(second.trigger_seq);
  EXPECT_GT(*second.trigger_seq, kFirstTrigger + 1);
  EXPECT_FALSE(seq_.tick(11.3).trigger_seq);  // and no third: 7 is not queued twice
}

TEST_F(Capture, UsesTheReadingsNearestTheExposure) {
  const int64_t trigger = start(1.0);
  // Arm readings 30 ms before, 10 ms before, 20 ms after the exposure: the one 10 ms before.
  seq_.on_arm_status(arm_at(q_plus(0.01), kExposure - 30000));
  seq_.on_arm_status(arm_at(q_plus(0.02), kExposure - 10000));
  seq_.on_arm_status(arm_at(q_plus(0.03), kExposure + 20000));
  // Turntable readings 40 ms before, 5 ms after, 45 ms after: the one 5 ms after.
  seq_.on_turntable_status(turntable_at(0.1, kExposure - 40000));
  seq_.on_turntable_status(turntable_at(0.2, kExposure + 5000));
  seq_.on_turntable_status(turntable_at(0.3, kExposure + 45000));
  const CaptureStep step = seq_.on_frame(flat_frame(trigger, kExposure, 1.0f), 1.5);
  ASSERT_TRUE(step.result);  // readings on both sides are in: answered at once
  const CaptureResult& c = *step.result;
  ASSERT_TRUE(c.ok) << c.message;
  EXPECT_EQ(c.joint_position_rad, q_plus(0.02));
  EXPECT_EQ(c.turntable_angle_rad, 0.2);
  const Pose expected = camera_in_object(arm_rig(), q_plus(0.02), 0.2, kObjectZ);
  EXPECT_LT((c.object_T_camera.translation() - expected.translation()).norm(), 1e-12);
  EXPECT_EQ(c.depth_frame_seq, 90);
  EXPECT_EQ(c.depth_frame_utime, kExposure);
  EXPECT_NEAR(c.capture_s, 0.5, 1e-12);  // trigger at 1.0 s, frame at 1.5 s
  EXPECT_EQ(c.scan_id, "test");
  EXPECT_EQ(c.iteration, 3);
  EXPECT_EQ(c.request_id, 7);
  EXPECT_TRUE(step.warnings.empty());
  EXPECT_FALSE(seq_.busy());
}

TEST_F(Capture, AReadingMustBeWithin50MillisecondsOfTheExposure) {
  // Exactly 50 ms from the exposure: used.
  int64_t trigger = start(1.0);
  seq_.on_arm_status(arm_at(q_plus(0.0), kExposure - 50000));
  seq_.on_arm_status(arm_at(q_plus(0.0), kExposure + 50000));
  seq_.on_turntable_status(turntable_at(0, kExposure + 50000));
  CaptureStep step = seq_.on_frame(flat_frame(trigger, kExposure, 1.0f), 1.5);
  ASSERT_TRUE(step.result);
  EXPECT_TRUE(step.result->ok) << step.result->message;

  // 50.001 ms on both sides of the next exposure: no arm reading to place the frame with.
  const int64_t t2 = kExposure + 1000000;
  trigger = start(2.0, request(8));
  seq_.on_arm_status(arm_at(q_plus(0.0), t2 - 50001));
  seq_.on_arm_status(arm_at(q_plus(0.0), t2 + 50001));
  seq_.on_turntable_status(turntable_at(0, t2));
  step = seq_.on_frame(flat_frame(trigger, t2, 1.0f), 2.5);
  EXPECT_FALSE(step.result);  // triggered again
  ASSERT_EQ(step.warnings.size(), 1u);
  EXPECT_EQ(step.warnings[0],
            "frame 90 unusable: no ARM_STATUS within 50 ms of the frame's exposure time (the nearest is 50.001 ms "
            "away): triggering again");
  step = seq_.tick(12.5);  // its timeout: the request fails naming that frame
  ASSERT_TRUE(step.result);
  EXPECT_FALSE(step.result->ok);
  EXPECT_NE(step.result->message.find("the nearest is 50.001 ms away"), std::string::npos) << step.result->message;
  EXPECT_TRUE(step.result->points.empty());

  // The arm is fine but the turntable is 60 ms off.
  const int64_t t3 = t2 + 1000000;
  trigger = start(3.0, request(9));
  seq_.on_arm_status(arm_at(q_plus(0.0), t3));
  seq_.on_turntable_status(turntable_at(0, t3 - 60000));
  seq_.on_turntable_status(turntable_at(0, t3 + 60000));
  step = seq_.on_frame(flat_frame(trigger, t3, 1.0f), 3.5);
  EXPECT_FALSE(step.result);
  ASSERT_EQ(step.warnings.size(), 1u);
  EXPECT_EQ(step.warnings[0],
            "frame 90 unusable: no TURNTABLE_STATUS within 50 ms of the frame's exposure time (the nearest is "
            "60.000 ms away): triggering again");
}

TEST_F(Capture, WaitsUpToOneSecondForReadingsAfterTheExposure) {
  const int64_t trigger = start(1.0);
  seq_.on_arm_status(arm_at(q_plus(0.0), kExposure - 20000));
  seq_.on_turntable_status(turntable_at(0.5, kExposure - 20000));
  EXPECT_FALSE(seq_.on_frame(flat_frame(trigger, kExposure, 1.0f), 1.5).result);
  EXPECT_FALSE(seq_.awaits_frame(trigger));  // the frame is in
  EXPECT_FALSE(seq_.tick(2.0).result);
  // The arm reports after the exposure, the turntable not yet: still waiting.
  seq_.on_arm_status(arm_at(q_plus(0.05), kExposure + 30000));
  EXPECT_FALSE(seq_.tick(2.2).result);
  // 1 s after the frame arrived: answered with the readings there are (the arm's 20 ms before
  // is nearer than its 30 ms after).
  const CaptureStep step = seq_.tick(2.51);
  ASSERT_TRUE(step.result);
  ASSERT_TRUE(step.result->ok) << step.result->message;
  EXPECT_EQ(step.result->joint_position_rad, q_plus(0.0));
  EXPECT_EQ(step.result->turntable_angle_rad, 0.5);
}

TEST_F(Capture, RetriggersEverySecondThenFailsAtTheTimeoutNamingTheTriggers) {
  const int64_t first = start(1.0);
  EXPECT_FALSE(seq_.tick(1.99).trigger_seq);  // a lost frame costs kCaptureRetriggerS = 1 s
  CaptureStep step = seq_.tick(2.0);
  ASSERT_TRUE(step.trigger_seq);
  EXPECT_EQ(*step.trigger_seq, first + 1);
  ASSERT_EQ(step.warnings.size(), 1u);
  EXPECT_EQ(step.warnings[0], "no DEPTH_FRAME for trigger 500 within 1 s: triggering again");
  // Every trigger of the request is answered by its frame, the first one too (a slow camera).
  EXPECT_TRUE(seq_.awaits_frame(first));
  EXPECT_TRUE(seq_.awaits_frame(first + 1));
  EXPECT_FALSE(seq_.awaits_frame(first + 2));
  int triggers = 2;
  for (double t = 3.0; t <= 11.0; t += 1.0) triggers += seq_.tick(t).trigger_seq ? 1 : 0;  // 3 .. 11 s
  EXPECT_EQ(triggers, 11);  // at 1, 2, ..., 11 s
  step = seq_.tick(11.01);  // the request's timeout: 1 + 10 s
  EXPECT_FALSE(step.trigger_seq);
  ASSERT_TRUE(step.result);
  EXPECT_FALSE(step.result->ok);
  EXPECT_EQ(step.result->message,
            "no usable DEPTH_FRAME answered 11 triggers within 10 s: is the camera driver (or the twin) running?");
  EXPECT_NEAR(step.result->capture_s, 10.01, 1e-9);  // from the first trigger
  EXPECT_EQ(step.result->request_id, 7);
  EXPECT_FALSE(seq_.busy());
}

TEST_F(Capture, AFrameAnsweringAnEarlierTriggerOfTheRequestIsTaken) {
  const int64_t first = start(1.0);
  ASSERT_TRUE(seq_.tick(2.0).trigger_seq);  // triggered again: the camera is slower than 1 s
  seq_.on_arm_status(arm_at(q_plus(0.0), kExposure + 10000));
  seq_.on_turntable_status(turntable_at(0.0, kExposure + 10000));
  const CaptureStep step = seq_.on_frame(flat_frame(first, kExposure, 0.5f), 2.5);
  ASSERT_TRUE(step.result) << "the first trigger's frame was not taken";
  EXPECT_TRUE(step.result->ok) << step.result->message;
  EXPECT_FALSE(seq_.awaits_frame(first + 1));  // the request is answered: later frames are not its
}

TEST_F(Capture, AFrameExposedBeforeNotBeforeIsTriggeredAgain) {
  CaptureRequest r = request();
  r.not_before_utime = kExposure;
  const int64_t first = start(1.0, r);
  seq_.on_arm_status(arm_at(q_plus(0.0), kExposure + 10000));
  seq_.on_turntable_status(turntable_at(0, kExposure + 10000));
  // Exposed 1 us too early: a new trigger (the request's deadline stays).
  CaptureStep step = seq_.on_frame(flat_frame(first, kExposure - 1, 1.0f), 1.5);
  EXPECT_FALSE(step.result);
  ASSERT_TRUE(step.trigger_seq);
  EXPECT_EQ(*step.trigger_seq, first + 1);
  ASSERT_EQ(step.warnings.size(), 1u);
  EXPECT_NE(step.warnings[0].find("before the rig settled"), std::string::npos) << step.warnings[0];
  EXPECT_FALSE(seq_.tick(2.4).trigger_seq);  // the next one 1 s after this trigger at 1.5 s
  // Exposed exactly at not_before: taken; the capture time counts from the second trigger.
  step = seq_.on_frame(flat_frame(first + 1, kExposure, 1.0f), 2.0);
  ASSERT_TRUE(step.result);
  EXPECT_TRUE(step.result->ok) << step.result->message;
  EXPECT_NEAR(step.result->capture_s, 0.5, 1e-12);
}

TEST_F(Capture, WarnsWhenTheRigWasMovingAtExposure) {
  const int64_t trigger = start(1.0);
  seq_.on_arm_status(arm_at(q_plus(0.0), kExposure, 0.02));  // 0.02 rad/s > 0.01
  seq_.on_turntable_status(turntable_at(0, kExposure));
  const CaptureStep step = seq_.on_frame(flat_frame(trigger, kExposure, 1.0f), 1.5);
  ASSERT_TRUE(step.result);
  EXPECT_TRUE(step.result->ok);
  ASSERT_EQ(step.warnings.size(), 1u);
  EXPECT_EQ(step.warnings[0],
            "the rig was moving at exposure (joint speed 0.020, turntable 0.000 rad/s): the pose may be blurred");
}

TEST_F(Capture, AnUnusableFrameFailsTheRequestNamingIt) {
  const int64_t trigger = start(1.0);
  EXPECT_FALSE(seq_.on_unusable_frame(91, trigger + 1, "depth_unit_m = 0", 1.5).result);  // not ours
  const CaptureStep step = seq_.on_unusable_frame(91, trigger, "DEPTH_FRAME depth_unit_m = 0 is not positive", 1.5);
  ASSERT_TRUE(step.result);
  EXPECT_FALSE(step.result->ok);
  EXPECT_EQ(step.result->message, "frame 91 unusable: DEPTH_FRAME depth_unit_m = 0 is not positive");
  EXPECT_NEAR(step.result->capture_s, 0.5, 1e-12);
  EXPECT_FALSE(seq_.busy());
}

// The arm and turntable placed for the view 0.75 m out and 0.35 m up looking at the object
// origin; a flat frame at depth |eye| shows the plane through the origin facing the camera.
class FlatFrame : public Capture {
 protected:
  void SetUp() override {
    ReachabilityChecker checker(arm_rig());
    const ViewSolution s = checker.solve(view_, arm_rig().q_home, 0, Eigen::AlignedBox3d(), kObjectZ);
    ASSERT_TRUE(s.reachable) << s.reason;
    q_ = s.q;
    turntable_ = s.turntable_rad;
  }

  // One capture, exposed at a time of its own (request id seconds after kExposure).
  CaptureResult capture(double turntable_offset_rad, const CaptureRequest& r = request()) {
    const int64_t exposure = kExposure + r.request_id * 1000000;
    const int64_t trigger = start(1.0, r);
    seq_.on_arm_status(arm_at(q_, exposure));
    seq_.on_turntable_status(turntable_at(turntable_ + turntable_offset_rad, exposure));
    const CaptureStep step = seq_.on_frame(flat_frame(trigger, exposure, static_cast<float>(eye_.norm())), 1.5);
    EXPECT_TRUE(step.result);
    return step.result.value_or(CaptureResult{});
  }

  const Eigen::Vector3d eye_{0.75, 0.0, 0.35};
  const Pose view_ = look_at_z_up(eye_, Eigen::Vector3d::Zero());
  Vector6d q_;
  double turntable_ = 0;
};

TEST_F(FlatFrame, PointsLieOnThePlaneTheFrameShowsAndTheTurntableIsCropped) {
  const CaptureResult c = capture(0.0);
  ASSERT_TRUE(c.ok) << c.message;
  EXPECT_LT((c.object_T_camera.translation() - eye_).norm(), 1e-6);
  const Eigen::Vector3d n = -eye_.normalized();  // the optical axis
  for (const Eigen::Vector3f& p : c.points) {
    EXPECT_NEAR(n.dot(p.cast<double>() - eye_), eye_.norm(), 1e-5);  // on the plane
    EXPECT_NEAR(n.dot(p.cast<double>()), 0.0, 1e-5);                 // through the origin
  }
  // The principal point (32, 24) sees the object origin.
  double nearest = 1;
  for (const Eigen::Vector3f& p : c.points) nearest = std::min(nearest, static_cast<double>(p.norm()));
  EXPECT_LT(nearest, 1e-5);
  // The camera's x axis is horizontal, so a pixel row v is at height z = -0.75 (v - 24) / 50
  // (the plane drops 0.75 m per metre down the image: |eye| cos(pitch) = 0.75). The turntable
  // top (z = -0.15) plus 4 mm clearance crops z <= -0.146: rows 34..47, 14 rows of 64 pixels.
  EXPECT_EQ(c.num_valid_pixels, 64 * 48);
  EXPECT_EQ(c.num_cropped, 14 * 64);
  EXPECT_EQ(static_cast<int>(c.points.size()), 34 * 64);
  for (const Eigen::Vector3f& p : c.points) EXPECT_GT(p.z(), -0.146);
}

TEST_F(FlatFrame, ATurnedTurntableTurnsTheCloudTheOtherWayInTheObjectFrame) {
  const CaptureResult at0 = capture(0.0);
  const CaptureResult turned = capture(kPi / 2, request(8));
  ASSERT_TRUE(at0.ok && turned.ok);
  ASSERT_EQ(at0.points.size(), turned.points.size());
  // The turntable 90 deg further: in the object frame the camera (and what it sees) is turned
  // -90 deg about z: (x, y, z) -> (y, -x, z).
  for (std::size_t i = 0; i < at0.points.size(); ++i) {
    const Eigen::Vector3f& a = at0.points[i];
    EXPECT_NEAR(turned.points[i].x(), a.y(), 1e-5);
    EXPECT_NEAR(turned.points[i].y(), -a.x(), 1e-5);
    EXPECT_NEAR(turned.points[i].z(), a.z(), 1e-5);
  }
}

TEST_F(FlatFrame, TheWorkingVolumeCropsAndDownsamplingThinsTheCloud) {
  CaptureRequest r = request();
  // The camera's x axis (image right) is the object's +y at this pose, so pixel column u is at
  // y = (u - 32) |eye| / 50; |y| <= 0.1 keeps |u - 32| <= 0.1 * 50 / |eye| = 6.04: columns
  // 26..38, 13 of them, on the 34 rows above the turntable.
  r.crop = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -0.1, -1), Eigen::Vector3d(1, 0.1, 1));
  const CaptureResult c = capture(0.0, r);
  ASSERT_TRUE(c.ok) << c.message;
  EXPECT_EQ(static_cast<int>(c.points.size()), 13 * 34);
  EXPECT_EQ(c.num_cropped, 64 * 48 - 13 * 34);
  // A 5 cm voxel grid leaves far fewer points, each still on the plane within the voxel.
  r.crop = Eigen::AlignedBox3d();
  r.voxel_m = 0.05;
  r.request_id = 9;
  const CaptureResult thin = capture(0.0, r);
  ASSERT_TRUE(thin.ok);
  EXPECT_LT(thin.points.size(), c.points.size());
  EXPECT_GT(thin.points.size(), 10u);
  EXPECT_EQ(thin.voxel_m, 0.05);
}

}  // namespace
}  // namespace pbnbv
