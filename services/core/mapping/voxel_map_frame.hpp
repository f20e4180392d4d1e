#pragma once
// What the phases of VoxelMap::integrate() share about the frame being integrated (voxel_map.cpp,
// voxel_map_projection.cpp, voxel_map_rays.cpp). Internal to core/mapping: not part of the map's
// interface.
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/mapping/voxel_map.hpp"

namespace pbnbv {

namespace voxel_cell {
constexpr uint8_t kNone = static_cast<uint8_t>(VoxelState::kNone);
constexpr uint8_t kEmpty = static_cast<uint8_t>(VoxelState::kEmpty);
constexpr uint8_t kOccupied = static_cast<uint8_t>(VoxelState::kOccupied);
constexpr uint8_t kUnknown = static_cast<uint8_t>(VoxelState::kUnknown);
constexpr uint8_t kFrontier = static_cast<uint8_t>(VoxelState::kFrontier);
}  // namespace voxel_cell

// Pixel classes: valid = inside [zlo, zhi] (NaN compares false); no return = 0 or not finite;
// anything else (negative, out of range) is ignored.
inline bool pixel_valid(float z, float zlo, float zhi) { return z >= zlo && z <= zhi; }
inline bool pixel_no_return(float z) { return z == 0.0f || !std::isfinite(z); }

// Image rows per worker below which another worker does not pay for its start
// (core/base/parallel.hpp).
constexpr std::size_t kRowsPerWorker = 32;

// The frame, validated, with what every phase derives from it (VoxelMap::prepare_frame). Camera rays are
// cam + t R (x_n, y_n, 1): t is the planar depth.
struct MapFrame {
  const float* depth = nullptr;  // row-major, width x height
  CameraIntrinsics k;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();   // object_T_camera's rotation
  Eigen::Vector3d cam = Eigen::Vector3d::Zero();     // camera centre, object frame
  double zlo = 0, zhi = 0;                           // valid depth range (zhi: max range)
  float zlo_f = 0, zhi_f = 0;
  bool free_no_return = true;                        // params_.no_return_is_free
  // The working volume in voxel units (a point outside it is not Occupied); infinite when none.
  Eigen::Vector3d wv_min = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  Eigen::Vector3d wv_max = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  int workers = 1;                                   // for the per-pixel passes

  bool valid(float z) const { return pixel_valid(z, zlo_f, zhi_f); }
  // The direction of pixel (u, v)'s ray, per metre of planar depth, object frame.
  Eigen::Vector3d ray(double u, double v) const {
    return R * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
  }
};

// Phase 1's result: every valid pixel's voxel (lattice index) per worker, and the counts (valid:
// points kept; outside: valid pixels whose point lies outside the working volume).
struct FramePoints {
  int64_t valid = 0, outside = 0;
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());  // box of the
  Eigen::Vector3i hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());  // point voxels
  std::vector<int64_t> per_worker;  // points_[w] holds per_worker[w] indices
};

}  // namespace pbnbv
