#pragma once
// The one palette of the voxel states: every picture of the map uses it (the OctoMap export of
// VoxelMap::write_octomap, and the plan figures' occupied and frontier ellipsoids in report/), so
// a state has the same colour wherever a person looks at it.
#include <cstdint>

#include "core/mapping/voxel_map.hpp"

namespace pbnbv {

// An 8-bit colour, red first (OctoMap's order; OpenCV callers swap to BGR).
struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

// The colour that stands for voxel state `s`: Occupied blue (40, 110, 230), Frontier orange
// (255, 140, 40), Unknown grey (150, 150, 150), Empty green (60, 200, 80), None light grey
// (220, 220, 220; never drawn: None cells are not exported).
Rgb state_colour(VoxelState s);

}  // namespace pbnbv
