// A recorded rig played back, without a bus: a hand-made recording of two views (statuses every
// 10 ms of rig time, a command, the rig moving, then still, a frame, the rig still after it), so
// every status played, every frame answered and every refusal can be checked by hand.
#include "core/scan/replay_rig.hpp"

#include <gtest/gtest.h>

#include "error_message.hpp"

using namespace pbnbv;

namespace {

constexpr int64_t kPeriodUs = 10000;  // the recording's status period

// Appends `n` statuses of both devices from rig time `utime` on (10 ms apart), still or moving,
// following command `seq` to joints `joint0` (all six) and turntable angle `turntable`.
void statuses(RigTimeline& t, int64_t& order, int64_t& utime, int n, bool still, int64_t seq = -1, double joint0 = 0,
              double turntable = 0) {
  for (int k = 0; k < n; ++k, utime += kPeriodUs) {
    t.arm.push_back({utime, ++order, still, seq, Vector6d::Constant(joint0)});
    RecordedStatus tt{utime, ++order, still, seq, Vector6d::Zero()};
    tt.commanded_rad[0] = turntable;
    t.turntable.push_back(tt);
  }
}

void command(RigTimeline& t, int64_t& order, int64_t seq, double joint0, double turntable) {
  RecordedCommand a;
  a.order = ++order;
  a.seq = seq;
  a.target_rad = Vector6d::Constant(joint0);
  t.arm_commands.push_back(a);
  RecordedCommand c;
  c.order = ++order;
  c.seq = seq;
  c.target_rad[0] = turntable;
  t.turntable_commands.push_back(c);
}

// 5 idle statuses (the rig as the scan found it, rig time 0..40 ms); per view: its command, 20
// moving statuses, 40 still ones (400 ms), the frame exposed at the last still one's time, 30
// more still ones (300 ms). View 1: joints 0.5, turntable 1.0; view 2: joints -0.25, turntable 2.0.
RigTimeline two_views() {
  RigTimeline t;
  int64_t order = 0, utime = 0;
  statuses(t, order, utime, 5, true);
  const double joints[] = {0.5, -0.25}, turntable[] = {1.0, 2.0};
  for (int v = 0; v < 2; ++v) {
    command(t, order, 100 + v, joints[v], turntable[v]);
    statuses(t, order, utime, 20, false, 100 + v, joints[v], turntable[v]);
    statuses(t, order, utime, 40, true, 100 + v, joints[v], turntable[v]);
    t.frames.push_back({utime - kPeriodUs, ++order});
    statuses(t, order, utime, 30, true, 100 + v, joints[v], turntable[v]);
  }
  return t;
}

// Ticks n times; the arm status of the last tick.
std::size_t tick(ReplayRig& rig, int n) {
  std::size_t at = 0;
  for (int k = 0; k < n; ++k) at = rig.tick().arm;
  return at;
}

}  // namespace

TEST(RecordedViews, EachFrameIsAViewWithItsCommandAndTheStillStatusesAroundIt) {
  const RigTimeline t = two_views();
  const std::vector<RecordedView> views = recorded_views(t);
  ASSERT_EQ(views.size(), 2u);
  // View 1: statuses 5..24 moving, 25..64 still; the frame at status 64's time (rig time 640 ms).
  // 300 ms of still statuses before it: 34..64; 200 ms after it: 65..84.
  EXPECT_EQ(views[0].frame, 0u);
  EXPECT_EQ(views[0].arm_command_seq, 100);
  EXPECT_EQ(views[0].arm_target_rad, Vector6d::Constant(0.5));
  EXPECT_EQ(views[0].turntable_target_rad, 1.0);
  EXPECT_EQ(t.arm[64].utime, t.frames[0].utime);
  EXPECT_EQ(views[0].arm.begin, 34u);
  EXPECT_EQ(views[0].arm.at_frame, 64u);
  EXPECT_EQ(views[0].arm.end, 85u);
  EXPECT_EQ(views[0].turntable.begin, 34u);
  // View 2 starts after view 1's 95 statuses: the frame at status 95 + 59 = 154.
  EXPECT_EQ(views[1].arm.at_frame, 154u);
  EXPECT_EQ(views[1].arm.begin, 124u);
  EXPECT_EQ(views[1].arm.end, 175u);
}

TEST(RecordedViews, ALaterFrameAfterTheSameCommandReplacesTheEarlierOne) {
  RigTimeline t = two_views();
  // The camera triggered again in view 1: a second frame 50 ms after the first.
  t.frames.insert(t.frames.begin() + 1, {t.arm[69].utime, t.arm[69].order + 1});
  const std::vector<RecordedView> views = recorded_views(t);
  ASSERT_EQ(views.size(), 2u);
  EXPECT_EQ(views[0].frame, 1u);
  EXPECT_EQ(views[0].arm.at_frame, 69u);
  EXPECT_EQ(views[1].frame, 2u);
}

TEST(RecordedViews, ACommandTheLogLostIsTheOneTheStatusesAcknowledged) {
  // lcm-logger under load lost view 2's commands: the statuses at its frame follow seq 101 to
  // joints -0.25, and that is its command.
  RigTimeline t = two_views();
  t.arm_commands.pop_back();
  t.turntable_commands.pop_back();
  const std::vector<RecordedView> views = recorded_views(t);
  ASSERT_EQ(views.size(), 2u);
  EXPECT_EQ(views[1].arm_command_seq, 101);
  EXPECT_EQ(views[1].arm_target_rad, Vector6d::Constant(-0.25));
  EXPECT_EQ(views[1].turntable_target_rad, std::nullopt);  // not checked
  EXPECT_EQ(views[1].arm.begin, 124u);
  EXPECT_EQ(views[1].arm.end, 175u);
}

TEST(RecordedViews, StillReadingsTheLogLostBeforeTheExposureAreStoodForByTheFirstOneAfterIt) {
  // lcm-logger lost view 1's statuses from the moment the rig was still up to the exposure (25..64):
  // the last one logged before the frame is a moving one (24).
  RigTimeline t = two_views();
  t.arm.erase(t.arm.begin() + 25, t.arm.begin() + 65);
  const std::vector<RecordedView> views = recorded_views(t);
  // The first still status after the frame (index 25 now, rig time 650 ms) is played before the
  // trigger with the exposure's time, 640 ms; after it, on to 840 ms (index 44).
  EXPECT_EQ(t.arm[25].utime, 650000);
  EXPECT_EQ(views[0].arm.begin, 25u);
  EXPECT_EQ(views[0].arm.at_frame, 25u);
  EXPECT_EQ(views[0].arm.end, 45u);
  EXPECT_EQ(views[0].arm.restamp_utime, std::optional<int64_t>(640000));
  EXPECT_EQ(views[0].turntable.restamp_utime, std::nullopt);  // its readings are all there
  EXPECT_TRUE(views[0].arm.nearest_reading_lost);   // the nearest logged is 10 ms away, the period 10 ms
  EXPECT_FALSE(views[0].turntable.nearest_reading_lost);
  EXPECT_FALSE(views[1].arm.nearest_reading_lost);
  ReplayRig rig(t);
  rig.on_arm_command(1, Vector6d::Constant(0.5));
  const ReplayRig::Statuses before = rig.tick();
  EXPECT_EQ(before.arm, 25u);
  EXPECT_EQ(before.arm_utime, std::optional<int64_t>(640000));
  rig.on_trigger();
  EXPECT_EQ(rig.tick().arm_utime, std::nullopt);  // its own time once the frame is taken
  EXPECT_EQ(rig.tick().arm, 26u);
}

TEST(RecordedViews, ARecordingWithoutFramesOrStatusesIsNamed) {
  RigTimeline t = two_views();
  t.frames.clear();
  EXPECT_EQ(pbnbv::testing::error_message([&] { recorded_views(t); }), "the recording holds no DEPTH_FRAME of the scan");
  t = two_views();
  t.arm.clear();
  EXPECT_EQ(pbnbv::testing::error_message([&] { recorded_views(t); }), "the recording holds no ARM_STATUS");
  t = two_views();
  for (RecordedStatus& s : t.arm) s.command_seq = -1;
  EXPECT_EQ(pbnbv::testing::error_message([&] { recorded_views(t); }),
            "the recording's DEPTH_FRAME at rig time 640000 us was taken before the arm acknowledged any command");
}

TEST(ReplayRig, PlaysTheCommandedViewUpToItsFrameThenOnAfterTheTrigger) {
  ReplayRig rig(two_views());
  // Before any command: the 5 idle statuses, the last one held; no frame to show.
  EXPECT_EQ(rig.tick().arm, 0u);
  EXPECT_EQ(tick(rig, 10), 4u);
  EXPECT_EQ(rig.on_trigger(), std::nullopt);
  EXPECT_EQ(rig.arm_command_seq(), -1);
  // View 2 commanded first (a replay may skip a view): its still statuses from 124, held at 154.
  rig.on_arm_command(7, Vector6d::Constant(-0.25));
  rig.on_turntable_command(7, 2.0);
  EXPECT_EQ(rig.view(), 1);
  EXPECT_EQ(rig.arm_command_seq(), 7);
  EXPECT_EQ(rig.turntable_command_seq(), 7);
  EXPECT_TRUE(rig.turntable_fault().empty());
  const ReplayRig::Statuses first = rig.tick();
  EXPECT_EQ(first.arm, 124u);
  EXPECT_EQ(first.turntable, std::optional<std::size_t>(124u));
  EXPECT_EQ(tick(rig, 100), 154u);
  // The trigger: view 2's frame, then the statuses after it up to 174, held.
  EXPECT_EQ(rig.on_trigger(), std::optional<std::size_t>(1u));
  EXPECT_EQ(tick(rig, 100), 174u);
  // A repeated command (the same seq) changes nothing; view 1 by its joints within 1e-4 rad.
  rig.on_arm_command(7, Vector6d::Constant(0.5));
  EXPECT_EQ(rig.view(), 1);
  rig.on_arm_command(8, Vector6d::Constant(0.5 + 0.5e-4));
  EXPECT_EQ(rig.view(), 0);
  EXPECT_EQ(rig.tick().arm, 34u);
}

TEST(ReplayRig, ACommandNoRecordedViewWasGivenIsRefusedAndTheRigHolds) {
  ReplayRig rig(two_views());
  rig.on_arm_command(5, Vector6d::Constant(0.5));
  tick(rig, 50);
  rig.on_arm_command(6, Vector6d::Constant(0.4));
  EXPECT_EQ(rig.arm_fault(),
            "ARM_COMMAND seq 6: no recorded view was commanded to these joints (the nearest, recorded view 1, is 0.1 "
            "rad away)");
  EXPECT_EQ(rig.arm_fault_seq(), 6);
  EXPECT_EQ(rig.arm_command_seq(), 5);  // the last command accepted
  EXPECT_EQ(rig.view(), 0);
  EXPECT_EQ(rig.tick().arm, 64u);  // still held at view 1's frame
  // A turntable target that is not the view's is refused once the arm command of its seq is in.
  rig.on_turntable_command(9, 2.5);
  EXPECT_TRUE(rig.turntable_fault().empty());
  rig.on_arm_command(9, Vector6d::Constant(-0.25));
  EXPECT_TRUE(rig.arm_fault().empty());
  EXPECT_EQ(rig.turntable_fault(), "TURNTABLE_COMMAND seq 9: recorded view 2 was commanded to 2.000000 rad, not 2.500000");
  EXPECT_EQ(rig.turntable_fault_seq(), 9);
  rig.on_turntable_command(10, 2.0);
  EXPECT_TRUE(rig.turntable_fault().empty());
}

// A move that took a detour: between view 1's frame and view 2's command the executor commanded a
// stop (seq 150: joints 0.1, turntable 1.5), the rig moved there (10 statuses) and was still (5),
// then view 2 as in two_views. The stop is recorded with view 2 and played when commanded.
TEST(ReplayRig, ADetoursStopIsPlayedWhereTheRecordingWentAndShowsNoFrame) {
  RigTimeline t;
  int64_t order = 0, utime = 0;
  statuses(t, order, utime, 5, true);
  command(t, order, 100, 0.5, 1.0);
  statuses(t, order, utime, 20, false, 100, 0.5, 1.0);
  statuses(t, order, utime, 40, true, 100, 0.5, 1.0);
  t.frames.push_back({utime - kPeriodUs, ++order});
  statuses(t, order, utime, 30, true, 100, 0.5, 1.0);  // arm statuses 0..94
  command(t, order, 150, 0.1, 1.5);
  command(t, order, 150, 0.1, 1.5);  // re-sent: one stop
  statuses(t, order, utime, 10, false, 150, 0.1, 1.5);  // 95..104
  statuses(t, order, utime, 5, true, 150, 0.1, 1.5);    // 105..109
  command(t, order, 101, -0.25, 2.0);
  statuses(t, order, utime, 20, false, 101, -0.25, 2.0);  // 110..129
  statuses(t, order, utime, 40, true, 101, -0.25, 2.0);   // 130..169
  t.frames.push_back({utime - kPeriodUs, ++order});
  statuses(t, order, utime, 30, true, 101, -0.25, 2.0);

  const std::vector<RecordedView> views = recorded_views(t);
  ASSERT_EQ(views.size(), 2u);
  EXPECT_TRUE(views[0].stops.empty());
  ASSERT_EQ(views[1].stops.size(), 1u);
  const RecordedStop& stop = views[1].stops[0];
  EXPECT_EQ(stop.arm_command_seq, 150);
  EXPECT_EQ(stop.arm_target_rad, Vector6d::Constant(0.1));
  EXPECT_EQ(stop.turntable_target_rad, std::optional<double>(1.5));
  EXPECT_EQ(stop.arm.begin, 105u);     // the first still status following it
  EXPECT_EQ(stop.arm.at_frame, 109u);  // the last one following it, held
  EXPECT_EQ(stop.arm.end, 110u);
  EXPECT_EQ(views[1].arm_command_seq, 101);

  ReplayRig rig(t);
  rig.on_arm_command(1, Vector6d::Constant(0.5));
  rig.on_turntable_command(1, 1.0);
  EXPECT_EQ(rig.view(), 0);
  EXPECT_EQ(rig.on_trigger(), std::optional<std::size_t>(0u));
  // The detour's stop: its statuses from 105, held at 109; no frame there; the view is still view 1.
  rig.on_arm_command(2, Vector6d::Constant(0.1));
  rig.on_turntable_command(2, 1.5);
  EXPECT_TRUE(rig.arm_fault().empty());
  EXPECT_TRUE(rig.turntable_fault().empty());
  EXPECT_EQ(rig.detour_stop(), 0);
  EXPECT_EQ(rig.view(), 0);
  EXPECT_EQ(rig.tick().arm, 105u);
  EXPECT_EQ(tick(rig, 50), 109u);
  EXPECT_EQ(rig.on_trigger(), std::nullopt);
  EXPECT_EQ(tick(rig, 5), 109u);
  // A turntable target that is not the stop's is named as the stop's.
  rig.on_turntable_command(2, 1.25);
  EXPECT_EQ(rig.turntable_fault(),
            "TURNTABLE_COMMAND seq 2: stop 1 of recorded view 2's detour was commanded to 1.500000 rad, not 1.250000");
  // Then view 2 as recorded.
  rig.on_arm_command(3, Vector6d::Constant(-0.25));
  rig.on_turntable_command(3, 2.0);
  EXPECT_EQ(rig.detour_stop(), -1);
  EXPECT_EQ(rig.view(), 1);
  EXPECT_TRUE(rig.turntable_fault().empty());
  EXPECT_EQ(rig.tick().arm, 139u);  // view 2's still statuses from 300 ms before its frame (169)
  EXPECT_EQ(rig.on_trigger(), std::optional<std::size_t>(1u));
}
