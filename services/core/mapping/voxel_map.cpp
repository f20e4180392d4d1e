// The five-state voxel map of PB-NBV (paper section III-B, method.md "Voxel map").
//
// What one integrate() does, in order:
//  1. Classify every pixel: valid (finite, > 0, inside [range.min_m, range.max_m]), no return
//     (0 or non-finite) or ignored (finite but outside the range, or negative). Back-project
//     every valid pixel into the object frame and take its voxel (lattice index
//     floor(p / resolution)). No valid pixel: the map is left untouched (updated == false).
//  2. Bounding box B (always on the voxel lattice: B's min corner is lo_ * resolution, so voxels
//     never shift when B grows):
//     - first frame with valid pixels: B = AABB of this frame's Occupied voxels, enlarged away
//       from the camera until its diagonal doubles (see first_frame_box());
//     - later frames: B first grows to cover this frame's Occupied voxels, so that every point
//       is recorded and its rays are traversed.
//  3. Every valid pixel's voxel becomes Occupied (sticky: traversal never writes Occupied).
//  4. Rays from the camera centre, traversed with a 3-D DDA (Amanatides & Woo 1987; the one in
//     core/geometry/voxel_traversal.hpp) inside B:
//     - a ray with a return (planar depth z): None/Unknown/Frontier voxels before the first
//       Occupied voxel become Empty, as long as the voxel is left before depth z (a voxel the
//       ray leaves beyond z is not known to be free); from the first Occupied voxel, or from the
//       voxel containing depth z, to where the ray leaves B, None voxels become Unknown.
//       Interpretation: the paper says "None -> Empty" before the hit. We also clear Unknown and
//       Frontier voxels that a ray sees through: otherwise a voxel once occluded could never be
//       observed free and the map could not converge (Frontier would never disappear).
//     - a ray without a return (no_return_is_free): free space up to range.max_m; None/Unknown/
//       Frontier -> Empty along it inside B; it stops at the first Occupied voxel it meets (and
//       marks nothing behind it) and at max range (a voxel straddling max range is not marked).
//     - ignored pixels cast no ray.
//  5. Frontier pass over ALL Unknown and Frontier voxels: an Unknown voxel with >= 1 Empty and
//     >= 1 Occupied voxel among its 26 neighbours is Frontier, a Frontier voxel without that goes
//     back to Unknown. Neighbours outside B count as None.
//  6. Later frames only: B grows to cover the Unknown voxels (always inside B already, since
//     traversal never leaves B) and the axis-aligned cube of half-edge gamma around every
//     Frontier voxel centre (which contains the gamma sphere). New voxels are None. The first
//     frame does not apply this rule: its B is the enlarged AABB (paper: "first frame ...; later
//     frames grow"), so the first B's diagonal is exactly the doubled one.
//
// Ray set (the speed part). Occupied voxels come from every valid pixel (one index per pixel).
// Free/occluded space uses one ray per block of s x s pixels (ray_stride_px, or automatically)
//   s = max(1, floor(min(fx, fy) * resolution / (sqrt(2) * d_max))),
// d_max = the largest distance from the camera centre to a corner of B (after B has grown to
// this frame's points). Why every voxel in the frustum is still crossed: a voxel contains a ball
// of radius res/2; seen from distance d <= d_max, the rays that hit that ball fill a disk of
// radius >= f * (res/2) / d pixels on the image plane (a ray at angle a from the ball's axis
// meets the image plane >= a*f pixels from the axis' image point, as the plane is >= f from the
// centre). The block rays form a square lattice of spacing s (the last, partial, block in a
// row/column gets the centre of its own pixels, and the outermost pixel row/column of the image
// gets one ray per pixel, see below), so every point of the image is within s/sqrt(2) of a ray,
// and s/sqrt(2) <= f*res/(2 d_max) puts a ray inside every such disk: every voxel whose
// inscribed ball projects inside the image is crossed by at least one ray - up to where that
// ray stops (a ray with a return runs to where it leaves B; a free ray stops at the first
// Occupied voxel and at max range, exactly as a per-pixel ray would). When
// f*res/(sqrt(2) d_max) < 1 (voxels smaller than ~1.4 pixels at the far side of B) even one ray
// per pixel cannot promise this; s is then 1, the reference itself. Tested against a wall that
// fills the image, with a rolled camera, at 0.005-0.03 m (SubsampledRaysCoverTheFrustum).
// Half-pixel strides (mixed_blocks): the floor above can nearly halve the spacing the bound
// allows (s = 1.8 gives blocks of 1 pixel, 3.2x the rays that s needs). Blocks of a and a + 1
// pixels (a = floor(s)) alternating along an axis put neighbouring block centres a + 0.5 apart
// along it. The lattice of block rays is then rectangular with spacings g_u, g_v (a or a + 0.5
// each), every point of the image lies within sqrt(g_u^2 + g_v^2) / 2 of a ray, and the argument
// above holds as long as that is <= s / sqrt(2), i.e. g_u^2 + g_v^2 <= 2 s^2: u alternates when
// (a + 0.5)^2 + a^2 <= 2 s^2, v too when s >= a + 0.5. Only for a <= 4 (0.005 and 0.01 m voxels
// at about 1 m), where the floor costs most rays; coarser voxels (0.02, 0.03 m) keep the uniform
// blocks they always had.
// What each block casts:
//  - all pixels valid and depth spread (max - min) <= resolution: one ray through the block
//    centre whose return depth is the block's MINIMUM depth, so free space is never claimed
//    behind any surface point of the block (it is free up to there; see step 4 for the rest);
//  - all pixels without return (and no_return_is_free): one free ray through the block centre;
//  - all pixels ignored (or without return while !no_return_is_free): no ray;
//  - anything else (silhouettes, depth jumps > resolution, range edges): one ray per pixel of
//    the block, each with its own depth, exactly as the reference (ray_stride_px = 1);
//  - blocks on the image border add one ray per pixel of the outermost pixel row/column.
// Differences to the one-ray-per-pixel reference (measured in SubsampledRaysMatchPerPixelReference:
// <= 0.6 % of the classified voxels, each on an interface between two states of the reference
// map) come from voxels only partly visible: (a) partly hidden behind an Occupied voxel that
// the free rays must pass (the Occupied rim of a surface is up to one voxel wider than its
// silhouette; the dense reference rays slip past its corners, sparse ones may all stop), so the
// reference has Empty/Unknown where we have None, or Empty where we have Unknown along a shadow
// boundary; (b) with an even s the block centre lies between pixel centres, so a block ray can
// cross a sliver no pixel-centre ray crosses (Empty here, Unknown in the reference); (c) in a
// smooth surface block, voxels between the block's minimum depth and the surface (< resolution
// + one voxel in front of the surface) are Unknown instead of Empty.
//
// Threads: the workers of core/base/parallel.hpp (one per core) over interleaved block rows. The
// only writes during traversal are the monotone transitions {None, Unknown, Frontier} -> Empty
// (relaxed atomic store; Empty always wins) and None -> Unknown (relaxed compare-exchange from
// None, so it can never overwrite an Empty written by another worker). Occupied is written
// before traversal and never during it. The result is therefore independent of ray order, thread
// interleaving and the number of workers: a voxel is Empty if any ray saw it free, else Unknown
// if any ray saw it occluded while it was None.
#include "core/mapping/voxel_map.hpp"
#include "core/mapping/state_colour.hpp"

#include <octomap/ColorOcTree.h>

#include "core/base/format.hpp"
#include "core/base/parallel.hpp"
#include "core/geometry/voxel_traversal.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace pbnbv {

namespace {

constexpr uint8_t kNoneB = static_cast<uint8_t>(VoxelState::kNone);
constexpr uint8_t kEmptyB = static_cast<uint8_t>(VoxelState::kEmpty);
constexpr uint8_t kOccB = static_cast<uint8_t>(VoxelState::kOccupied);
constexpr uint8_t kUnkB = static_cast<uint8_t>(VoxelState::kUnknown);
constexpr uint8_t kFrontB = static_cast<uint8_t>(VoxelState::kFrontier);

// Pixel classes: valid = inside [zlo, zhi] (NaN compares false); no return = 0 or not finite;
// anything else (negative, out of range) is ignored.
inline bool pixel_valid(float z, float zlo, float zhi) { return z >= zlo && z <= zhi; }
inline bool pixel_no_return(float z) { return z == 0.0f || !std::isfinite(z); }

// floor() for the lattice index of a coordinate already divided by the resolution. Fast path
// for |x| < 2^20 voxels (a 1 mm lattice out to 1 km); std::floor beyond.
inline int lattice_floor(double x) {
  constexpr double kOff = 1048576.0;
  if (x > -kOff && x < kOff) return static_cast<int>(x + kOff) - static_cast<int>(kOff);
  return static_cast<int>(std::floor(x));
}

constexpr int64_t kMaxVoxels = int64_t(1) << 31;

// Work shares below which another worker does not pay for its start (core/base/parallel.hpp):
// image rows per worker in an update, voxels per worker in the frontier pass.
constexpr std::size_t kRowsPerWorker = 32;
constexpr int64_t kVoxelsPerWorker = 100000;

inline uint8_t load_relaxed(const uint8_t* c) { return __atomic_load_n(c, __ATOMIC_RELAXED); }
inline void store_relaxed(uint8_t* c, uint8_t v) { __atomic_store_n(c, v, __ATOMIC_RELAXED); }
inline void none_to_unknown(uint8_t* c) {
  uint8_t expected = kNoneB;
  __atomic_compare_exchange_n(c, &expected, kUnkB, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED);
}

// The automatic ray set alternates blocks of a and a + 1 pixels (see "Half-pixel strides") only
// when a is at most this: there the floor to a whole stride costs most rays ((a + 0.5)^2 / a^2
// >= 1.23); coarser voxels keep the ray set they always had.
constexpr int kMaxMixedStride = 4;

// The pixel edges of the blocks along one image axis of n pixels: [0, a, 2a, ..., n], or with
// `alternate` widths a, a + 1, a, a + 1, ... (the last block is cut at n). Neighbouring block
// centres are then a + 0.5 apart at most (a when not alternating).
std::vector<int> block_edges(int n, int a, bool alternate) {
  std::vector<int> e{0};
  for (int i = 0; e.back() < n; ++i) e.push_back(std::min(n, e.back() + a + (alternate && i % 2 == 1 ? 1 : 0)));
  return e;
}

inline int floor_index(double x_m, double res) { return static_cast<int>(std::floor(x_m / res)); }

// The dense grid as the ray caster sees it.
struct Grid {
  uint8_t* cells;
  VoxelLattice lattice;  // dims_ cells of edge res, relative to B's min corner
};

// Traverses one ray o + t d (o relative to B's min corner; d = R (x_n, y_n, 1), so t is the planar
// depth) through B (the one voxel traversal, core/geometry/voxel_traversal.hpp). has_return: the
// pixel saw a surface at depth t_free; otherwise the ray is free up to t_free (= max range).
// Returns whether it entered B.
bool cast_ray(const Grid& g, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_free,
              bool has_return) {
  uint8_t* const cells = g.cells;
  const double t_max = has_return ? std::numeric_limits<double>::infinity() : t_free;
  return traverse_voxels(
      g.lattice, o, d, 0.0, t_max,
      // Free phase: up to the first Occupied voxel or the first voxel not left before t_free.
      [&](int64_t lin, double, double t_out) {
        uint8_t* c = cells + lin;
        const uint8_t s = load_relaxed(c);
        if (s == kOccB) {
          // A free ray stops at the first Occupied voxel; behind it a ray with a return is occluded.
          return has_return ? VoxelVisit::kHandOver : VoxelVisit::kStop;
        }
        if (t_out > t_free) {  // the ray leaves this voxel beyond t_free
          if (!has_return) return VoxelVisit::kStop;  // straddles max range: not known to be free
          if (s == kNoneB) none_to_unknown(c);        // straddles the return depth: not known to be free
          return VoxelVisit::kHandOver;
        }
        if (s != kEmptyB) store_relaxed(c, kEmptyB);  // left before the return: observed free
        return VoxelVisit::kNext;
      },
      // Occluded phase: None -> Unknown to where the ray leaves B.
      [&](int64_t lin, double, double) {
        uint8_t* c = cells + lin;
        if (load_relaxed(c) == kNoneB) none_to_unknown(c);
        return VoxelVisit::kNext;
      });
}

// Lattice index box of the first frame's B (see the comment at integrate()).
void first_frame_box(const Eigen::Vector3i& occ_lo, const Eigen::Vector3i& occ_hi,
                     const Eigen::Vector3d& camera, const Eigen::Vector3d& optical_axis,
                     double res, Eigen::Vector3i* lo, Eigen::Vector3i* hi) {
  const Eigen::Vector3d box_lo = occ_lo.cast<double>() * res;
  const Eigen::Vector3d box_hi = (occ_hi.cast<double>() + Eigen::Vector3d::Ones()) * res;
  const Eigen::Vector3d size = box_hi - box_lo;
  const double diag = size.norm();
  Eigen::Vector3d dir = 0.5 * (box_lo + box_hi) - camera;
  if (dir.norm() < 1e-9) dir = optical_axis;
  dir.normalize();
  // Extend the far faces by t * d: edge i grows by t |d_i|, so the new diagonal is
  // |size + t |d||; |size + t a|^2 = 4 diag^2 with a = |d| (|a| = 1) gives
  // t^2 + 2 t (size . a) - 3 diag^2 = 0, t = -(size . a) + sqrt((size . a)^2 + 3 diag^2).
  const Eigen::Vector3d a = dir.cwiseAbs();
  const double b = size.dot(a);
  const double t = -b + std::sqrt(b * b + 3.0 * diag * diag);
  *lo = occ_lo;
  *hi = occ_hi;
  for (int i = 0; i < 3; ++i) {
    const double ext = t * dir[i];
    if (ext > 0) {
      (*hi)[i] = std::max(occ_hi[i],
                          static_cast<int>(std::ceil((box_hi[i] + ext) / res - 1e-9)) - 1);
    } else if (ext < 0) {
      (*lo)[i] = std::min(occ_lo[i], static_cast<int>(std::floor((box_lo[i] + ext) / res + 1e-9)));
    }
  }
}

}  // namespace

const char* to_string(VoxelState s) {
  switch (s) {
    case VoxelState::kNone: return "None";
    case VoxelState::kEmpty: return "Empty";
    case VoxelState::kOccupied: return "Occupied";
    case VoxelState::kUnknown: return "Unknown";
    case VoxelState::kFrontier: return "Frontier";
  }
  return "?";
}

VoxelMap::VoxelMap(const VoxelMapParams& params) : params_(params) {
  if (!(std::isfinite(params.resolution_m) && params.resolution_m > 0)) {
    std::ostringstream os;
    os << "VoxelMap: resolution_m = " << params.resolution_m << " must be a positive number";
    throw std::invalid_argument(os.str());
  }
  if (!(std::isfinite(params.gamma_m) && params.gamma_m >= 0)) {
    std::ostringstream os;
    os << "VoxelMap: gamma_m = " << params.gamma_m << " must be finite and >= 0";
    throw std::invalid_argument(os.str());
  }
  if (params.frontier_empty_neighbours != 6 && params.frontier_empty_neighbours != 26) {
    std::ostringstream os;
    os << "VoxelMap: frontier_empty_neighbours = " << params.frontier_empty_neighbours << " must be 6 or 26";
    throw std::invalid_argument(os.str());
  }
  if (params.ray_stride_px < 0) {
    std::ostringstream os;
    os << "VoxelMap: ray_stride_px = " << params.ray_stride_px << " must be >= 0 (0 = automatic)";
    throw std::invalid_argument(os.str());
  }
}

Eigen::AlignedBox3d VoxelMap::bounds() const {
  if (empty()) return Eigen::AlignedBox3d();  // empty box
  return Eigen::AlignedBox3d(origin_, origin_ + dims_.cast<double>() * params_.resolution_m);
}

VoxelState VoxelMap::state(const Eigen::Vector3i& i) const {
  if ((i.array() < 0).any() || (i.array() >= dims_.array()).any()) return VoxelState::kNone;
  return cells_[i.x() + int64_t(dims_.x()) * (i.y() + int64_t(dims_.y()) * i.z())];
}

VoxelState VoxelMap::state_at(const Eigen::Vector3d& p) const {
  if (empty() || !p.allFinite()) return VoxelState::kNone;
  const double res = params_.resolution_m;
  const Eigen::Vector3i g(floor_index(p.x(), res), floor_index(p.y(), res),
                          floor_index(p.z(), res));
  return state(g - lo_);
}

Eigen::Vector3d VoxelMap::centre(const Eigen::Vector3i& i) const {
  return (lo_.cast<double>() + i.cast<double>() + Eigen::Vector3d::Constant(0.5)) *
         params_.resolution_m;
}

VoxelCounts VoxelMap::counts() const {
  int64_t n[5] = {0, 0, 0, 0, 0};
  for (VoxelState s : cells_) ++n[static_cast<uint8_t>(s)];
  VoxelCounts c;
  c.none = n[0];
  c.empty = n[1];
  c.occupied = n[2];
  c.unknown = n[3];
  c.frontier = n[4];
  return c;
}

VoxelGrid VoxelMap::grid() const {
  VoxelGrid g;
  g.origin_m = origin_;
  g.dims = dims_;
  g.resolution_m = params_.resolution_m;
  g.cells = cells_;
  return g;
}

void VoxelGrid::validate(const std::string& what) const {
  std::ostringstream os;
  if ((dims.array() < 0).any()) {
    os << what << ": dims " << dims.transpose() << " must not be negative";
  } else if (static_cast<int64_t>(cells.size()) != int64_t(dims.x()) * dims.y() * dims.z()) {
    os << what << ": " << cells.size() << " cells for dims " << dims.transpose() << " ("
       << int64_t(dims.x()) * dims.y() * dims.z() << " expected)";
  } else if (!(std::isfinite(resolution_m) && resolution_m > 0)) {
    os << what << ": resolution_m = " << resolution_m << " must be a positive number";
  } else if (!origin_m.allFinite()) {
    os << what << ": origin is not finite";
  } else {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (static_cast<uint8_t>(cells[i]) > 4) {
        os << what << ": cell " << i << " has state " << int(static_cast<uint8_t>(cells[i]))
           << " (0 none, 1 empty, 2 occupied, 3 unknown, 4 frontier expected)";
        break;
      }
    }
  }
  if (!os.str().empty()) throw std::invalid_argument(os.str());
}

std::vector<Eigen::Vector3d> VoxelMap::centres(VoxelState s) const {
  std::vector<Eigen::Vector3d> out;
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  int64_t lin = 0;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x, ++lin)
        if (cells_[lin] == s) out.push_back(centre(Eigen::Vector3i(x, y, z)));
  return out;
}

void VoxelMap::grow_to_cover(const Eigen::Vector3i& lo_in, const Eigen::Vector3i& hi_in) {
  Eigen::Vector3i lo = lo_in, hi = hi_in;
  if (limited_) {  // B stays inside the working volume
    lo = lo.cwiseMax(limit_lo_);
    hi = hi.cwiseMin(limit_hi_);
    if ((hi.array() < lo.array()).any()) return;
  }
  if (!empty()) {
    lo = lo.cwiseMin(lo_);
    hi = hi.cwiseMax(lo_ + dims_ - Eigen::Vector3i::Ones());
    if (lo == lo_ && hi == lo_ + dims_ - Eigen::Vector3i::Ones()) return;
  }
  const Eigen::Vector3i dims = hi - lo + Eigen::Vector3i::Ones();
  if ((dims.array() <= 0).any()) throw std::logic_error("VoxelMap::grow_to_cover: empty box");
  const int64_t total = int64_t(dims.x()) * dims.y() * dims.z();
  if (total > kMaxVoxels) {
    std::ostringstream os;
    os << "VoxelMap: bounding box of " << dims.x() << " x " << dims.y() << " x " << dims.z()
       << " voxels at " << params_.resolution_m
       << " m exceeds 2^31 voxels (crop the cloud to the working volume or use coarser voxels)";
    throw std::length_error(os.str());
  }
  std::vector<VoxelState> cells(static_cast<size_t>(total), VoxelState::kNone);
  if (!empty()) {
    const Eigen::Vector3i off = lo_ - lo;
    for (int z = 0; z < dims_.z(); ++z) {
      for (int y = 0; y < dims_.y(); ++y) {
        const int64_t src = int64_t(dims_.x()) * (y + int64_t(dims_.y()) * z);
        const int64_t dst =
            off.x() + int64_t(dims.x()) * ((y + off.y()) + int64_t(dims.y()) * (z + off.z()));
        std::memcpy(&cells[dst], &cells_[src], dims_.x() * sizeof(VoxelState));
      }
    }
  }
  cells_.swap(cells);
  lo_ = lo;
  dims_ = dims;
  origin_ = lo_.cast<double>() * params_.resolution_m;
}

void VoxelMap::reserve_bounds(const Eigen::AlignedBox3d& box_m) {
  if (box_m.isEmpty() || !box_m.min().allFinite() || !box_m.max().allFinite()) {
    throw std::invalid_argument("VoxelMap::reserve_bounds: the box is empty or not finite");
  }
  const double res = params_.resolution_m;
  Eigen::Vector3i lo, hi;
  for (int i = 0; i < 3; ++i) {
    lo[i] = static_cast<int>(std::floor(box_m.min()[i] / res + 1e-9));
    hi[i] = std::max(lo[i], static_cast<int>(std::ceil(box_m.max()[i] / res - 1e-9)) - 1);
  }
  grow_to_cover(lo, hi);
}

VoxelCounts VoxelMap::update_frontiers() {
  // 26-neighbourhood test with a separable 3x3x3 dilation of two bits per voxel
  // (bit 0 = Empty, bit 1 = Occupied): plane by plane, mask + dilation along x then y into
  // scratch_; then along z on the fly while deciding each Unknown/Frontier voxel. The voxel
  // itself is in its own 3x3x3 block, but it is Unknown/Frontier (neither bit), so the result is
  // exactly "some 26-neighbour is Empty and some is Occupied". Outside B counts as None.
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  const int64_t plane = int64_t(nx) * ny;
  scratch_.resize(static_cast<size_t>(plane * nz));
  uint8_t* cells = reinterpret_cast<uint8_t*>(cells_.data());
  uint8_t* dil = scratch_.data();
  const bool face_empty = params_.frontier_empty_neighbours == 6;
  // Several workers only for grids beyond about 200,000 voxels (each takes >= 100,000).
  const int nt = worker_count(static_cast<std::size_t>(nz),
                              static_cast<std::size_t>((kVoxelsPerWorker + plane - 1) / plane));

  parallel_run(nt, [&](int tid, int n_threads) {
    std::vector<uint8_t> m(static_cast<size_t>(plane)), mx(static_cast<size_t>(plane));
    for (int z = tid; z < nz; z += n_threads) {
      const uint8_t* src = cells + plane * z;
      for (int64_t i = 0; i < plane; ++i) {
        const uint8_t s = src[i];
        m[i] = static_cast<uint8_t>((s == kEmptyB) | ((s == kOccB) << 1));
      }
      for (int y = 0; y < ny; ++y) {
        const uint8_t* r = m.data() + int64_t(y) * nx;
        uint8_t* o = mx.data() + int64_t(y) * nx;
        if (nx == 1) {
          o[0] = r[0];
          continue;
        }
        o[0] = r[0] | r[1];
        for (int x = 1; x < nx - 1; ++x) o[x] = r[x - 1] | r[x] | r[x + 1];
        o[nx - 1] = r[nx - 2] | r[nx - 1];
      }
      uint8_t* out = dil + plane * z;
      for (int y = 0; y < ny; ++y) {
        const uint8_t* c = mx.data() + int64_t(y) * nx;
        const uint8_t* a = y > 0 ? c - nx : c;
        const uint8_t* b = y + 1 < ny ? c + nx : c;
        uint8_t* o = out + int64_t(y) * nx;
        for (int x = 0; x < nx; ++x) o[x] = a[x] | c[x] | b[x];
      }
      if (face_empty) {
        // Bit 0 becomes Empty among the in-plane face neighbours (x +- 1, y +- 1: the row's
        // x-dilation mx at y, the raw mask at y +- 1); bit 2 keeps this plane's raw Empty for the
        // z +- 1 neighbours of the planes above and below.
        for (int y = 0; y < ny; ++y) {
          const uint8_t* c = mx.data() + int64_t(y) * nx;
          const uint8_t* r = m.data() + int64_t(y) * nx;
          const uint8_t* a = y > 0 ? r - nx : r;
          const uint8_t* b = y + 1 < ny ? r + nx : r;
          uint8_t* o = out + int64_t(y) * nx;
          for (int x = 0; x < nx; ++x) {
            o[x] = static_cast<uint8_t>((o[x] & 2) | ((c[x] | a[x] | b[x]) & 1) | ((r[x] & 1) << 2));
          }
        }
      }
    }
  });

  std::vector<std::array<int64_t, 5>> n(static_cast<std::size_t>(nt), std::array<int64_t, 5>{});
  parallel_run(nt, [&](int tid, int n_threads) {
    int64_t cnt[5] = {0, 0, 0, 0, 0};  // local: the cell stores below cannot alias it
    for (int z = tid; z < nz; z += n_threads) {
      const uint8_t* c = dil + plane * z;
      const uint8_t* a = z > 0 ? c - plane : c;
      const uint8_t* b = z + 1 < nz ? c + plane : c;
      uint8_t* s = cells + plane * z;
      for (int64_t i = 0; i < plane; ++i) {
        uint8_t v = s[i];
        if (v == kUnkB || v == kFrontB) {
          const uint8_t near = face_empty ? static_cast<uint8_t>(((a[i] | b[i] | c[i]) & 2) |
                                                                  (c[i] & 1) | (((a[i] | b[i]) >> 2) & 1))
                                          : static_cast<uint8_t>(a[i] | c[i] | b[i]);
          v = near == 3 ? kFrontB : kUnkB;
          s[i] = v;
        }
        ++cnt[v];
      }
    }
    std::copy(cnt, cnt + 5, n[tid].begin());
  });
  VoxelCounts out;
  for (const auto& c : n) {
    out.none += c[0];
    out.empty += c[1];
    out.occupied += c[2];
    out.unknown += c[3];
    out.frontier += c[4];
  }
  return out;
}

MapUpdateResult VoxelMap::integrate(const DepthView& view) {
  const auto t_start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  if (view.depth_m == nullptr) throw std::invalid_argument("VoxelMap::integrate: depth_m is null");
  const CameraIntrinsics& k = view.intrinsics;
  k.validate();
  view.range.validate();
  const int W = k.width, H = k.height;
  if (view.depth_m->size() != static_cast<size_t>(W) * H) {
    std::ostringstream os;
    os << "VoxelMap::integrate: depth has " << view.depth_m->size() << " values, expected "
       << W << " x " << H << " = " << int64_t(W) * H;
    throw std::invalid_argument(os.str());
  }
  if (!view.object_T_camera.matrix().allFinite()) {
    throw std::invalid_argument("VoxelMap::integrate: object_T_camera is not finite");
  }
  const float* depth = view.depth_m->data();
  const double res = params_.resolution_m;
  limited_ = !view.working_volume.isEmpty();
  if (limited_) {
    if (!view.working_volume.min().allFinite() || !view.working_volume.max().allFinite()) {
      throw std::invalid_argument("VoxelMap::integrate: working_volume is not finite");
    }
    for (int i = 0; i < 3; ++i) {
      limit_lo_[i] = static_cast<int>(std::floor(view.working_volume.min()[i] / res));
      limit_hi_[i] = static_cast<int>(std::floor(view.working_volume.max()[i] / res));
    }
  }
  // The working volume in voxel units (points are compared exactly, not by voxel).
  const Eigen::Vector3d wv_min = limited_ ? Eigen::Vector3d(view.working_volume.min() / res)
                                          : Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  const Eigen::Vector3d wv_max = limited_ ? Eigen::Vector3d(view.working_volume.max() / res)
                                          : Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  const double zlo = view.range.min_m, zhi = view.range.max_m;
  const Eigen::Matrix3d R = view.object_T_camera.linear();
  const Eigen::Vector3d cam = view.object_T_camera.translation();
  // Workers (core/base/parallel.hpp): each takes a share of the image rows.
  const int nt = worker_count(static_cast<std::size_t>(H), kRowsPerWorker);
  if (points_.size() < static_cast<std::size_t>(nt)) points_.resize(static_cast<std::size_t>(nt));

  // 1. Classify pixels, back-project the valid ones, collect their lattice indices. The point
  // of pixel (u, v) at depth z is cam + z (a_u + b_v), a_u = R x_n(u), b_v = R (0, y_n(v), 1).
  const float zlo_f = static_cast<float>(zlo), zhi_f = static_cast<float>(zhi);
  const double inv_res = 1.0 / res;
  std::vector<Eigen::Vector3d> col_dir(W);
  for (int u = 0; u < W; ++u) col_dir[u] = R.col(0) * ((u - k.cx) / k.fx);
  struct PassOne {
    Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
    Eigen::Vector3i hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
    int64_t valid = 0, no_return = 0, ignored = 0, outside = 0;
  };
  std::vector<PassOne> part(static_cast<std::size_t>(nt));
  parallel_run(nt, [&](int tid, int n_threads) {
    const int v0 = H * tid / n_threads, v1 = H * (tid + 1) / n_threads;
    std::vector<Eigen::Vector3i>& pts = points_[tid];  // grows to the most valid pixels seen
    if (pts.size() < 4096) pts.resize(4096);
    // Locals, so the compiler keeps them in registers (no aliasing with the point stores).
    Eigen::Vector3i* out = pts.data();
    int64_t n_out = 0, cap = static_cast<int64_t>(pts.size()), n_nr = 0, n_ign = 0, n_outside = 0;
    Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
    Eigen::Vector3i hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
    const float lo_z = zlo_f, hi_z = zhi_f;
    const double s = inv_res;
    const Eigen::Vector3d cam_v = cam * inv_res;
    const Eigen::Vector3d* cd = col_dir.data();
    for (int v = v0; v < v1; ++v) {
      const Eigen::Vector3d row_dir = R.col(1) * ((v - k.cy) / k.fy) + R.col(2);
      const float* drow = depth + int64_t(v) * W;
      for (int u = 0; u < W; ++u) {
        const float z = drow[u];
        if (pixel_valid(z, lo_z, hi_z)) {
          const double zs = z * s;
          // The point in voxel units; outside the working volume it is not Occupied (its ray is
          // still cast: free up to it).
          const Eigen::Vector3d q(cam_v.x() + zs * (cd[u].x() + row_dir.x()),
                                  cam_v.y() + zs * (cd[u].y() + row_dir.y()),
                                  cam_v.z() + zs * (cd[u].z() + row_dir.z()));
          if ((q.array() < wv_min.array()).any() || (q.array() > wv_max.array()).any()) {
            ++n_outside;
            continue;
          }
          const Eigen::Vector3i g(lattice_floor(q.x()), lattice_floor(q.y()), lattice_floor(q.z()));
          if (n_out == cap) {
            pts.resize(static_cast<size_t>(2 * cap));
            cap = static_cast<int64_t>(pts.size());
            out = pts.data();
          }
          out[n_out++] = g;
          lo = lo.cwiseMin(g);
          hi = hi.cwiseMax(g);
        } else if (pixel_no_return(z)) {
          ++n_nr;
        } else {
          ++n_ign;
        }
      }
    }
    PassOne& pr = part[tid];
    pr.valid = n_out;
    pr.no_return = n_nr;
    pr.ignored = n_ign;
    pr.outside = n_outside;
    pr.lo = lo;
    pr.hi = hi;
  });
  int64_t n_valid = 0, n_no_return = 0, n_ignored = 0, n_outside = 0;
  Eigen::Vector3i occ_lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
  Eigen::Vector3i occ_hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
  for (const PassOne& pr : part) {
    n_valid += pr.valid;
    n_no_return += pr.no_return;
    n_ignored += pr.ignored;
    n_outside += pr.outside;
    occ_lo = occ_lo.cwiseMin(pr.lo);
    occ_hi = occ_hi.cwiseMax(pr.hi);
  }
  MapUpdateResult result;
  if (n_valid == 0) {
    std::ostringstream os;
    os << "map unchanged: the frame has no valid depth pixel";
    if (limited_) os << " inside the working volume (" << n_outside << " outside it";
    else os << " (";
    os << (limited_ ? ", " : "") << n_no_return << " without return (0 or not finite), " << n_ignored
       << " outside [" << zlo << ", " << zhi << "] m)";
    result.updated = false;
    result.message = os.str();
    result.counts = counts();
    result.time_s = elapsed();
    return result;
  }

  // 2. B before traversal.
  const bool first = !initialised_;
  if (first) {
    Eigen::Vector3i lo, hi;
    first_frame_box(occ_lo, occ_hi, cam, R.col(2), res, &lo, &hi);
    grow_to_cover(lo, hi);
  } else {
    grow_to_cover(occ_lo, occ_hi);
  }

  const Grid grid{reinterpret_cast<uint8_t*>(cells_.data()), VoxelLattice(dims_, res)};

  // 3. Occupied from every valid pixel (sticky).
  for (int t = 0; t < nt; ++t) {
    for (int64_t i = 0; i < part[t].valid; ++i) {
      const Eigen::Vector3i& g = points_[t][i];
      const Eigen::Vector3i l = g - lo_;
      grid.cells[l.x() + int64_t(dims_.x()) * (l.y() + int64_t(dims_.y()) * l.z())] = kOccB;
    }
  }

  // 4. Ray stride and traversal.
  int stride = params_.ray_stride_px;
  bool alt_u = false, alt_v = false;  // blocks of stride and stride + 1 pixels alternate along u, v
  if (stride <= 0) {
    double d_max = 0;
    const Eigen::AlignedBox3d b = bounds();
    for (int c = 0; c < 8; ++c) {
      const auto corner = b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
      d_max = std::max(d_max, (corner - cam).norm());
    }
    const double s = std::min(k.fx, k.fy) * res / (std::sqrt(2.0) * d_max);
    stride = std::max(1, static_cast<int>(std::floor(s)));
    if (params_.mixed_blocks && stride <= kMaxMixedStride) {  // see "Half-pixel strides"
      const double a = stride, wide = a + 0.5;
      alt_u = wide * wide + a * a <= 2.0 * s * s;
      alt_v = s >= wide;
    }
  }
  last_stride_px_ = stride;
  last_alternate_ = alt_u;
  const std::vector<int> ub = block_edges(W, stride, alt_u), vb = block_edges(H, stride, alt_v);
  const bool wide_blocks = stride > 1 || alt_u;
  const bool free_no_return = params_.no_return_is_free;
  const Eigen::Vector3d o = cam - origin_;
  const int n_bu = static_cast<int>(ub.size()) - 1, n_bv = static_cast<int>(vb.size()) - 1;
  // Block kinds, then the rays.
  enum : uint8_t { kBlockNothing = 0, kBlockSurface = 1, kBlockFree = 2, kBlockMixed = 3 };
  block_kind_.assign(static_cast<size_t>(n_bu) * n_bv, kBlockNothing);
  block_depth_.resize(static_cast<size_t>(n_bu) * n_bv);
  parallel_run(nt, [&](int tid, int n_threads) {
    // Locals: the byte stores to `kinds` may alias anything reached through the captures, so
    // these would be reloaded after every block.
    const float lo_z = zlo_f, hi_z = zhi_f;
    const float res_f = static_cast<float>(res);
    const int W_l = W, n_bu_l = n_bu, n_bv_l = n_bv;
    const int* ub_l = ub.data();
    const int* vb_l = vb.data();
    const bool free_nr = free_no_return;
    const float* depth_l = depth;
    uint8_t* kinds = block_kind_.data();
    float* zmins = block_depth_.data();
    for (int bv = tid; bv < n_bv_l; bv += n_threads) {
      const int v0 = vb_l[bv], v1 = vb_l[bv + 1];
      for (int bu = 0; bu < n_bu_l; ++bu) {
        const int u0 = ub_l[bu], u1 = ub_l[bu + 1];
        int n_val = 0, n_nr = 0;
        float z_min = std::numeric_limits<float>::infinity(), z_max = 0.0f;
        for (int v = v0; v < v1; ++v) {
          const int64_t row = int64_t(v) * W_l;
          for (int u = u0; u < u1; ++u) {
            const float z = depth_l[row + u];
            if (pixel_valid(z, lo_z, hi_z)) {
              ++n_val;
              z_min = std::min(z_min, z);
              z_max = std::max(z_max, z);
            } else if (pixel_no_return(z)) {
              ++n_nr;
            }
          }
        }
        const int n_pix = (v1 - v0) * (u1 - u0);
        const int64_t b = int64_t(bv) * n_bu_l + bu;
        uint8_t kind;
        if (n_val == n_pix && z_max - z_min <= res_f) {
          kind = kBlockSurface;
        } else if (n_nr == n_pix) {
          kind = free_nr ? kBlockFree : kBlockNothing;
        } else if (n_val == 0 && !free_nr) {
          kind = kBlockNothing;  // only ignored pixels and returns that do not count as free
        } else {
          kind = kBlockMixed;
        }
        kinds[b] = kind;
        zmins[b] = z_min;
      }
    }
  });
  std::vector<int64_t> rays(static_cast<std::size_t>(nt), 0);
  parallel_run(nt, [&](int tid, int n_threads) {
    int64_t n_rays = 0;
    auto ray = [&](double u, double v, double t_free, bool has_return) {
      const Eigen::Vector3d d = R * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      if (cast_ray(grid, o, d, t_free, has_return)) ++n_rays;
    };
    for (int bv = tid; bv < n_bv; bv += n_threads) {
      const int v0 = vb[bv], v1 = vb[bv + 1];
      for (int bu = 0; bu < n_bu; ++bu) {
        const int u0 = ub[bu], u1 = ub[bu + 1];
        const int64_t b = int64_t(bv) * n_bu + bu;
        const uint8_t kind = block_kind_[b];
        if (kind != kBlockMixed && wide_blocks &&
            (bu == 0 || bv == 0 || bu == n_bu - 1 || bv == n_bv - 1)) {
          // Image border: also one ray per pixel of the outermost pixel row/column, so the
          // voxels the frustum boundary cuts are sampled out to the last pixel, like the
          // reference (the block's own ray follows below).
          auto edge_ray = [&](int u, int v) {
            const float z = depth[int64_t(v) * W + u];
            if (pixel_valid(z, zlo_f, zhi_f)) {
              ray(u, v, z, true);
            } else if (free_no_return && pixel_no_return(z)) {
              ray(u, v, zhi, false);
            }
          };
          for (int v = v0; v < v1; ++v) {
            for (int u = u0; u < u1; ++u) {
              if (u == 0 || v == 0 || u == W - 1 || v == H - 1) edge_ray(u, v);
            }
          }
        }
        const double uc = 0.5 * (u0 + u1 - 1), vc = 0.5 * (v0 + v1 - 1);
        if (kind == kBlockSurface) {
          ray(uc, vc, block_depth_[b], true);  // free only up to the block's nearest depth
        } else if (kind == kBlockFree) {
          ray(uc, vc, zhi, false);
        } else if (kind == kBlockMixed) {
          for (int v = v0; v < v1; ++v) {  // one ray per pixel
            const int64_t row = int64_t(v) * W;
            for (int u = u0; u < u1; ++u) {
              const float z = depth[row + u];
              if (pixel_valid(z, zlo_f, zhi_f)) {
                ray(u, v, z, true);
              } else if (free_no_return && pixel_no_return(z)) {
                ray(u, v, zhi, false);
              }
            }
          }
        }
      }
    }
    rays[tid] = n_rays;
  });

  // 5. Frontier pass.
  VoxelCounts c = update_frontiers();

  // 6. Later frames: B covers the Unknown voxels (inside B by construction) and gamma around
  // every Frontier voxel.
  if (!first && c.frontier > 0) {
    const int kk = static_cast<int>(std::floor(params_.gamma_m / res + 0.5));
    Eigen::Vector3i f_lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
    Eigen::Vector3i f_hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
    const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
    int64_t lin = 0;
    for (int z = 0; z < nz; ++z)
      for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x, ++lin)
          if (grid.cells[lin] == kFrontB) {
            const Eigen::Vector3i l(x, y, z);
            f_lo = f_lo.cwiseMin(l);
            f_hi = f_hi.cwiseMax(l);
          }
    // Voxel g's centre is (g + 1/2) res; the voxels g-kk..g+kk reach (kk + 1/2) res > gamma
    // from it on each side, so they cover the cube [c - gamma, c + gamma] around the centre.
    const Eigen::Vector3i need_lo = lo_ + f_lo - Eigen::Vector3i::Constant(kk);
    const Eigen::Vector3i need_hi = lo_ + f_hi + Eigen::Vector3i::Constant(kk);
    const int64_t before = dims_.prod();
    grow_to_cover(need_lo, need_hi);
    c.none += dims_.prod() - before;
  }
  initialised_ = true;

  result.updated = true;
  result.counts = c;
  result.rays = static_cast<int>(std::accumulate(rays.begin(), rays.end(), int64_t(0)));
  result.time_s = elapsed();
  std::ostringstream os;
  const Eigen::Vector3d size = dims_.cast<double>() * res;
  os << (first ? "first frame: " : "") << n_valid << " valid pixels, " << result.rays
     << " rays (stride " << stride << (alt_u ? "/" + std::to_string(stride + 1) : std::string())
     << (alt_v ? " both axes" : alt_u ? " along u" : "") << " px); B " << size.x() << " x " << size.y() << " x "
     << size.z() << " m (" << dims_.x() << " x " << dims_.y() << " x " << dims_.z()
     << " voxels); occupied " << c.occupied << ", empty " << c.empty << ", unknown "
     << c.unknown << ", frontier " << c.frontier;
  result.message = os.str();
  return result;
}

void VoxelMap::write_octomap(const std::string& path) const {
  octomap::ColorOcTree tree(params_.resolution_m);
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  int64_t lin = 0;
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      for (int x = 0; x < nx; ++x, ++lin) {
        const VoxelState s = cells_[lin];
        // Only what was observed: Unknown and Frontier (and None) cells stay out of the tree, so
        // that OctoMap's consumers (isNodeOccupied, MoveIt, octomap_server) read them as unknown.
        if (s != VoxelState::kOccupied && s != VoxelState::kEmpty) continue;
        const Eigen::Vector3d c = centre(Eigen::Vector3i(x, y, z));
        octomap::OcTreeKey key;
        if (!tree.coordToKeyChecked(octomap::point3d(c.x(), c.y(), c.z()), key)) continue;
        // lazy_eval: no pruning while inserting, so every voxel is its own leaf.
        tree.updateNode(key, s == VoxelState::kOccupied, true);
        const Rgb colour = state_colour(s);  // the one palette (state_colour.hpp)
        tree.setNodeColor(key, colour.r, colour.g, colour.b);
      }
    }
  }
  tree.updateInnerOccupancy();
  if (!tree.write(path)) {
    throw std::runtime_error("VoxelMap::write_octomap: cannot write " + path);
  }
}

void VoxelMap::write_states_ply(const std::string& path) const {
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  const int64_t n = int64_t(nx) * ny * nz;
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by pbnbv: voxel map cell centres\n"
                    "comment units metres, frame object (the normalised object frame)\n"
                    "comment resolution_m " + exact(params_.resolution_m) +
                    "\ncomment state 0 none, 1 empty, 2 occupied, 3 unknown, 4 frontier\nelement vertex " +
                    std::to_string(n) +
                    "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar state\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  const std::size_t header = out.size();
  out.resize(header + 16 * static_cast<std::size_t>(n));
  char* dst = &out[header];
  const uint16_t one = 1;
  unsigned char first_byte;
  std::memcpy(&first_byte, &one, 1);
  const bool little = first_byte == 1;
  int64_t lin = 0;
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      for (int x = 0; x < nx; ++x, ++lin) {
        const VoxelState s = cells_[lin];
        const Eigen::Vector3d c = centre(Eigen::Vector3i(x, y, z));
        for (int k = 0; k < 3; ++k) {
          const float f = static_cast<float>(c[k]);
          unsigned char b[4];
          std::memcpy(b, &f, 4);
          if (!little) std::reverse(b, b + 4);
          std::memcpy(dst, b, 4);
          dst += 4;
        }
        const Rgb colour = state_colour(s);
        *dst++ = static_cast<char>(s);
        *dst++ = static_cast<char>(colour.r);
        *dst++ = static_cast<char>(colour.g);
        *dst++ = static_cast<char>(colour.b);
      }
    }
  }
  std::ofstream f(path + ".tmp", std::ios::binary);
  f.write(out.data(), static_cast<std::streamsize>(out.size()));
  f.close();
  if (!f || std::rename((path + ".tmp").c_str(), path.c_str()) != 0) {
    throw std::runtime_error("VoxelMap::write_states_ply: cannot write " + path);
  }
}

namespace {
constexpr char kMapMagic[] = "PBNBV-VOXELMAP 1\n";

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
T take(const std::string& in, std::size_t& at, const std::string& what) {
  if (at + sizeof(T) > in.size()) throw std::invalid_argument(what + " is cut short at byte " + std::to_string(at));
  T v;
  std::memcpy(&v, in.data() + at, sizeof(T));
  at += sizeof(T);
  return v;
}
}  // namespace

std::string VoxelMap::serialise() const {
  std::string out(kMapMagic);
  put(out, params_.resolution_m);
  for (int i = 0; i < 3; ++i) put(out, static_cast<int32_t>(lo_[i]));
  for (int i = 0; i < 3; ++i) put(out, static_cast<int32_t>(dims_[i]));
  put(out, static_cast<uint8_t>(initialised_));
  out.append(reinterpret_cast<const char*>(cells_.data()), cells_.size());
  return out;
}

VoxelMap VoxelMap::restore(const std::string& bytes, const VoxelMapParams& params, const std::string& what) {
  const std::string magic(kMapMagic);
  if (bytes.compare(0, magic.size(), magic) != 0) throw std::invalid_argument(what + " is not a saved voxel map");
  std::size_t at = magic.size();
  const double res = take<double>(bytes, at, what);
  if (res != params.resolution_m) {
    throw std::invalid_argument(what + " was saved at resolution " + std::to_string(res) + " m, the map is at " +
                                std::to_string(params.resolution_m) + " m");
  }
  VoxelMap map(params);
  for (int i = 0; i < 3; ++i) map.lo_[i] = take<int32_t>(bytes, at, what);
  for (int i = 0; i < 3; ++i) map.dims_[i] = take<int32_t>(bytes, at, what);
  map.initialised_ = take<uint8_t>(bytes, at, what) != 0;
  if ((map.dims_.array() < 0).any() || static_cast<int64_t>(map.dims_.cast<int64_t>().prod()) != static_cast<int64_t>(bytes.size() - at)) {
    throw std::invalid_argument(what + " holds " + std::to_string(bytes.size() - at) + " cells for a grid of " +
                                std::to_string(map.dims_.x()) + " x " + std::to_string(map.dims_.y()) + " x " +
                                std::to_string(map.dims_.z()));
  }
  map.cells_.resize(bytes.size() - at);
  std::memcpy(map.cells_.data(), bytes.data() + at, map.cells_.size());
  for (uint8_t c : std::string_view(bytes).substr(at)) {
    if (c > static_cast<uint8_t>(VoxelState::kFrontier)) {
      throw std::invalid_argument(what + " holds a cell state " + std::to_string(c) + " that is not a voxel state");
    }
  }
  map.origin_ = map.lo_.cast<double>() * res;
  return map;
}

}  // namespace pbnbv
