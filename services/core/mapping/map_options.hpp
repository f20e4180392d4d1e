#pragma once
// The voxel map's settings, each defined once (core/base/setting.hpp). VoxelMapParams takes its
// defaults from here; so do the scan settings, the benchmark and pbnbv-mapping's options.
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<double> kMapResolution{"resolution", 0.03, 0.002, 0.2, "m",
                                                "voxel map resolution (0.01 suits a real rig)"};
inline constexpr Setting<double> kFrontierMargin{"gamma", 0.1, 0.0, 1.0, "m",
                                                 "B grows to cover a sphere of this radius around each Frontier voxel"};
inline constexpr Setting<int> kFrontierEmptyNeighbours{
    "frontier-empty", 26, 6, 26, "",
    "an Unknown voxel next to an Occupied one is Frontier when an Empty voxel is among its 6 face neighbours "
    "(6) or among all 26 (26, the paper's reading)"};

}  // namespace pbnbv
