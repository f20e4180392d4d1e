#pragma once
// The voxel map's settings, each defined once (core/base/setting.hpp). VoxelMapParams takes its
// defaults from here; so do the scan settings, the benchmark and pbnbv-mapping's options.
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<double> kMapResolution{"resolution", 0.03, 0.002, 0.2, "m",
                                                "voxel map resolution (0.01 suits a real rig)"};
inline constexpr Setting<double> kFrontierMargin{"gamma", 0.1, 0.0, 1.0, "m",
                                                 "B grows to cover a sphere of this radius around each Frontier voxel"};
// Which neighbours of an Unknown voxel next to an Occupied one must hold an Empty voxel for it to
// be Frontier: the 6 face neighbours (planner pbnbv) or all 26 (the paper's reading).
enum class FrontierEmpty { kFaceNeighbours, kAllNeighbours };

template <>
struct EnumNames<FrontierEmpty> {
  static constexpr std::string_view what = "frontier rule";
  static constexpr std::array<NamedValue<FrontierEmpty>, 2> names{
      {{FrontierEmpty::kFaceNeighbours, "6"}, {FrontierEmpty::kAllNeighbours, "26"}}};
};

inline constexpr ChoiceSetting<FrontierEmpty> kFrontierEmpty{
    "frontier-empty", FrontierEmpty::kAllNeighbours,
    "an Unknown voxel next to an Occupied one is Frontier when an Empty voxel is among its 6 face neighbours "
    "(6) or among all 26 (26, the paper's reading)"};

// Which pose the planner's voxel map takes each view at (docs/scan.md "For each view"):
//   rig         the rig's reading (the camera's kinematic pose) with the camera-frame correction the
//               registration found for the view before: the next view is planned from the map while
//               the registration refines this one, and the rig moves meanwhile;
//   registered  the registration's pose: the next view is planned once it has answered.
// The model (cloud.ply, the mesh) takes the registered poses either way. A voxel is 30 mm; the
// registration moves a calibrated rig's view by well under a millimetre.
enum class MapPose { kRegistered, kRig };
template <>
struct EnumNames<MapPose> {
  static constexpr std::string_view what = "map pose";
  static constexpr std::array<NamedValue<MapPose>, 2> names{{{MapPose::kRig, "rig"}, {MapPose::kRegistered, "registered"}}};
};
inline constexpr ChoiceSetting<MapPose> kMapPose{
    "map-pose", MapPose::kRig,
    "the pose each view enters the planner's map at: rig (the kinematic pose with the last registration's correction: the "
    "next view is planned while the registration refines this one) or registered (planned after it)"};

}  // namespace pbnbv
