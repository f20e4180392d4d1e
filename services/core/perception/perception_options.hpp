#pragma once
// The perception settings, each defined once (core/base/setting.hpp): the scan's cloud
// downsampling voxel (per frame and accumulated), also pbnbv-registration's model voxel; how
// well the rig knows the camera's pose (registration's prior).
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<double> kCloudVoxel{"voxel", 0.002, 0.0, 0.05, "m",
                                             "cloud downsampling voxel, per frame and accumulated (0: off)"};

// The kinematic camera pose's uncertainty, 1 sigma per axis: registration takes a correction only
// as far as the overlap pins the pose down better than this (core/perception/registration.hpp).
inline constexpr Setting<double> kPoseSigmaMm{
    "pose-sigma-mm", 0.5, 0.001, 100.0, "mm",
    "how far the rig's kinematic camera position may be from the truth, 1 sigma per axis (registration's prior)"};
inline constexpr Setting<double> kPoseSigmaDeg{
    "pose-sigma-deg", 0.1, 0.0001, 20.0, "deg",
    "how far the rig's kinematic camera orientation may be from the truth, 1 sigma per axis (registration's prior)"};

}  // namespace pbnbv
