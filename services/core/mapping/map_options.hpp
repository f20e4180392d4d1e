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

}  // namespace pbnbv
