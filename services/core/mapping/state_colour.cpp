// The voxel states' palette (state_colour.hpp).
#include "core/mapping/state_colour.hpp"

namespace pbnbv {

Rgb state_colour(VoxelState s) {
  switch (s) {
    case VoxelState::kOccupied: return {40, 110, 230};   // blue
    case VoxelState::kFrontier: return {255, 140, 40};   // orange
    case VoxelState::kUnknown: return {150, 150, 150};   // grey
    case VoxelState::kEmpty: return {60, 200, 80};       // green
    case VoxelState::kNone: break;
  }
  return {220, 220, 220};  // None: light grey
}

}  // namespace pbnbv
