#pragma once
// Volumetric information gain by ray casting: the approach PB-NBV replaces (docs/method.md
// "Paper's evaluation"), built as a fair, optimised peer so that the benchmark measures the
// method and not a weak implementation. For each candidate view, rays are cast from the camera
// centre through the voxel map, one ray per voxel footprint (at the distance of B's centre) over
// the image region that B projects to; along each ray the unobserved voxels (None, Unknown,
// Frontier) are counted until the ray meets an Occupied voxel, leaves B or leaves the depth
// range (the one voxel traversal, core/geometry/voxel_traversal.hpp). A voxel crossed by several
// rays of one view counts once. Candidates are spread over the workers of core/base/parallel.hpp;
// each worker keeps a stamp per voxel instead of clearing a visited set per view.
#include <cstdint>
#include <vector>

#include "core/geometry/camera_model.hpp"
#include "core/base/pose.hpp"
#include "core/mapping/voxel_map.hpp"

namespace pbnbv {

struct RaycastParams {
  CameraIntrinsics camera;
  DepthRange range;
  // Ray spacing in voxel footprints at the distance from the camera to B's centre (1: one ray
  // per voxel footprint; smaller: denser). Never finer than one ray per pixel.
  double ray_spacing_voxels = 1.0;
  int threads = 0;  // at most this many workers; 0: one per core (core/base/parallel.hpp)
  void validate() const;  // throws std::invalid_argument naming the field
};

struct RaycastGain {
  int64_t unknown = 0;  // distinct unobserved voxels the view would reveal
  int rays = 0;         // rays cast
  double spacing_px = 0;  // ray spacing used, pixels
};

// The gain of every view (object_T_camera, optical frame). Views with active[i] == 0 are skipped
// (gain 0, no rays); an empty `active` means all. Throws std::invalid_argument for a bad grid,
// bad parameters, or an `active` of the wrong size.
std::vector<RaycastGain> raycast_gains(const VoxelGrid& grid, const std::vector<Pose>& views,
                                       const std::vector<uint8_t>& active, const RaycastParams& params);

// The image rectangle (pixels, [u0, u1) x [v0, v1), clipped to the image) that the box projects
// to; the whole image when some but not all corners are at or behind the camera plane; empty
// (u1 <= u0) when the box is wholly behind the camera or outside the image.
struct PixelRect {
  double u0 = 0, v0 = 0, u1 = 0, v1 = 0;
  bool empty() const { return u1 <= u0 || v1 <= v0; }
};
PixelRect projected_box(const Eigen::AlignedBox3d& box, const CameraIntrinsics& k, const Pose& object_T_camera);

// The visibility term of pbnbv's combined ranking (planner.hpp, docs/method.md "Beyond the paper"):
// for each view, over the same rays as raycast_gains (one per ray_spacing_voxels voxel footprints),
// the sum of 1 - exp(-n / saturation_voxels), n the unobserved voxels (None, Unknown, Frontier) a
// ray crosses before the first Occupied voxel. A ray that enters unobserved space is likely to meet
// surface there, the more so the longer it stays in it; unlike the count of distinct voxels, a long
// stretch does not outweigh many rays that each reach some unobserved space.
struct UnobservedRayParams {
  CameraIntrinsics camera;
  DepthRange range;
  double saturation_voxels = 8.0;
  double ray_spacing_voxels = 1.0;
  int threads = 0;  // at most this many workers; 0: one per core
  void validate() const;  // throws std::invalid_argument naming the field
};
std::vector<double> unobserved_ray_scores(const VoxelGrid& grid, const std::vector<Pose>& views,
                                          const std::vector<uint8_t>& active, const UnobservedRayParams& params);

// The grid with `factor` x `factor` x `factor` voxels merged into one (the last ones partial): Occupied
// if any is, else unobserved (Unknown) if any is, else Empty. Throws std::invalid_argument for
// factor < 1.
VoxelGrid coarsened(const VoxelGrid& grid, int factor);

}  // namespace pbnbv
