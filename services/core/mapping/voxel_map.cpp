// The five-state voxel map of PB-NBV (paper section III-B, method.md "Voxel map").
//
// What one integrate() does, in order (one private member function per phase):
//  1. collect_points: classify every pixel: valid (finite, > 0, inside [range.min_m,
//     range.max_m]), no return (0 or non-finite) or ignored (finite but outside the range, or
//     negative). Back-project every valid pixel into the object frame and take its voxel
//     (lattice index floor(p / resolution)); points outside the working volume are counted, not
//     kept. No valid pixel: the map is left untouched (updated == false).
//  2. place_bounds: bounding box B (always on the voxel lattice: B's min corner is
//     lo_ * resolution, so voxels never shift when B grows):
//     - first frame with valid pixels: B = AABB of this frame's Occupied voxels, enlarged away
//       from the camera until its diagonal doubles (see first_frame_box());
//     - later frames: B first grows to cover this frame's Occupied voxels, so that every point
//       is recorded and the space in front of it is judged.
//  3. mark_occupied: every kept point's voxel becomes Occupied (sticky: nothing after this
//     writes Occupied or overwrites it).
//  4. project_voxels (voxel_map_projection.cpp): free and hidden space. Along a pixel's ray from
//     the camera centre, inside B:
//     - a ray with a return (planar depth z): None/Unknown/Frontier voxels before the first
//       Occupied voxel become Empty, as long as the ray leaves the voxel before depth z (a voxel
//       the ray leaves beyond z is not known to be free); from the first Occupied voxel, or from
//       the voxel containing depth z, to where the ray leaves B, None voxels become Unknown.
//       Interpretation: the paper says "None -> Empty" before the hit. We also clear Unknown and
//       Frontier voxels that a ray sees through: otherwise a voxel once occluded could never be
//       observed free and the map could not converge (Frontier would never disappear).
//     - a ray without a return (no_return_is_free): free space up to range.max_m; None/Unknown/
//       Frontier -> Empty along it inside B, up to the first Occupied voxel it meets (nothing
//       behind it is marked) and up to max range (a voxel straddling max range is not marked).
//     - ignored pixels cast no ray.
//     Each voxel of B in view that can still change is projected into the image and decided
//     along the rays of the sample pixels (one every few pixels) that cross it, the one nearest
//     to its projected centre first. (walk_rays, voxel_map_rays.cpp: the same rules by walking
//     rays through B; the reference the tests and benchmarks compare with.)
//  5. update_frontiers: over ALL Unknown and Frontier voxels: an Unknown voxel with >= 1 Empty
//     and >= 1 Occupied voxel among its 26 neighbours (Empty among the 6 face neighbours with
//     frontier_empty = kFaceNeighbours) is Frontier, a Frontier voxel without that goes back to
//     Unknown. Neighbours outside B count as None.
//  6. grow_around_frontiers, later frames only: B grows to cover the Unknown voxels (always inside
//     B already, since phase 4 never leaves B) and the axis-aligned cube of half-edge gamma
//     around every Frontier voxel centre (which contains the gamma sphere). New voxels are None.
//     The first frame does not apply this rule: its B is the enlarged AABB (paper: "first frame
//     ...; later frames grow"), so the first B's diagonal is exactly the doubled one.
#include "core/mapping/voxel_map.hpp"
#include "core/base/version.hpp"
#include "core/mapping/state_colour.hpp"

#include <octomap/OcTree.h>

#include "core/base/atomic_file.hpp"
#include "core/base/format.hpp"
#include "core/base/parallel.hpp"
#include "core/mapping/voxel_map_frame.hpp"

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

using namespace voxel_cell;

// floor() for the lattice index of a coordinate already divided by the resolution. Fast path
// for |x| < 2^20 voxels (a 1 mm lattice out to 1 km); std::floor beyond.
inline int lattice_floor(double x) {
  constexpr double kOff = 1048576.0;
  if (x > -kOff && x < kOff) return static_cast<int>(x + kOff) - static_cast<int>(kOff);
  return static_cast<int>(std::floor(x));
}

constexpr int64_t kMaxVoxels = int64_t(1) << 31;

// Voxels per worker in the frontier pass below which another worker does not pay for its start
// (core/base/parallel.hpp).
constexpr int64_t kFrontierVoxelsPerWorker = 100000;

inline int floor_index(double x_m, double res) { return static_cast<int>(std::floor(x_m / res)); }

// Runs of pixels that collect_points() tests at once (most pixels are not valid: background).
constexpr int kPixelRun = 16;
// Whether any of the kPixelRun depths from z is in [lo, hi] (NaN is not), four at a time (GCC's
// vector extension: SSE on x86-64, NEON on ARM; the plain loop stays scalar in its caller).
inline bool any_valid(const float* z, float lo, float hi) {
  typedef float Float4 __attribute__((vector_size(16)));
  typedef int Int4 __attribute__((vector_size(16)));
  Int4 any = {0, 0, 0, 0};
  for (int i = 0; i < kPixelRun; i += 4) {
    Float4 v;
    std::memcpy(&v, z + i, sizeof(v));
    any |= (v >= lo) & (v <= hi);
  }
  return (any[0] | any[1] | any[2] | any[3]) != 0;
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
  } else if ((dims.array() > kMaxGridDim).any()) {  // and the product below stays far inside int64
    os << what << ": dims " << dims.x() << " x " << dims.y() << " x " << dims.z() << " must be at most " << kMaxGridDim
       << " per axis";
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

VoxelCounts VoxelMap::update_frontiers(Eigen::Vector3i* frontier_lo, Eigen::Vector3i* frontier_hi) {
  // Neighbourhood test with a separable 3x3x3 dilation of two bits per voxel (bit 0 = Empty,
  // bit 1 = Occupied): plane by plane, mask + dilation along x then y into scratch_; then along z
  // on the fly while deciding each Unknown/Frontier voxel. The voxel itself is in its own 3x3x3
  // block, but it is Unknown/Frontier (neither bit), so the result is exactly "some 26-neighbour
  // is Occupied and some 26-neighbour is Empty"; with the face rule (frontier_empty =
  // kFaceNeighbours) the Empty bit is read from the 6 face neighbours instead. Outside B counts
  // as None.
  scratch_.resize(static_cast<size_t>(dims_.prod()));
  // Several workers only for grids beyond about 200,000 voxels (each takes >= 100,000).
  const int64_t plane_cells = int64_t(dims_.x()) * dims_.y();
  const int nt = worker_count(static_cast<std::size_t>(dims_.z()),
                              static_cast<std::size_t>((kFrontierVoxelsPerWorker + plane_cells - 1) / plane_cells));
  dilate_in_planes(nt);
  return classify_unknown(nt, frontier_lo, frontier_hi);
}

// The frontier pass's first half: each plane's Empty/Occupied bits dilated along x and y into
// scratch_ (with the face rule, bit 0 from the in-plane face neighbours and bit 2 the plane's own
// Empty).
void VoxelMap::dilate_in_planes(int nt) {
  // Each pass copies the sizes into locals: the byte stores could alias the lambda's captures,
  // and loop bounds read through them would keep the compiler from vectorising the loops.
  parallel_run(nt, [&](int tid, int n_threads) {
    const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
    const int64_t plane = int64_t(nx) * ny;
    const bool face_empty = params_.frontier_empty == FrontierEmpty::kFaceNeighbours;
    uint8_t* const cells = reinterpret_cast<uint8_t*>(cells_.data());
    uint8_t* const dil = scratch_.data();
    std::vector<uint8_t> m(static_cast<size_t>(plane)), mx(static_cast<size_t>(plane));
    for (int z = tid; z < nz; z += n_threads) {
      const uint8_t* src = cells + plane * z;
      for (int64_t i = 0; i < plane; ++i) {
        const uint8_t s = src[i];
        m[i] = static_cast<uint8_t>((s == kEmpty) | ((s == kOccupied) << 1));
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
}

// The frontier pass's second half: the dilation along z on the fly, each Unknown or Frontier voxel
// decided again; returns the counts per state and sets the Frontier voxels' index box.
VoxelCounts VoxelMap::classify_unknown(int nt, Eigen::Vector3i* frontier_lo, Eigen::Vector3i* frontier_hi) {
  std::vector<std::array<int64_t, 5>> n(static_cast<std::size_t>(nt), std::array<int64_t, 5>{});
  std::vector<Eigen::Vector3i> f_lo(static_cast<std::size_t>(nt), Eigen::Vector3i::Constant(std::numeric_limits<int>::max()));
  std::vector<Eigen::Vector3i> f_hi(static_cast<std::size_t>(nt), Eigen::Vector3i::Constant(std::numeric_limits<int>::min()));
  parallel_run(nt, [&](int tid, int n_threads) {
    const int nx = dims_.x(), nz = dims_.z();
    const int64_t plane = int64_t(nx) * dims_.y();
    const bool face_empty = params_.frontier_empty == FrontierEmpty::kFaceNeighbours;
    uint8_t* const cells = reinterpret_cast<uint8_t*>(cells_.data());
    const uint8_t* const dil = scratch_.data();
    int64_t cnt[5] = {0, 0, 0, 0, 0};  // local: the cell stores below cannot alias it
    Eigen::Vector3i lo = f_lo[tid], hi = f_hi[tid];
    for (int z = tid; z < nz; z += n_threads) {
      const uint8_t* c = dil + plane * z;
      const uint8_t* a = z > 0 ? c - plane : c;
      const uint8_t* b = z + 1 < nz ? c + plane : c;
      uint8_t* s = cells + plane * z;
      for (int64_t i = 0; i < plane; ++i) {
        uint8_t v = s[i];
        if (v == kUnknown || v == kFrontier) {
          const uint8_t near = face_empty ? static_cast<uint8_t>(((a[i] | b[i] | c[i]) & 2) |
                                                                  (c[i] & 1) | (((a[i] | b[i]) >> 2) & 1))
                                          : static_cast<uint8_t>(a[i] | c[i] | b[i]);
          v = near == 3 ? kFrontier : kUnknown;
          s[i] = v;
          if (v == kFrontier) {
            const Eigen::Vector3i l(static_cast<int>(i % nx), static_cast<int>(i / nx), z);
            lo = lo.cwiseMin(l);
            hi = hi.cwiseMax(l);
          }
        }
        ++cnt[v];
      }
    }
    std::copy(cnt, cnt + 5, n[tid].begin());
    f_lo[tid] = lo;
    f_hi[tid] = hi;
  });
  *frontier_lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
  *frontier_hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
  for (int t = 0; t < nt; ++t) {
    *frontier_lo = frontier_lo->cwiseMin(f_lo[t]);
    *frontier_hi = frontier_hi->cwiseMax(f_hi[t]);
  }
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

MapFrame VoxelMap::prepare_frame(const DepthView& view) {
  if (view.depth_m == nullptr) throw std::invalid_argument("VoxelMap::integrate: depth_m is null");
  MapFrame f;
  f.k = view.intrinsics;
  f.k.validate();
  view.range.validate();
  const int W = f.k.width, H = f.k.height;
  if (view.depth_m->size() != static_cast<size_t>(W) * H) {
    std::ostringstream os;
    os << "VoxelMap::integrate: depth has " << view.depth_m->size() << " values, expected "
       << W << " x " << H << " = " << int64_t(W) * H;
    throw std::invalid_argument(os.str());
  }
  if (!view.object_T_camera.matrix().allFinite()) {
    throw std::invalid_argument("VoxelMap::integrate: object_T_camera is not finite");
  }
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
    // The working volume in voxel units (points are compared exactly, not by voxel).
    f.wv_min = view.working_volume.min() / res;
    f.wv_max = view.working_volume.max() / res;
  }
  f.depth = view.depth_m->data();
  f.R = view.object_T_camera.linear();
  f.cam = view.object_T_camera.translation();
  f.zlo = view.range.min_m;
  f.zhi = view.range.max_m;
  f.zlo_f = static_cast<float>(f.zlo);
  f.zhi_f = static_cast<float>(f.zhi);
  f.free_no_return = params_.no_return_is_free;
  f.workers = worker_count(static_cast<std::size_t>(H), kRowsPerWorker);
  return f;
}

FramePoints VoxelMap::collect_points(const MapFrame& f) {
  // The point of pixel (u, v) at depth z is cam + z (a_u + b_v), a_u = R x_n(u), b_v = R (0, y_n(v), 1).
  const int W = f.k.width, H = f.k.height, nt = f.workers;
  if (points_.size() < static_cast<std::size_t>(nt)) points_.resize(static_cast<std::size_t>(nt));
  const double inv_res = 1.0 / params_.resolution_m;
  std::vector<Eigen::Vector3d> col_dir(W);
  for (int u = 0; u < W; ++u) col_dir[u] = f.R.col(0) * ((u - f.k.cx) / f.k.fx);
  std::vector<FramePoints> part(static_cast<std::size_t>(nt));
  parallel_run(nt, [&](int tid, int n_threads) {
    const int v0 = H * tid / n_threads, v1 = H * (tid + 1) / n_threads;
    std::vector<Eigen::Vector3i>& pts = points_[tid];  // grows to the most valid pixels seen
    if (pts.size() < 4096) pts.resize(4096);
    // Locals, so the compiler keeps them in registers (no aliasing with the point stores).
    Eigen::Vector3i* out = pts.data();
    int64_t n_out = 0, cap = static_cast<int64_t>(pts.size()), n_outside = 0;
    Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
    Eigen::Vector3i hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
    const float lo_z = f.zlo_f, hi_z = f.zhi_f;
    const double s = inv_res;
    const Eigen::Vector3d cam_v = f.cam * inv_res, wv_min = f.wv_min, wv_max = f.wv_max;
    const Eigen::Vector3d* cd = col_dir.data();
    for (int v = v0; v < v1; ++v) {
      const Eigen::Vector3d row_dir = f.R.col(1) * ((v - f.k.cy) / f.k.fy) + f.R.col(2);
      const float* drow = f.depth + int64_t(v) * W;
      for (int u0 = 0; u0 < W; u0 += kPixelRun) {
        const int u1 = std::min(W, u0 + kPixelRun);
        if (u1 - u0 == kPixelRun && !any_valid(drow + u0, lo_z, hi_z)) continue;  // the common case
        for (int u = u0; u < u1; ++u) {
          const float z = drow[u];
          if (!pixel_valid(z, lo_z, hi_z)) continue;
          const double zs = z * s;
          // The point in voxel units; outside the working volume it is not Occupied (its ray
          // still counts: free up to it).
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
        }
      }
    }
    FramePoints& pr = part[tid];
    pr.valid = n_out;
    pr.outside = n_outside;
    pr.lo = lo;
    pr.hi = hi;
  });
  FramePoints all;
  for (const FramePoints& pr : part) {
    all.valid += pr.valid;
    all.outside += pr.outside;
    all.lo = all.lo.cwiseMin(pr.lo);
    all.hi = all.hi.cwiseMax(pr.hi);
    all.per_worker.push_back(pr.valid);
  }
  return all;
}

void VoxelMap::place_bounds(const MapFrame& f, const FramePoints& points) {
  if (initialised_) {
    grow_to_cover(points.lo, points.hi);
    return;
  }
  Eigen::Vector3i lo, hi;
  first_frame_box(points.lo, points.hi, f.cam, f.R.col(2), params_.resolution_m, &lo, &hi);
  grow_to_cover(lo, hi);
}

void VoxelMap::mark_occupied(const FramePoints& points) {
  uint8_t* cells = reinterpret_cast<uint8_t*>(cells_.data());
  const int64_t nx = dims_.x(), nxy = int64_t(dims_.x()) * dims_.y();
  for (std::size_t t = 0; t < points.per_worker.size(); ++t) {
    for (int64_t i = 0; i < points.per_worker[t]; ++i) {
      const Eigen::Vector3i l = points_[t][i] - lo_;
      cells[l.x() + nx * l.y() + nxy * l.z()] = kOccupied;
    }
  }
}

int64_t VoxelMap::grow_around_frontiers(const Eigen::Vector3i& f_lo, const Eigen::Vector3i& f_hi) {
  if ((f_hi.array() < f_lo.array()).any()) return 0;  // no Frontier voxel
  const int kk = static_cast<int>(std::floor(params_.gamma_m / params_.resolution_m + 0.5));
  // Voxel g's centre is (g + 1/2) res; the voxels g-kk..g+kk reach (kk + 1/2) res > gamma
  // from it on each side, so they cover the cube [c - gamma, c + gamma] around the centre.
  const int64_t before = dims_.prod();
  grow_to_cover(lo_ + f_lo - Eigen::Vector3i::Constant(kk), lo_ + f_hi + Eigen::Vector3i::Constant(kk));
  return dims_.prod() - before;
}

namespace {

// Why a frame changed nothing: its pixels by class (counted only then).
std::string unchanged_message(const MapFrame& f, const FramePoints& p, bool limited) {
  int64_t no_return = 0, ignored = 0;
  for (int64_t i = 0; i < int64_t(f.k.width) * f.k.height; ++i) {
    const float z = f.depth[i];
    if (!f.valid(z)) ++(pixel_no_return(z) ? no_return : ignored);
  }
  const double zlo = f.zlo, zhi = f.zhi;
  std::ostringstream os;
  os << "map unchanged: the frame has no valid depth pixel";
  if (limited) os << " inside the working volume (" << p.outside << " outside it";
  else os << " (";
  os << (limited ? ", " : "") << no_return << " without return (0 or not finite), " << ignored
     << " outside [" << zlo << ", " << zhi << "] m)";
  return os.str();
}

}  // namespace

MapUpdateResult VoxelMap::integrate(const DepthView& view) {
  const auto t_start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  const MapFrame f = prepare_frame(view);
  const FramePoints points = collect_points(f);                   // 1.
  MapUpdateResult result;
  if (points.valid == 0) {
    result.message = unchanged_message(f, points, limited_);
    result.counts = counts();
    result.time_s = elapsed();
    return result;
  }
  const bool first = !initialised_;
  place_bounds(f, points);                                       // 2.
  mark_occupied(points);                                         // 3.
  if (params_.reference_rays) {                                  // 4.
    result.rays = walk_rays(f);
  } else {
    result.projected = project_voxels(f);
  }
  Eigen::Vector3i f_lo, f_hi;                                    // 5.
  VoxelCounts c = update_frontiers(&f_lo, &f_hi);
  if (!first) c.none += grow_around_frontiers(f_lo, f_hi);       // 6.
  initialised_ = true;

  result.updated = true;
  result.counts = c;
  result.time_s = elapsed();
  std::ostringstream os;
  const Eigen::Vector3d size = dims_.cast<double>() * params_.resolution_m;
  os << (first ? "first frame: " : "") << points.valid << " valid pixels, ";
  if (params_.reference_rays) os << result.rays << " rays walked (stride " << last_stride_px_ << " px)";
  else os << result.projected << " voxels projected (sample rays every " << last_stride_px_ << " px)";
  os << "; B " << size.x() << " x " << size.y() << " x " << size.z() << " m (" << dims_.x() << " x "
     << dims_.y() << " x " << dims_.z() << " voxels); occupied " << c.occupied << ", empty " << c.empty
     << ", unknown " << c.unknown << ", frontier " << c.frontier;
  result.message = os.str();
  return result;
}

void VoxelMap::write_octomap(const std::string& path) const {
  octomap::OcTree tree(params_.resolution_m);
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
      }
    }
  }
  tree.updateInnerOccupancy();
  std::ostringstream bytes;
  if (!tree.write(bytes)) throw std::runtime_error("VoxelMap::write_octomap: OctoMap cannot encode the tree for " + path);
  write_file_atomic(path, bytes.str());
}

void VoxelMap::write_states_ply(const std::string& path) const {
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  const int64_t n = int64_t(nx) * ny * nz;
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by pbnbv " + std::string(pbnbv_version()) +
                    ": voxel map cell centres\n"
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
  write_file_atomic(path, out);
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
