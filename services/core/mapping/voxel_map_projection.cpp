// Phase 4 of VoxelMap::integrate(): free and hidden space (docs/method.md "Voxel map", rules 2-4)
// by projecting B's voxels into the depth image instead of walking rays through B.
//
// The rules along one pixel's ray p (t = planar depth along it): the ray has a return at depth
// z_p, or is free up to max range (no return), or casts nothing (ignored pixel). Let t_occ(p) be
// where it first enters an Occupied voxel of B. A voxel V that the ray crosses over [t_in, t_out]
//  - becomes Empty when t_out <= z_p (free rays: max range) and t_in < t_occ(p), i.e. the ray
//    leaves V before its return and meets no Occupied voxel before V (Occupied stays Occupied);
//  - otherwise, if the ray has a return, goes from None to Unknown (it lies behind the surface,
//    or behind the first Occupied voxel, or holds the return, up to where the ray leaves B).
// A walk along the ray visits the voxels in order and stops where the rules say; the decision for
// V needs only z_p, t_occ(p) and V's [t_in, t_out], so it can be taken voxel by voxel:
//  a. Sample rays: the pixels 0, s, 2s, ... (and the last one) along u and along v (only where B
//     projects), each with its depth class and z_p. The spacing: the bound
//       b = min(fx, fy) * resolution / (sqrt(2) * d_max),
//     d_max the largest distance from the camera centre to a corner of B, floored, halved, raised
//     to keep the image within kSampleBudget sample rays, never above floor(b) (sample_stride).
//  b. t_occ of every sample ray: each Occupied voxel in the view frustum is intersected (slab
//     test) with the sample rays inside its projection whose free part could reach it.
//  c. Every voxel of B in the view frustum (a row of voxels is clipped against the frustum's
//     planes) that a rule can still change (None, Unknown, Frontier: Empty and Occupied are final
//     here) is projected (its centre) and decided along the sample ray nearest to that
//     projection. Its planar depth lies in centre +- h, h = res/2 * |R e_z|_1 (R e_z the optical
//     axis in the object frame), so when min(z_p, t_occ) >= centre + h it is free and when
//     min(z_p, t_occ) <= centre - h it is not, without intersecting it; voxels near that depth,
//     and those whose centre projects outside the image (the nearest sample ray then may miss
//     them), are intersected exactly. Where the nearest ray does not make the voxel Empty, the
//     other sample rays inside its projection decide as the walk along all of them would: Empty
//     when any of them sees it free, else Unknown when any with a return crosses it. Tiles of
//     sample rays bound how far any of their rays is free, so that a voxel that none of the rays
//     around it can decide otherwise skips this (most of them).
// Why the nearest sample ray crosses V when V's centre projects inside the image: V contains a
// ball of radius res/2; seen from distance d <= d_max, the rays that hit it fill a disk of radius
// >= f * (res/2) / d pixels around the projection of its centre (a ray at angle a from the
// ball's axis meets the image plane >= a f pixels from the axis' image point, the plane being
// >= f from the camera centre). The nearest sample is within s/2 along u and along v, so within
// s / sqrt(2) <= f res / (2 d_max) of the centre's projection: inside that disk. When b < 1
// (voxels under ~1.4 pixels at the far side of B) not even the nearest pixel promises it; every
// voxel is then intersected exactly (a voxel its ray misses is left to the other sample rays).
// Why half of b: the more sample rays a voxel's projection holds, the closer step c comes to
// one ray per pixel (in ProjectionMatchesPerPixelRays up to 1.7 % of the classified voxels
// differed with floor(b), 0.61 % with half of it).
// Cost: one projection per voxel of B in view that can still change and, for the few near a
// surface or a shadow's edge, some slab tests; the walk it replaces visited every voxel once per
// ray crossing it (several rays per voxel on the side of B near the camera, since the ray spacing
// is set by the far side), Empty ones included.
// Differences to one ray per pixel, all on an interface between two states (measured in
// voxel_map_test ProjectionMatchesPerPixelRays): a voxel is judged along the sample rays that
// cross it, the walk along all the pixels' rays that cross it. They differ where those rays
// disagree: (a) at the edge of a shadow (behind a silhouette or a depth jump), where a sliver of
// the voxel narrower than the sample spacing is seen free (or hidden) by some pixels' rays only;
// (b) likewise behind an Occupied voxel, of this frame or an earlier one, that some pixels' rays
// pass beside; (c) in front of a surface, where a voxel in a step of the voxelised surface is
// left before an Occupied voxel by some rays only; (d) at the border of the view (a voxel whose
// centre projects outside the image is judged by the sample rays on the image border); (e) a
// voxel reaching behind the camera plane is not projected at all (the walk starts at the camera).
//
// Threads (core/base/parallel.hpp), only where the work pays for another one's start: the sample
// rays by rows, t_occ by bands of sample rows, the voxels by interleaved z-slices; each voxel is
// written by one worker only, and every decision depends on the frame and the map before this
// phase only, so the result does not depend on the number of workers.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "core/base/parallel.hpp"
#include "core/mapping/voxel_map.hpp"
#include "core/mapping/voxel_map_frame.hpp"

namespace pbnbv {

namespace {

using namespace voxel_cell;
using Eigen::Vector3d;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Work per worker below which another worker does not pay for its start (a thread start costs
// about as much as projecting a few thousand voxels): voxels projected, cells scanned, sample
// rays read, and sample rays intersected with an Occupied voxel.
constexpr int64_t kVoxelsPerWorker = 100000;
constexpr int64_t kCellsPerWorker = 1000000;
constexpr int64_t kSamplesPerWorker = 400000;
constexpr int64_t kCrossingsPerWorker = 100000;

// The sample pixels along one image axis of n pixels: 0, s, 2s, ... and n - 1.
struct SampleAxis {
  int n, s, count;
  double inv_s;
  SampleAxis(int n_px, int stride)
      : n(n_px), s(stride), count((n_px - 1 + stride - 1) / stride + 1), inv_s(1.0 / stride) {}
  int pixel(int i) const { return std::min(i * s, n - 1); }
  // The sample nearest to c in [0, n - 1]: within s / 2 of it.
  int nearest(double c) const { return std::min(static_cast<int>(c * inv_s + 0.5), count - 1); }
  // The samples whose pixel lies in [lo, hi]: [*first, *last]; false when there is none.
  bool within(double lo, double hi, int* first, int* last) const {
    lo = std::max(lo, 0.0);
    hi = std::min(hi, static_cast<double>(n - 1));
    if (!(lo <= hi)) return false;
    *first = static_cast<int>(std::ceil(lo * inv_s));
    *last = hi >= n - 1 ? count - 1 : static_cast<int>(std::floor(hi * inv_s));
    return *first <= *last;
  }
};

// One sample ray: limit > 0: a return at depth limit; limit < 0: no return, free up to -limit;
// 0: no ray. occ: t_occ, where it first enters an Occupied voxel (infinite: never).
struct Sample {
  float limit;
  float occ;
};

// Over a tile of samples: the farthest any of their rays is free (max of min(|limit|, occ)),
// whether any has a return.
struct TileBound {
  float limit = 0.0f;
  uint8_t any_return = 0;
};

// Where the ray o + t d (t >= 0; voxel units relative to B's min corner) enters and leaves the
// voxel with min corner c. It crosses the voxel over a positive length iff *t_in < *t_out.
inline void cross(const Vector3d& o, const Vector3d& d, const Vector3d& c, double* t_in, double* t_out) {
  double a = 0.0, b = kInf;
  for (int k = 0; k < 3; ++k) {
    const double rel = c[k] - o[k];
    if (std::abs(d[k]) < 1e-15) {  // parallel to the slab: inside it or never
      if (rel > 0.0 || rel + 1.0 <= 0.0) b = -1.0;
      continue;
    }
    const double inv = 1.0 / d[k];
    double t1 = rel * inv, t2 = (rel + 1.0) * inv;
    if (t1 > t2) std::swap(t1, t2);
    a = std::max(a, t1);
    b = std::min(b, t2);
  }
  *t_in = a;
  *t_out = b;
}

// The voxel lattice of B as the camera sees it: the camera-frame centre of voxel (x, y, z) is
// q0 + x ex + y ey + z ez; planar depths within a voxel span centre +- half_depth.
struct VoxelView {
  Vector3d q0, ex, ey, ez;
  Vector3d o;                 // the camera centre, voxel units relative to B's min corner
  double half_depth = 0;
  double rho = 0;             // half a voxel's diagonal, m
  // The frustum of the pixel centres' rays (u in [0, W-1], v in [0, H-1]) and the camera's near
  // side, as half-spaces n . q + m >= 0 in the camera frame: m makes them hold for every voxel
  // that reaches into the half-space (m = res/2 |R n|_1); the near one holds for voxels wholly
  // in front of the camera.
  Vector3d n[5];
  double m[5];

  VoxelView(const MapFrame& f, const Vector3d& origin, double res) {
    const Eigen::Matrix3d Rt = f.R.transpose();
    q0 = Rt * (origin + Vector3d::Constant(0.5 * res) - f.cam);
    ex = Rt.col(0) * res;
    ey = Rt.col(1) * res;
    ez = Rt.col(2) * res;
    o = (f.cam - origin) / res;
    half_depth = 0.5 * res * f.R.col(2).lpNorm<1>();
    rho = 0.5 * std::sqrt(3.0) * res;
    const CameraIntrinsics& k = f.k;
    n[0] = Vector3d(k.fx, 0, k.cx);
    n[1] = Vector3d(-k.fx, 0, k.width - 1 - k.cx);
    n[2] = Vector3d(0, k.fy, k.cy);
    n[3] = Vector3d(0, -k.fy, k.height - 1 - k.cy);
    for (int i = 0; i < 4; ++i) m[i] = 0.5 * res * (f.R * n[i]).lpNorm<1>();
    n[4] = Vector3d(0, 0, 1);
    m[4] = -half_depth - 1e-9;
  }
  Vector3d centre(int x, int y, int z) const { return q0 + x * ex + y * ey + z * ez; }
  // How far (px, along u and v) the projection of the voxel centred at q (camera frame), whose
  // nearest point lies at planar depth near, reaches from that of q. A corner q + d projects
  // f (d_x - t d_z) / (q_z + d_z) px from it along u (t = q_x / q_z), d = (+-ex +- ey +- ez) / 2:
  // at most f |ex_x - t ex_z| + |ey_x - t ey_z| + |ez_x - t ez_z| / (2 near); likewise along v.
  Eigen::Vector2d reach_px(const Vector3d& q, double near, const CameraIntrinsics& k) const {
    const double tu = q.x() / q.z(), tv = q.y() / q.z(), half = 0.5 / near;
    return Eigen::Vector2d(k.fx * half * (std::abs(ex.x() - tu * ex.z()) + std::abs(ey.x() - tu * ey.z()) +
                                          std::abs(ez.x() - tu * ez.z())),
                           k.fy * half * (std::abs(ex.y() - tv * ex.z()) + std::abs(ey.y() - tv * ey.z()) +
                                          std::abs(ez.y() - tv * ez.z())));
  }
  // The voxels x0..x1 (inclusive) of row (y, z) that may be in view; false when none.
  bool clip_row(int y, int z, int nx, int* x0, int* x1) const {
    const Vector3d q = centre(0, y, z);
    double lo = 0, hi = nx - 1;
    for (int i = 0; i < 5; ++i) {
      const double a = n[i].dot(q) + m[i], b = n[i].dot(ex);  // a + b x >= 0
      if (b > 0) {
        lo = std::max(lo, -a / b);
      } else if (b < 0) {
        hi = std::min(hi, a / -b);
      } else if (a < 0) {
        return false;
      }
    }
    if (!(lo <= hi)) return false;
    *x0 = static_cast<int>(std::ceil(lo));
    *x1 = static_cast<int>(std::floor(hi));
    return *x0 <= *x1;
  }
};

// The sample rays of the frame (step a) and, once their t_occ is known (bound_tiles), bounds
// over tiles of `tile` x `tile` samples, each widened to its 3 x 3 neighbour tiles: step c uses
// them to skip the voxels that no sample ray around the nearest one can decide otherwise.
struct SampleRays {
  SampleAxis u, v;
  std::vector<Vector3d> a, b;  // ray (i, j) = a[i] + b[j]: voxel units per metre of planar depth
  Sample* at;                  // [j * u.count + i]
  bool crosses_nearest = false;  // the nearest sample ray crosses every voxel projected inside
  double d_max = 1.0;            // the largest distance from the camera centre to B, m
  int wi0 = 0, wi1 = -1, wj0 = 0, wj1 = -1;  // the samples read from the image
  int tile = 1, tiles_u = 1, tiles_v = 1;
  std::vector<TileBound> near_tiles;  // [tj * tiles_u + ti]: over the tile and its neighbours

  // `store`: the map's scratch (kept between frames, so that a frame does not fault its pages in).
  // Only the samples in the pixel window (where B projects) are read from the image; the others
  // are set to cast no ray (no voxel of B projects there).
  SampleRays(const MapFrame& f, int stride, double res, const Eigen::AlignedBox2d& window, std::vector<float>& store)
      : u(f.k.width, stride), v(f.k.height, stride) {
    a.resize(u.count);
    b.resize(v.count);
    for (int i = 0; i < u.count; ++i) a[i] = f.R.col(0) * ((u.pixel(i) - f.k.cx) / f.k.fx / res);
    for (int j = 0; j < v.count; ++j) b[j] = (f.R.col(1) * ((v.pixel(j) - f.k.cy) / f.k.fy) + f.R.col(2)) / res;
    static_assert(sizeof(Sample) == 2 * sizeof(float), "a sample is two floats");
    store.resize(2 * static_cast<size_t>(u.count) * v.count);
    at = reinterpret_cast<Sample*>(store.data());
    // The window in samples, one more on each side (a centre projected at its edge may round
    // outward).
    if (u.within(window.min().x(), window.max().x(), &wi0, &wi1) && v.within(window.min().y(), window.max().y(), &wj0, &wj1)) {
      wi0 = std::max(0, wi0 - 1);
      wi1 = std::min(u.count - 1, wi1 + 1);
      wj0 = std::max(0, wj0 - 1);
      wj1 = std::min(v.count - 1, wj1 + 1);
    }
    const float no_return = f.free_no_return ? -f.zhi_f : 0.0f;
    const size_t n_samples = static_cast<size_t>(u.count) * v.count;
    parallel_run(worker_count(n_samples, kSamplesPerWorker, v.count), [&](int tid, int n_threads) {
      for (int j = tid; j < v.count; j += n_threads) {
        Sample* out = at + int64_t(j) * u.count;
        const bool in_rows = j >= wj0 && j <= wj1;
        if (!in_rows || wi0 > 0 || wi1 < u.count - 1) std::memset(out, 0, sizeof(Sample) * u.count);
        if (!in_rows) continue;
        const float* row = f.depth + int64_t(v.pixel(j)) * f.k.width;
        for (int i = wi0; i <= wi1; ++i) {
          const float z = row[u.pixel(i)];
          out[i].limit = f.valid(z) ? z : pixel_no_return(z) ? no_return : 0.0f;
          out[i].occ = std::numeric_limits<float>::infinity();
        }
      }
    });
  }

  // The tile bounds, for tiles of `tile_samples` samples: over a tile, the farthest any of its
  // rays is free (min(|limit|, occ)) and whether any has a return; then over its neighbours.
  void bound_tiles(int tile_samples) {
    tile = tile_samples;
    tiles_u = (u.count + tile - 1) / tile;
    tiles_v = (v.count + tile - 1) / tile;
    std::vector<TileBound> own(static_cast<size_t>(tiles_u) * tiles_v);
    for (int j = std::max(0, wj0); j <= wj1; ++j) {
      const Sample* row = at + int64_t(j) * u.count;
      TileBound* t_row = own.data() + int64_t(j / tile) * tiles_u;
      for (int ti = wi0 / tile; ti <= wi1 / tile && wi0 <= wi1; ++ti) {
        float reach = t_row[ti].limit;
        uint8_t any_return = t_row[ti].any_return;
        for (int i = std::max(wi0, ti * tile); i <= std::min(wi1, (ti + 1) * tile - 1); ++i) {
          reach = std::max(reach, std::min(std::abs(row[i].limit), row[i].occ));
          any_return |= row[i].limit > 0.0f;
        }
        t_row[ti] = TileBound{reach, any_return};
      }
    }
    near_tiles.assign(own.size(), TileBound{});
    for (int tj = 0; tj < tiles_v; ++tj) {
      for (int ti = 0; ti < tiles_u; ++ti) {
        TileBound& nb = near_tiles[int64_t(tj) * tiles_u + ti];
        for (int sj = std::max(0, tj - 1); sj <= std::min(tiles_v - 1, tj + 1); ++sj) {
          for (int si = std::max(0, ti - 1); si <= std::min(tiles_u - 1, ti + 1); ++si) {
            const TileBound& t = own[int64_t(sj) * tiles_u + si];
            nb.limit = std::max(nb.limit, t.limit);
            nb.any_return |= t.any_return;
          }
        }
      }
    }
  }
  Vector3d ray(int i, int j) const { return a[i] + b[j]; }
  Sample& operator()(int i, int j) { return at[int64_t(j) * u.count + i]; }
  const Sample& operator()(int i, int j) const { return at[int64_t(j) * u.count + i]; }
};

// The largest distance from the camera centre to a corner of B, and the smallest planar depth of
// a corner (of any point of B: planar depth is linear).
double farthest_corner(const Eigen::AlignedBox3d& b, const Vector3d& cam) {
  double d = 0;
  for (int c = 0; c < 8; ++c) d = std::max(d, (b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - cam).norm());
  return d;
}
double nearest_depth(const Eigen::AlignedBox3d& b, const MapFrame& f) {
  double z = kInf;
  for (int c = 0; c < 8; ++c) z = std::min(z, f.R.col(2).dot(b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - f.cam));
  return z;
}

// The pixels where B projects (the box of its corners' projections, which holds the projection
// of every point of B when all corners lie in front of the camera), or the whole image.
Eigen::AlignedBox2d image_window(const Eigen::AlignedBox3d& b, const MapFrame& f) {
  Eigen::AlignedBox2d w;
  for (int c = 0; c < 8; ++c) {
    const Vector3d q = f.R.transpose() * (b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - f.cam);
    if (q.z() <= 1e-9) return Eigen::AlignedBox2d(Eigen::Vector2d::Zero(), Eigen::Vector2d(f.k.width - 1, f.k.height - 1));
    w.extend(Eigen::Vector2d(f.k.fx * q.x() / q.z() + f.k.cx, f.k.fy * q.y() / q.z() + f.k.cy));
  }
  return w;
}

// The Occupied voxels of B in view (lattice indices relative to B).
std::vector<Eigen::Vector3i> occupied_in_view(const VoxelView& vv, const uint8_t* cells, const Eigen::Vector3i& dims) {
  const int nx = dims.x(), ny = dims.y(), nz = dims.z();
  const int nt = worker_count(static_cast<size_t>(dims.prod()), kCellsPerWorker, nz);
  std::vector<std::vector<Eigen::Vector3i>> found(static_cast<size_t>(nt));
  parallel_run(nt, [&](int tid, int n_threads) {
    for (int z = tid; z < nz; z += n_threads) {
      for (int y = 0; y < ny; ++y) {
        int x0, x1;
        if (!vv.clip_row(y, z, nx, &x0, &x1)) continue;
        const uint8_t* row = cells + int64_t(nx) * (y + int64_t(ny) * z);
        for (int x = x0; x <= x1; ++x)
          if (row[x] == kOccupied) found[tid].emplace_back(x, y, z);
      }
    }
  });
  std::vector<Eigen::Vector3i> all = std::move(found[0]);
  for (int t = 1; t < nt; ++t) all.insert(all.end(), found[t].begin(), found[t].end());
  return all;
}

// Step b: t_occ of every sample ray from the Occupied voxels in view (lattice indices relative
// to B). Workers take bands of sample rows, so each sample is written by one worker.
void occluders(const MapFrame& f, const VoxelView& vv, const std::vector<Eigen::Vector3i>& occupied,
               SampleRays& rays) {
  // About (f res / (z s))^2 sample rays in the projection of a voxel at depth z; z >= d_max / 2
  // for most of them.
  const double per_voxel = std::pow(2.0 * f.k.fx * vv.rho / (rays.u.s * rays.d_max) + 1.0, 2.0);
  const int nt = worker_count(static_cast<size_t>(occupied.size() * per_voxel), kCrossingsPerWorker, rays.v.count);
  parallel_run(nt, [&](int tid, int n_threads) {
    const int band0 = rays.v.count * tid / n_threads, band1 = rays.v.count * (tid + 1) / n_threads - 1;
    for (const Eigen::Vector3i& w : occupied) {
      const Vector3d q = vv.centre(w.x(), w.y(), w.z());
      const double near = q.z() - vv.half_depth;
      if (near <= 1e-9) continue;  // reaches behind the camera plane: no footprint to project
      const double inv = 1.0 / q.z(), pu = f.k.fx * q.x() * inv + f.k.cx, pv = f.k.fy * q.y() * inv + f.k.cy;
      const Eigen::Vector2d r = vv.reach_px(q, near, f.k);
      int i0, i1, j0, j1;
      if (!rays.u.within(pu - r.x(), pu + r.x(), &i0, &i1) || !rays.v.within(pv - r.y(), pv + r.y(), &j0, &j1)) continue;
      j0 = std::max(j0, band0);
      j1 = std::min(j1, band1);
      const Vector3d c = w.cast<double>();
      for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
          Sample& s = rays(i, j);
          // Only a ray whose free part could reach the voxel: otherwise t_occ changes no decision.
          if (s.limit == 0.0f || near >= std::min(std::abs(s.limit), s.occ)) continue;
          double t_in, t_out;
          cross(vv.o, rays.ray(i, j), c, &t_in, &t_out);
          if (t_in < t_out && t_in < s.occ) s.occ = static_cast<float>(t_in);
        }
      }
    }
  });
}

enum Verdict : int { kNothing = 0, kHidden = 1, kFree = 2 };

// Whether the kRun cells from c are all Empty or Occupied (16 at a time with GCC's vector
// extension; most of B is Empty after a few frames).
constexpr int kRun = 16;
inline bool all_final(const uint8_t* c) {
  typedef uint8_t Bytes __attribute__((vector_size(kRun)));
  Bytes v;
  std::memcpy(&v, c, sizeof(v));
  const Bytes other = (v != kEmpty) & (v != kOccupied);
  uint64_t w[2];
  std::memcpy(w, &other, sizeof(w));
  return (w[0] | w[1]) == 0;
}

// Sample ray (i, j)'s verdict on the voxel with min corner c (voxel units), intersected exactly:
// kFree (Empty), kHidden (None -> Unknown) or kNothing.
int exact_verdict(const Sample& s, const SampleRays& rays, int i, int j, const Vector3d& o, const Vector3d& c) {
  if (s.limit == 0.0f) return kNothing;
  double t_in, t_out;
  cross(o, rays.ray(i, j), c, &t_in, &t_out);
  if (!(t_in < t_out)) return kNothing;  // the ray misses the voxel
  if (t_in < s.occ && t_out <= std::abs(s.limit)) return kFree;
  return s.limit > 0.0f ? kHidden : kNothing;
}

// Step c, per voxel: the projection of its centre, its nearest sample ray and the verdict.
struct Projector {
  const MapFrame& f;
  const VoxelView& vv;
  const SampleRays& rays;
  double tile_depth = 0;  // from this near depth on, a voxel's neighbour tiles hold its projection

  // The verdict of the sample rays [i0, i1] x [j0, j1] other than (i, j) on the voxel, given v0,
  // that of (i, j): Empty when any of them frees it, else Unknown when any with a return crosses
  // it. Only the rays that could change v0 are intersected.
  int refine(int v0, int i, int j, int i0, int i1, int j0, int j1, const Vector3d& c, double near) const {
    int best = v0;
    for (int jj = j0; jj <= j1; ++jj) {
      for (int ii = i0; ii <= i1; ++ii) {
        const Sample& n = rays(ii, jj);
        if ((ii == i && jj == j) || n.limit == 0.0f) continue;
        const bool may_free = near < std::min(std::abs(n.limit), n.occ);
        if (!may_free && !(best == kNothing && n.limit > 0.0f)) continue;
        const int v = exact_verdict(n, rays, ii, jj, vv.o, c);
        if (v == kFree) return kFree;
        best = std::max(best, v);
      }
    }
    return best;
  }

  // The rare cases, out of line: the verdict of the nearest ray (i, j), given (v0) or, when the
  // depth interval does not decide it (exact), by intersection; then that of the other sample
  // rays in the projection of the voxel (min corner c, centre q, projected at (pu, pv)).
  [[gnu::noinline]] int settle(int v0, bool exact, int i, int j, double pu, double pv, const Vector3d& q,
                               const Vector3d& c) const {
    int v = exact ? exact_verdict(rays(i, j), rays, i, j, vv.o, c) : v0;
    if (v == kFree) return v;
    const double near = q.z() - vv.half_depth;
    const Eigen::Vector2d r = vv.reach_px(q, near, f.k);
    int i0, i1, j0, j1;
    if (!rays.u.within(pu - r.x(), pu + r.x(), &i0, &i1) || !rays.v.within(pv - r.y(), pv + r.y(), &j0, &j1)) return v;
    return refine(v, i, j, i0, i1, j0, j1, c, near);
  }

  // Step c for one row of voxels x0..x1 at (y, z). Returns the voxels projected.
  int64_t decide_row(uint8_t* row, int x0, int x1, int y, int z) const {
    // Locals: the byte stores to `row` may alias anything reached through members.
    const double fx = f.k.fx, fy = f.k.fy, cx = f.k.cx, cy = f.k.cy;
    const double u_max = f.k.width - 1, v_max = f.k.height - 1, h = vv.half_depth, tile_z = tile_depth;
    const bool crosses = rays.crosses_nearest;
    const Sample* at = rays.at;
    const TileBound* tiles = rays.near_tiles.data();
    const int nu = rays.u.count, nv = rays.v.count, tile = rays.tile, tiles_u = rays.tiles_u;
    const double inv_su = rays.u.inv_s, inv_sv = rays.v.inv_s;
    const Vector3d q_row = vv.centre(0, y, z), ex = vv.ex;
    int64_t projected = 0;
    for (int x = x0; x <= x1; ++x) {
      if ((x & (kRun - 1)) == 0 && x + kRun - 1 <= x1 && all_final(row + x)) {
        x += kRun - 1;  // a run of voxels that no rule changes here
        continue;
      }
      const uint8_t state = row[x];
      if (state == kOccupied || state == kEmpty) continue;  // final: no rule changes them here
      ++projected;
      const Vector3d q = q_row + x * ex;
      const double inv = 1.0 / q.z();
      const double pu = fx * q.x() * inv + cx, pv = fy * q.y() * inv + cy;
      const Vector3d c(x, y, z);
      int v;
      if (!(crosses && pu >= 0 && pu <= u_max && pv >= 0 && pv <= v_max)) {
        // Projected outside the image (or voxels too small to promise a crossing): exactly.
        const int i = rays.u.nearest(std::clamp(pu, 0.0, u_max)), j = rays.v.nearest(std::clamp(pv, 0.0, v_max));
        v = settle(kNothing, true, i, j, pu, pv, q, c);
      } else {
        const int i = std::min(static_cast<int>(pu * inv_su + 0.5), nu - 1);
        const int j = std::min(static_cast<int>(pv * inv_sv + 0.5), nv - 1);
        const Sample s = at[int64_t(j) * nu + i];
        const float reach = std::min(std::abs(s.limit), s.occ);
        const double near = q.z() - h;
        if (s.limit != 0.0f && q.z() + h <= reach) {
          v = kFree;  // wholly in front of where the ray stops being free
        } else {
          const bool decided = s.limit == 0.0f || near >= reach;  // nothing, or wholly behind it
          v = decided && s.limit > 0.0f ? kHidden : kNothing;
          const bool want_hide = v == kNothing && state == kNone;
          // No ray of the neighbour tiles reaches the voxel, or could hide it where needed:
          // the nearest ray's verdict stands.
          const TileBound& t = tiles[int64_t(j / tile) * tiles_u + i / tile];
          if (!decided || near < tile_z || near < t.limit || (want_hide && t.any_return)) {
            v = settle(v, !decided, i, j, pu, pv, q, c);
          }
        }
      }
      if (v == kFree) {
        if (state != kEmpty) row[x] = kEmpty;
      } else if (v == kHidden && state == kNone) {
        row[x] = kUnknown;
      }
    }
    return projected;
  }
};

// The sample spacing (see the top of the file): half the bound (the more sample rays a voxel's
// projection holds, the closer the refinement comes to one ray per pixel), but not so fine that
// the image has more than kSampleBudget of them (their t_occ is the costly part), and never
// coarser than the bound, which every voxel's crossing by its nearest sample ray needs.
constexpr double kSampleBudget = 102400;  // one per 3 x 3 pixels of a 1280 x 720 image
int sample_stride(double bound, const CameraIntrinsics& k) {
  const int whole = std::max(1, static_cast<int>(std::min(std::floor(bound), 1e6)));
  const int budget = static_cast<int>(std::ceil(std::sqrt(double(k.width) * k.height / kSampleBudget)));
  return std::min(whole, std::max({1, whole / 2, budget}));
}

}  // namespace

int64_t VoxelMap::project_voxels(const MapFrame& f) {
  const double res = params_.resolution_m;
  const Eigen::AlignedBox3d box = bounds();
  const double d_max = farthest_corner(box, f.cam);
  const double bound = std::min(f.k.fx, f.k.fy) * res / (std::sqrt(2.0) * d_max);
  const int stride = sample_stride(bound, f.k);
  last_stride_px_ = stride;
  const VoxelView vv(f, origin_, res);
  // A voxel's projection reaches at most f rho sqrt(1 + t^2) / (its near depth) px from its
  // centre's (t: the tangent of the angle off the optical axis, within the image at most
  // sqrt(tu^2 + tv^2); VoxelView::reach_px is the tighter bound per voxel).
  const double tu = std::max(f.k.cx, f.k.width - 1 - f.k.cx) / f.k.fx, tv = std::max(f.k.cy, f.k.height - 1 - f.k.cy) / f.k.fy;
  const double footprint = std::max(f.k.fx, f.k.fy) * vv.rho * std::sqrt(1.0 + tu * tu + tv * tv);
  // Tiles wide enough for the projection of B's nearest voxels, within reason.
  const double z_near = std::max(nearest_depth(box, f), 0.05);
  const int tile = std::clamp(static_cast<int>(std::ceil(footprint / z_near / stride + 0.5)), 4, 32);
  SampleRays rays(f, stride, res, image_window(box, f), samples_);
  rays.crosses_nearest = bound >= 1.0;
  rays.d_max = d_max;
  uint8_t* cells = reinterpret_cast<uint8_t*>(cells_.data());
  occluders(f, vv, occupied_in_view(vv, cells, dims_), rays);
  rays.bound_tiles(tile);
  // The neighbour tiles hold every sample within (tile - 1/2) s px of the nearest one's.
  const Projector p{f, vv, rays, footprint / ((tile - 0.5) * stride)};

  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  const int nt = worker_count(static_cast<size_t>(dims_.prod()), kVoxelsPerWorker, nz);
  std::vector<int64_t> projected(static_cast<size_t>(nt), 0);
  parallel_run(nt, [&](int tid, int n_threads) {
    for (int z = tid; z < nz; z += n_threads) {
      for (int y = 0; y < ny; ++y) {
        int x0, x1;
        if (!vv.clip_row(y, z, nx, &x0, &x1)) continue;
        projected[tid] += p.decide_row(cells + int64_t(nx) * (y + int64_t(ny) * z), x0, x1, y, z);
      }
    }
  });
  int64_t total = 0;
  for (int64_t d : projected) total += d;
  return total;
}

}  // namespace pbnbv
