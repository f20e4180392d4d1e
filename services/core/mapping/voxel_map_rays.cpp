// Phase 4 of VoxelMap::integrate() the way the map did it before it projected voxels: rays walked
// voxel by voxel through B (VoxelMapParams::reference_rays). Kept as the reference that the
// tests (one ray per pixel: the rules of docs/method.md "Voxel map" read literally) and the
// benchmarks (the subsampled ray set below, as it ran in production) compare the projection with.
//
// Each ray from the camera centre is traversed with the 3-D DDA (Amanatides & Woo 1987; the one in
// core/geometry/voxel_traversal.hpp) inside B:
//  - a ray with a return (planar depth z): None/Unknown/Frontier voxels before the first Occupied
//    voxel become Empty, as long as the voxel is left before depth z; from the first Occupied
//    voxel, or from the voxel containing depth z, to where the ray leaves B, None voxels become
//    Unknown;
//  - a ray without a return (no_return_is_free): free space up to range.max_m; it stops at the
//    first Occupied voxel it meets (and marks nothing behind it) and at max range (a voxel
//    straddling max range is not marked);
//  - ignored pixels cast no ray.
//
// Ray set. One ray per block of s x s pixels (ray_stride_px, or automatically)
//   s = max(1, floor(min(fx, fy) * resolution / (sqrt(2) * d_max))),
// d_max = the largest distance from the camera centre to a corner of B: every voxel whose
// inscribed ball projects inside the image is crossed by at least one ray (the argument is in
// voxel_map_projection.cpp, whose sample lattice uses the same bound). Blocks of a and a + 1
// pixels alternate where the floor would cost most rays (a = floor(s) <= 4): u alternates when
// (a + 0.5)^2 + a^2 <= 2 s^2, v too when s >= a + 0.5, which keeps every image point within
// s / sqrt(2) of a ray. What each block casts:
//  - all pixels valid and depth spread <= resolution: one ray through the block centre whose
//    return depth is the block's MINIMUM depth;
//  - all pixels without return (and no_return_is_free): one free ray through the block centre;
//  - all pixels ignored (or without return while !no_return_is_free): no ray;
//  - anything else (silhouettes, depth jumps, range edges): one ray per pixel of the block;
//  - blocks on the image border add one ray per pixel of the outermost pixel row/column.
//
// Threads: workers over interleaved block rows. The only writes are the monotone transitions
// {None, Unknown, Frontier} -> Empty (relaxed atomic store; Empty always wins) and None -> Unknown
// (relaxed compare-exchange from None), so the result does not depend on ray order or workers.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "core/base/parallel.hpp"
#include "core/geometry/voxel_traversal.hpp"
#include "core/mapping/voxel_map.hpp"
#include "core/mapping/voxel_map_frame.hpp"

namespace pbnbv {

namespace {

using namespace voxel_cell;

inline uint8_t load_relaxed(const uint8_t* c) { return __atomic_load_n(c, __ATOMIC_RELAXED); }
inline void store_relaxed(uint8_t* c, uint8_t v) { __atomic_store_n(c, v, __ATOMIC_RELAXED); }
inline void none_to_unknown(uint8_t* c) {
  uint8_t expected = kNone;
  __atomic_compare_exchange_n(c, &expected, kUnknown, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED);
}

constexpr int kMaxMixedStride = 4;

// The pixel edges of the blocks along one image axis of n pixels: [0, a, 2a, ..., n], or with
// `alternate` widths a, a + 1, a, a + 1, ... (the last block is cut at n).
std::vector<int> block_edges(int n, int a, bool alternate) {
  std::vector<int> e{0};
  for (int i = 0; e.back() < n; ++i) e.push_back(std::min(n, e.back() + a + (alternate && i % 2 == 1 ? 1 : 0)));
  return e;
}

// Traverses one ray o + t d (o relative to B's min corner, t the planar depth) through B.
// has_return: the pixel saw a surface at depth t_free; otherwise the ray is free up to t_free.
// Returns whether it entered B.
bool cast_ray(uint8_t* cells, const VoxelLattice& lattice, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
              double t_free, bool has_return) {
  const double t_max = has_return ? std::numeric_limits<double>::infinity() : t_free;
  return traverse_voxels(
      lattice, o, d, 0.0, t_max,
      [&](int64_t lin, double, double t_out) {  // free phase
        uint8_t* c = cells + lin;
        const uint8_t s = load_relaxed(c);
        if (s == kOccupied) return has_return ? VoxelVisit::kHandOver : VoxelVisit::kStop;
        if (t_out > t_free) {  // the ray leaves this voxel beyond t_free: not known to be free
          if (!has_return) return VoxelVisit::kStop;
          if (s == kNone) none_to_unknown(c);
          return VoxelVisit::kHandOver;
        }
        if (s != kEmpty) store_relaxed(c, kEmpty);
        return VoxelVisit::kNext;
      },
      [&](int64_t lin, double, double) {  // occluded phase: None -> Unknown to where it leaves B
        uint8_t* c = cells + lin;
        if (load_relaxed(c) == kNone) none_to_unknown(c);
        return VoxelVisit::kNext;
      });
}

// The block lattice of the ray set (see the top of the file).
struct Blocks {
  std::vector<int> ub, vb;  // pixel edges along u and v
  int stride = 1;
  bool wide = false;        // more than one pixel per block
  int nu() const { return static_cast<int>(ub.size()) - 1; }
  int nv() const { return static_cast<int>(vb.size()) - 1; }
};

Blocks choose_blocks(const CameraIntrinsics& k, int stride_param, const Eigen::AlignedBox3d& b,
                     const Eigen::Vector3d& cam, double res) {
  Blocks out;
  out.stride = stride_param;
  bool alt_u = false, alt_v = false;
  if (out.stride <= 0) {
    double d_max = 0;
    for (int c = 0; c < 8; ++c) d_max = std::max(d_max, (b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - cam).norm());
    const double s = std::min(k.fx, k.fy) * res / (std::sqrt(2.0) * d_max);
    out.stride = std::max(1, static_cast<int>(std::floor(s)));
    if (out.stride <= kMaxMixedStride) {
      const double a = out.stride, wide = a + 0.5;
      alt_u = wide * wide + a * a <= 2.0 * s * s;
      alt_v = s >= wide;
    }
  }
  out.ub = block_edges(k.width, out.stride, alt_u);
  out.vb = block_edges(k.height, out.stride, alt_v);
  out.wide = out.stride > 1 || alt_u;
  return out;
}

enum : uint8_t { kBlockNothing = 0, kBlockSurface = 1, kBlockFree = 2, kBlockMixed = 3 };

// Each block's kind and nearest depth.
void classify_blocks(const MapFrame& f, const Blocks& bl, double res, int nt, std::vector<uint8_t>& kinds_out,
                     std::vector<float>& zmins_out) {
  kinds_out.assign(static_cast<size_t>(bl.nu()) * bl.nv(), kBlockNothing);
  zmins_out.assign(static_cast<size_t>(bl.nu()) * bl.nv(), 0.0f);
  parallel_run(nt, [&](int tid, int n_threads) {
    // Locals: the byte stores to `kinds` may alias anything reached through the captures, so
    // these would be reloaded after every block.
    const float lo_z = f.zlo_f, hi_z = f.zhi_f;
    const float res_f = static_cast<float>(res);
    const int W_l = f.k.width, n_bu_l = bl.nu(), n_bv_l = bl.nv();
    const int* ub_l = bl.ub.data();
    const int* vb_l = bl.vb.data();
    const bool free_nr = f.free_no_return;
    const float* depth_l = f.depth;
    uint8_t* kinds = kinds_out.data();
    float* zmins = zmins_out.data();
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
}

}  // namespace

int64_t VoxelMap::walk_rays(const MapFrame& f) {
  const double res = params_.resolution_m;
  const Blocks bl = choose_blocks(f.k, params_.ray_stride_px, bounds(), f.cam, res);
  last_stride_px_ = bl.stride;
  std::vector<uint8_t> kinds;
  std::vector<float> zmins;
  classify_blocks(f, bl, res, f.workers, kinds, zmins);
  uint8_t* cells = reinterpret_cast<uint8_t*>(cells_.data());
  const VoxelLattice lattice(dims_, res);
  const Eigen::Vector3d o = f.cam - origin_;
  const int W = f.k.width, H = f.k.height, n_bu = bl.nu(), n_bv = bl.nv();
  std::vector<int64_t> rays(static_cast<std::size_t>(f.workers), 0);
  parallel_run(f.workers, [&](int tid, int n_threads) {
    int64_t n_rays = 0;
    auto ray = [&](double u, double v, double t_free, bool has_return) {
      if (cast_ray(cells, lattice, o, f.ray(u, v), t_free, has_return)) ++n_rays;
    };
    auto pixel_ray = [&](int u, int v) {  // one ray per pixel, with its own depth
      const float z = f.depth[int64_t(v) * W + u];
      if (f.valid(z)) {
        ray(u, v, z, true);
      } else if (f.free_no_return && pixel_no_return(z)) {
        ray(u, v, f.zhi, false);
      }
    };
    for (int bv = tid; bv < n_bv; bv += n_threads) {
      const int v0 = bl.vb[bv], v1 = bl.vb[bv + 1];
      for (int bu = 0; bu < n_bu; ++bu) {
        const int u0 = bl.ub[bu], u1 = bl.ub[bu + 1];
        const int64_t b = int64_t(bv) * n_bu + bu;
        const uint8_t kind = kinds[b];
        if (kind != kBlockMixed && bl.wide && (bu == 0 || bv == 0 || bu == n_bu - 1 || bv == n_bv - 1)) {
          for (int v = v0; v < v1; ++v)  // image border: one ray per pixel of the outermost row/column
            for (int u = u0; u < u1; ++u)
              if (u == 0 || v == 0 || u == W - 1 || v == H - 1) pixel_ray(u, v);
        }
        const double uc = 0.5 * (u0 + u1 - 1), vc = 0.5 * (v0 + v1 - 1);
        if (kind == kBlockSurface) {
          ray(uc, vc, zmins[b], true);  // free only up to the block's nearest depth
        } else if (kind == kBlockFree) {
          ray(uc, vc, f.zhi, false);
        } else if (kind == kBlockMixed) {
          for (int v = v0; v < v1; ++v)
            for (int u = u0; u < u1; ++u) pixel_ray(u, v);
        }
      }
    }
    rays[tid] = n_rays;
  });
  return std::accumulate(rays.begin(), rays.end(), int64_t(0));
}

}  // namespace pbnbv
