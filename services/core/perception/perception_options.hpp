#pragma once
// The perception settings, each defined once (core/base/setting.hpp): the scan's cloud
// downsampling voxel (per frame and accumulated), also pbnbv-registration's model voxel.
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<double> kCloudVoxel{"voxel", 0.002, 0.0, 0.05, "m",
                                             "cloud downsampling voxel, per frame and accumulated (0: off)"};

}  // namespace pbnbv
