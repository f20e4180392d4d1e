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
// ICP's voxel: both clouds downsampled to it before the alignment (core/perception/registration.hpp).
// 3 mm since stop 47: registration twice as fast as at 2 mm, the clouds as accurate with a real
// camera's depth errors; with none, 2 mm aligns to 0.065 mm where 3 mm gives 0.12 mm.
inline constexpr Setting<double> kIcpVoxel{
    "icp-voxel", 0.003, 0.0005, 0.05, "m",
    "registration: both clouds downsampled to this for ICP (finer: a little more exact with a low-noise camera, slower)"};
inline constexpr Setting<double> kPoseSigmaDeg{
    "pose-sigma-deg", 0.1, 0.0001, 20.0, "deg",
    "how far the rig's kinematic camera orientation may be from the truth, 1 sigma per axis (registration's prior)"};

}  // namespace pbnbv
