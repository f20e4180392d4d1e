#pragma once
// The five-state voxel map of PB-NBV (docs/method.md "Voxel map", paper section III-B) with its
// bounding box B. Dense grid over B; free and hidden space by projecting B's voxels into the depth
// image (voxel_map_projection.cpp), each voxel judged along the sample rays that cross it.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/geometry/camera_model.hpp"
#include "core/base/pose.hpp"
#include "core/mapping/map_options.hpp"

namespace pbnbv {

enum class VoxelState : uint8_t { kNone = 0, kEmpty = 1, kOccupied = 2, kUnknown = 3, kFrontier = 4 };
const char* to_string(VoxelState s);

struct VoxelMapParams {
  double resolution_m = kMapResolution.value;  // voxel edge
  double gamma_m = kFrontierMargin.value;      // B grows to cover a sphere of this radius around each Frontier voxel
  bool no_return_is_free = true;   // a pixel without a return (0) means free space up to max range
  // Free and hidden space from rays walked voxel by voxel through B (the 3-D DDA of
  // core/geometry/voxel_traversal.hpp; voxel_map_rays.cpp), the way this map worked before it
  // projected voxels. Kept as the reference that the tests (one ray per pixel) and the
  // benchmarks (the subsampled ray set, as it ran) compare the projection with; no service sets it.
  bool reference_rays = false;
  // With reference_rays only, the ray set: one ray per `ray_stride_px` pixels in u and v; 0 =
  // automatic (about one ray per voxel footprint at the far side of B), 1 = one ray per pixel.
  int ray_stride_px = 0;
  // Frontier: an Unknown voxel with an Occupied voxel among its 26 neighbours and an Empty one
  // among all 26 (the paper's reading) or among the 6 face neighbours only (planner pbnbv: an
  // Unknown voxel that touches observed free space only along an edge or at a corner lies behind
  // the surface, see docs/method.md "Beyond the paper").
  FrontierEmpty frontier_empty = kFrontierEmpty.value;
};

// One depth frame as the map needs it: planar depth (0 or non-finite = no return), the camera
// model and range, and the (registered) camera pose in the object frame.
struct DepthView {
  const std::vector<float>* depth_m = nullptr;  // row-major, width * height
  CameraIntrinsics intrinsics;
  DepthRange range;
  Pose object_T_camera = Pose::Identity();
  // The working volume (object frame): only points inside it become Occupied, and B never
  // extends beyond it. A point outside it (the turntable, the table, the room) still tells
  // that its ray was free up to it. Empty box (the default): no limit.
  Eigen::AlignedBox3d working_volume;
};

// The most voxels of a grid along one axis (a 0.002 m map over 130 m): a bound for grids that come
// from a message or a file, so that their cell counts are computed without overflow.
inline constexpr int kMaxGridDim = 1 << 16;

// The map's cells as plain data (what the VOXEL_MAP message carries for planners that read the
// whole map, e.g. ray casting): B's min corner, the lattice size, the states with x fastest,
// then y, then z.
struct VoxelGrid {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  double resolution_m = 0;
  std::vector<VoxelState> cells;

  bool empty() const { return (dims.array() == 0).any(); }
  Eigen::AlignedBox3d bounds() const {
    return Eigen::AlignedBox3d(origin_m, origin_m + dims.cast<double>() * resolution_m);
  }
  VoxelState at(int x, int y, int z) const {
    return cells[x + int64_t(dims.x()) * (y + int64_t(dims.y()) * z)];
  }
  // Throws std::invalid_argument naming `what` and the field: negative dims, cells.size() !=
  // dims product, a resolution that is not positive, a non-finite origin, a state above 4.
  void validate(const std::string& what) const;
};

// What integrate()'s phases share about a frame (voxel_map_frame.hpp; internal to core/mapping).
struct MapFrame;
struct FramePoints;

struct VoxelCounts {
  int64_t none = 0, empty = 0, occupied = 0, unknown = 0, frontier = 0;
};

struct MapUpdateResult {
  bool updated = false;          // false: the frame was empty / all invalid; map unchanged
  std::string message;           // why not, or a summary
  VoxelCounts counts;
  double time_s = 0;             // wall time of the update
  int64_t projected = 0;         // voxels of B judged along a pixel's ray (the projection)
  int64_t rays = 0;              // rays traversed (reference_rays only)
};

class VoxelMap {
 public:
  explicit VoxelMap(const VoxelMapParams& params);

  // Integrates one frame with the paper's rules:
  //  - a voxel holding a point of the frame becomes Occupied (Occupied is kept);
  //  - along a pixel's ray from the camera centre, None, Unknown and Frontier voxels that the ray
  //    leaves before its return and before the first Occupied voxel become Empty; None voxels
  //    behind that become Unknown (each voxel judged along the rays of the sample pixels, one
  //    every few pixels, that cross it: voxel_map_projection.cpp);
  //  - then every Unknown voxel with at least one Occupied voxel among its 26 neighbours and at
  //    least one Empty voxel among the neighbours params.frontier_empty names (all 26, or the 6
  //    face neighbours) is Frontier, every other Frontier voxel goes back to Unknown;
  //  - B: the first frame sets B to the AABB of its Occupied voxels enlarged along the viewing
  //    direction until its diagonal doubles; later frames grow B to cover the Occupied and
  //    Unknown voxels and a sphere of radius gamma around every Frontier voxel (B never shrinks).
  // A frame with no valid pixel, or only NaNs, leaves the map unchanged and says so.
  MapUpdateResult integrate(const DepthView& view);

  const VoxelMapParams& params() const { return params_; }
  bool empty() const { return dims_.prod() == 0; }
  Eigen::AlignedBox3d bounds() const;            // B, object frame
  Eigen::Vector3i dims() const { return dims_; }  // voxels along x, y, z
  VoxelState state(const Eigen::Vector3i& index) const;
  VoxelState state_at(const Eigen::Vector3d& point_m) const;  // kNone outside B
  Eigen::Vector3d centre(const Eigen::Vector3i& index) const;
  VoxelCounts counts() const;
  std::vector<Eigen::Vector3d> centres(VoxelState s) const;  // object frame
  VoxelGrid grid() const;                                     // a copy of the cells

  // Grows B to cover `box_m` (snapped outward to the voxel lattice); new voxels are None and B
  // never shrinks. Optional: lets a caller that knows its working volume (or a test) start with
  // a larger B. Called before the first frame, the first frame's rule still applies and B
  // becomes the union of this box and the first frame's enlarged AABB.
  void reserve_bounds(const Eigen::AlignedBox3d& box_m);
  // Pixel spacing of the rays the last integrated frame judged free and hidden space along: the
  // sample lattice of the projection (or the reference's ray stride). Diagnostics.
  int last_ray_stride_px() const { return last_stride_px_; }

  // Writes the map as a plain OctoMap OcTree (.ot: octovis, octomap_server's default type,
  // MoveIt's "OcTree" id and compare_octrees read it): Occupied voxels as occupied nodes, Empty
  // voxels as free nodes; Unknown, Frontier and None voxels are not in the tree (unknown space:
  // search() returns null). The five states are in write_states_ply's file.
  void write_octomap(const std::string& path) const;
  // Writes every cell of B with its state, the five states kept: a binary little-endian PLY of
  // cell centres (float x y z, object frame, m), `uchar state` (0 None, 1 Empty, 2 Occupied,
  // 3 Unknown, 4 Frontier) and `uchar red green blue` (state_colour.hpp), written atomically.
  void write_states_ply(const std::string& path) const;

  // The map's whole state as bytes (B's place and size, every cell), so that a restarted mapping
  // service continues the same map: restore(serialise()) is the same map, and integrating the
  // next frame into either gives the same cells.
  std::string serialise() const;
  // Throws std::invalid_argument naming `what` when the bytes are not a serialised map, are cut
  // short, or were made at another resolution than `params`.
  static VoxelMap restore(const std::string& bytes, const VoxelMapParams& params, const std::string& what);

 private:
  VoxelMapParams params_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  // min corner of B, on the voxel lattice
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  std::vector<VoxelState> cells_;
  // (implementation helpers are private to voxel_map.cpp)
  Eigen::Vector3i lo_ = Eigen::Vector3i::Zero();  // lattice index of B's min voxel (origin_ =
                                                  // lo_ * resolution)
  bool initialised_ = false;                      // a frame with valid points has been integrated
  int last_stride_px_ = 0;
  // Working memory, kept from frame to frame so that a frame does not fault its pages in. Not
  // part of the map's state: a copy of the map starts without it, an assignment keeps the
  // target's (the buffers grow to what a frame needs).
  template <class Buffer>
  struct Scratch : Buffer {
    Scratch() = default;
    Scratch(const Scratch&) : Buffer() {}
    Scratch& operator=(const Scratch&) { return *this; }
    Scratch(Scratch&&) = default;
    Scratch& operator=(Scratch&&) = default;
  };
  Scratch<std::vector<std::vector<Eigen::Vector3i>>> points_;  // per worker: each valid pixel's
                                                               // lattice index
  Scratch<std::vector<uint8_t>> scratch_;         // frontier pass (one byte per voxel)
  Scratch<std::vector<float>> samples_;           // projection (two floats per sample ray)

  // Grows B to cover the lattice indices [lo, hi] (inclusive); copies states, new cells None.
  void grow_to_cover(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi);
  // The working volume of the frame being integrated, as a lattice index box (B is clamped to it).
  bool limited_ = false;
  Eigen::Vector3i limit_lo_ = Eigen::Vector3i::Zero(), limit_hi_ = Eigen::Vector3i::Zero();
  // Re-evaluates Frontier/Unknown over the whole grid; returns the state counts and the box of
  // the Frontier voxels (local indices; empty, lo > hi, when there is none).
  VoxelCounts update_frontiers(Eigen::Vector3i* frontier_lo, Eigen::Vector3i* frontier_hi);
  void dilate_in_planes(int nt);
  VoxelCounts classify_unknown(int nt, Eigen::Vector3i* frontier_lo, Eigen::Vector3i* frontier_hi);

  // The phases of integrate(), in order (voxel_map_frame.hpp: what they share about the frame).
  MapFrame prepare_frame(const DepthView& view);                   // checks; the working volume
  FramePoints collect_points(const MapFrame& f);                   // 1. pixels -> point voxels
  void place_bounds(const MapFrame& f, const FramePoints& points); // 2. B before the free space
  void mark_occupied(const FramePoints& points);                   // 3. Occupied (sticky)
  int64_t project_voxels(const MapFrame& f);                       // 4. free / hidden space
  int64_t walk_rays(const MapFrame& f);                            // 4'. the reference_rays way
  int64_t grow_around_frontiers(const Eigen::Vector3i& f_lo,       // 6. B around Frontier voxels
                                const Eigen::Vector3i& f_hi);
};

}  // namespace pbnbv
