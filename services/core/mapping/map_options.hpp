#pragma once
// The voxel map's settings, each defined once (core/base/setting.hpp). VoxelMapParams takes its
// defaults from here; so do the scan settings, the benchmark and pbnbv-mapping's options.
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<double> kMapResolution{"resolution", 0.03, 0.002, 0.2, "m",
                                                "voxel map resolution (0.01 suits a real rig)"};
inline constexpr Setting<double> kFrontierMargin{"gamma", 0.1, 0.0, 1.0, "m",
                                                 "B grows to cover a sphere of this radius around each Frontier voxel"};

}  // namespace pbnbv
