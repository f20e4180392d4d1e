// Which messages a process serving one scan takes: its own scan's; an empty scan id only from a
// rig driver or a heartbeat (a driver serving one scan at a time need not echo the id); every
// message type of the contract but the nested ones carries a scan id.
#include <gtest/gtest.h>

#include "bus/bus.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/pose_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

using namespace pbnbv;
using bus::HasScanId;
using bus::MayBeUnscoped;

static_assert(HasScanId<arm_command_t>::value && HasScanId<arm_status_t>::value && HasScanId<turntable_command_t>::value &&
              HasScanId<turntable_status_t>::value && HasScanId<depth_trigger_t>::value && HasScanId<depth_frame_t>::value);
static_assert(HasScanId<move_request_t>::value && HasScanId<move_result_t>::value && HasScanId<capture_request_t>::value &&
              HasScanId<point_cloud_t>::value && HasScanId<registered_cloud_t>::value && HasScanId<voxel_set_t>::value &&
              HasScanId<ellipsoid_set_t>::value && HasScanId<plan_request_t>::value && HasScanId<view_plan_t>::value &&
              HasScanId<scan_status_t>::value && HasScanId<heartbeat_t>::value);
static_assert(!HasScanId<pose_t>::value);
static_assert(MayBeUnscoped<arm_status_t>::value && MayBeUnscoped<turntable_status_t>::value &&
              MayBeUnscoped<depth_frame_t>::value && MayBeUnscoped<heartbeat_t>::value);
static_assert(!MayBeUnscoped<point_cloud_t>::value && !MayBeUnscoped<arm_command_t>::value &&
              !MayBeUnscoped<depth_trigger_t>::value);

TEST(ScanScope, AProcessForEveryScanTakesEveryMessage) {
  EXPECT_TRUE(bus::in_scope("", "bunny-0123456789abcdef", false));
  EXPECT_TRUE(bus::in_scope("", "", false));
}

TEST(ScanScope, AProcessForOneScanTakesOnlyThatScansMessages) {
  const std::string mine = "bunny-0123456789abcdef";
  EXPECT_TRUE(bus::in_scope(mine, mine, false));
  EXPECT_FALSE(bus::in_scope(mine, "bunny-0123456789abcdee", false));  // one digit apart
  EXPECT_FALSE(bus::in_scope(mine, "bunny", false));                   // a prefix is not the id
  EXPECT_FALSE(bus::in_scope(mine, "", false));                        // a pipeline message must name its scan
  EXPECT_TRUE(bus::in_scope(mine, "", true));                          // a driver that does not echo the id
  EXPECT_FALSE(bus::in_scope(mine, "box-0000000000000001", true));     // a driver of another scan's rig
}

TEST(ScanScope, AHeartbeatIsFilteredByTheScanItsSenderServesNotTheLastItHandled) {
  heartbeat_t h{};
  h.scan_id = "bunny-0000000000000001";  // an unscoped service's last scan
  h.serves_scan = "";
  EXPECT_TRUE(bus::in_scope("box-0000000000000002", bus::scan_of(h), MayBeUnscoped<heartbeat_t>::value));
  h.serves_scan = "bunny-0000000000000001";  // a service of another scan
  EXPECT_FALSE(bus::in_scope("box-0000000000000002", bus::scan_of(h), MayBeUnscoped<heartbeat_t>::value));
}
