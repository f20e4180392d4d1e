#pragma once
// The settings of `pbnbv view` (core/base/setting.hpp).
#include "core/base/setting.hpp"

namespace pbnbv {

inline constexpr Setting<int> kViewPort{"port", 8765, 1024, 65535, "", "HTTP port of the page, on 127.0.0.1 only"};
inline constexpr Setting<double> kViewVoxel{"cloud-voxel", 0.005, 0.001, 0.05, "m",
                                            "the cloud is sent to the page voxel-downsampled to this edge"};
inline constexpr Setting<int> kViewMaxPoints{"max-points", 60000, 1000, 2000000, "",
                                             "most cloud points sent to the page (the voxel edge grows until it fits)"};

}  // namespace pbnbv
