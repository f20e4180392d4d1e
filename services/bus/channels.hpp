#pragma once
// The channel names of the contract (README "Channels" lists type, publisher, subscribers, rate).
namespace pbnbv::channels {

// Rig channels: the only ones the twin (or a real rig driver) speaks.
inline constexpr const char* kArmCommand = "ARM_COMMAND";              // arm_command_t
inline constexpr const char* kArmStatus = "ARM_STATUS";                // arm_status_t
inline constexpr const char* kTurntableCommand = "TURNTABLE_COMMAND";  // turntable_command_t
inline constexpr const char* kTurntableStatus = "TURNTABLE_STATUS";    // turntable_status_t
inline constexpr const char* kDepthTrigger = "DEPTH_TRIGGER";          // depth_trigger_t
inline constexpr const char* kDepthFrame = "DEPTH_FRAME";              // depth_frame_t

// Pipeline channels.
inline constexpr const char* kMoveRequest = "MOVE_REQUEST";        // move_request_t
inline constexpr const char* kMoveResult = "MOVE_RESULT";          // move_result_t
inline constexpr const char* kCaptureRequest = "CAPTURE_REQUEST";  // capture_request_t
inline constexpr const char* kCloud = "CLOUD";                     // point_cloud_t
// The DEPTH_FRAME a CLOUD was made from, published again by the camera service when it answers a
// repeated capture request (the coordinator repeats it while the view's REGISTERED_CLOUD or
// VOXEL_MAP is late): a subscriber that lost the frame on the bus gets it again.
inline constexpr const char* kDepthFrameResent = "DEPTH_FRAME_RESENT";  // depth_frame_t
inline constexpr const char* kScanStatus = "SCAN_STATUS";          // scan_status_t
inline constexpr const char* kHeartbeat = "HEARTBEAT";             // heartbeat_t
inline constexpr const char* kStop = "STOP";                       // stop_request_t
// Perception and planning.
inline constexpr const char* kRegisteredCloud = "REGISTERED_CLOUD";  // registered_cloud_t
inline constexpr const char* kVoxelMap = "VOXEL_MAP";                // voxel_set_t
inline constexpr const char* kEllipsoids = "ELLIPSOIDS";             // ellipsoid_set_t
inline constexpr const char* kPlanRequest = "PLAN_REQUEST";          // plan_request_t
inline constexpr const char* kViewPlan = "VIEW_PLAN";                // view_plan_t
// The scan's end: the surface mesh of the merged views, made by the registration service.
inline constexpr const char* kMeshRequest = "MESH_REQUEST";          // mesh_request_t
inline constexpr const char* kMeshResult = "MESH_RESULT";            // mesh_result_t

}  // namespace pbnbv::channels
