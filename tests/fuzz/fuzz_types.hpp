#pragma once
// The message types fuzz_messages feeds, in the order of its inputs' first byte (the seeds of
// corpus/fuzz_messages are named by it: fuzz_seeds writes them). Append only: a new type at the
// end keeps the seeds' meaning.
#include <cstddef>

#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/ellipsoid_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/mesh_request_t.hpp"
#include "pbnbv/mesh_result_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/pose_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/stop_request_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

namespace pbnbv::fuzz {

template <class... T>
struct Types {
  static constexpr std::size_t size = sizeof...(T);
};

inline constexpr Types<arm_command_t, arm_status_t, capture_request_t, depth_frame_t, depth_trigger_t, ellipsoid_set_t,
                       ellipsoid_t, heartbeat_t, move_request_t, move_result_t, plan_request_t, point_cloud_t, pose_t,
                       registered_cloud_t, scan_status_t, stop_request_t, turntable_command_t, turntable_status_t,
                       view_plan_t, voxel_set_t, mesh_request_t, mesh_result_t>  // new types at the end: the
    kTypes{};                                                                     // corpus keeps its first bytes
inline constexpr std::size_t kNumTypes = decltype(kTypes)::size;

}  // namespace pbnbv::fuzz
