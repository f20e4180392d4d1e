// The five-state voxel map (voxel_map.hpp) against geometry checkable by hand: synthetic depth
// images ray-cast analytically (cube, sphere, plane), no renderer.
#include "core/mapping/voxel_map.hpp"
#include "core/mapping/state_colour.hpp"
#include "core/perception/depth_filter.hpp"

#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>

namespace pbnbv {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3i;

// Returns the ray parameter t > 0 of the first hit of o + t d, or NaN.
using HitFn = std::function<double(const Vector3d& o, const Vector3d& d)>;

HitFn cube(double half) {
  return [half](const Vector3d& o, const Vector3d& d) {
    double t0 = -std::numeric_limits<double>::infinity();
    double t1 = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      if (std::abs(d[i]) < 1e-15) {
        if (std::abs(o[i]) > half) return std::nan("");
        continue;
      }
      double a = (-half - o[i]) / d[i], b = (half - o[i]) / d[i];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    return (t0 <= t1 && t0 > 0) ? t0 : std::nan("");
  };
}

HitFn sphere(double r) {
  return [r](const Vector3d& o, const Vector3d& d) {
    const double a = d.squaredNorm(), b = o.dot(d), c = o.squaredNorm() - r * r;
    const double disc = b * b - a * c;
    if (disc < 0) return std::nan("");
    const double t = (-b - std::sqrt(disc)) / a;
    return t > 0 ? t : std::nan("");
  };
}

// The plane n . p = offset.
HitFn plane(const Vector3d& n, double offset) {
  return [n, offset](const Vector3d& o, const Vector3d& d) {
    const double nd = n.dot(d);
    if (std::abs(nd) < 1e-12) return std::nan("");
    const double t = (offset - n.dot(o)) / nd;
    return t > 0 ? t : std::nan("");
  };
}

// Planar depth image: t is the depth because d = R (x_n, y_n, 1). Misses get `miss`.
std::vector<float> render(const CameraIntrinsics& k, const Pose& T, const HitFn& hit,
                          float miss = 0.0f) {
  std::vector<float> depth(static_cast<size_t>(k.width) * k.height, miss);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Vector3d d = T.linear() * Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      const double t = hit(T.translation(), d);
      if (std::isfinite(t)) depth[static_cast<size_t>(v) * k.width + u] = static_cast<float>(t);
    }
  }
  return depth;
}

CameraIntrinsics small_camera() {  // the D435 field of view at a quarter of the size
  CameraIntrinsics k;
  k.width = 320;
  k.height = 180;
  k.fx = k.fy = 174.0;
  k.cx = 160.0;
  k.cy = 90.0;
  return k;
}

CameraIntrinsics wide_camera() {  // 106 degrees both ways: sees all of B from 0.9 m
  CameraIntrinsics k;
  k.width = 320;
  k.height = 320;
  k.fx = k.fy = 120.0;
  k.cx = 160.0;
  k.cy = 160.0;
  return k;
}

MapUpdateResult integrate(VoxelMap& map, const CameraIntrinsics& k, const Pose& T,
                          const HitFn& hit) {
  const std::vector<float> depth = render(k, T, hit);
  DepthView view;
  view.depth_m = &depth;
  view.intrinsics = k;
  view.object_T_camera = T;
  return map.integrate(view);
}

Pose from(const Vector3d& eye) { return look_at_z_up(eye, Vector3d::Zero()); }

std::vector<VoxelState> all_states(const VoxelMap& m) {
  std::vector<VoxelState> s;
  const Vector3i n = m.dims();
  for (int z = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) s.push_back(m.state(Vector3i(x, y, z)));
  return s;
}

// Lattice index of a voxel (the map's local index + the index of B's min voxel).
Vector3i global_index(const VoxelMap& m, const Vector3i& local) {
  const Vector3d c = m.centre(local) / m.params().resolution_m;
  return Vector3i(static_cast<int>(std::floor(c.x())), static_cast<int>(std::floor(c.y())),
                  static_cast<int>(std::floor(c.z())));
}

template <class F>
void for_each_voxel(const VoxelMap& m, F f) {
  const Vector3i n = m.dims();
  for (int z = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) f(Vector3i(x, y, z));
}

// All 8 corners of the voxel project inside the image (pixel centres 0..W-1, 0..H-1) in front
// of the camera, within max range.
bool inside_frustum(const VoxelMap& m, const Vector3i& local, const CameraIntrinsics& k,
                    const Pose& T, double max_m = 3.0) {
  const double h = 0.5 * m.params().resolution_m;
  const Vector3d c = m.centre(local);
  const Eigen::Matrix3d Rt = T.linear().transpose();
  const Vector3d qc = Rt * (c - T.translation());
  for (int i = 0; i < 8; ++i) {
    const Vector3d q = qc + Rt * Vector3d((i & 1) ? h : -h, (i & 2) ? h : -h, (i & 4) ? h : -h);
    if (q.z() <= 1e-6 || q.z() > max_m) return false;
    const double u = k.fx * q.x() / q.z() + k.cx, v = k.fy * q.y() / q.z() + k.cy;
    if (u < 0 || u > k.width - 1 || v < 0 || v > k.height - 1) return false;
  }
  return true;
}

constexpr double kHalf = 0.15;  // the 0.3 m cube / sphere radius

// ---------------------------------------------------------------------------------------------
// Cube seen from +x, first frame with no other information: B and every state by hand.
TEST(VoxelMap, CubeFirstFrameHandCountedBoundsAndStates) {
  // res 0.02: the face x = 0.15 lies mid-voxel (voxel 7 = [0.14, 0.16]); the face's pixels give
  // y, z in [-0.1498, 0.1498] (|u - 640| <= 139 px at 0.75 m), voxels -8..7 = [-0.16, 0.16].
  // Occupied AABB: [0.14, 0.16] x [-0.16, 0.16]^2, size (0.02, 0.32, 0.32), diagonal 0.45299.
  // View direction camera -> box centre = -x: extend the min x face by t with
  // (0.02 + t)^2 + 2 * 0.32^2 = 4 * 0.45299^2 -> t = 0.76486, min x = -0.62486 -> lattice -0.64.
  // B = [-0.64, 0.16] x [-0.16, 0.16]^2 = 40 x 16 x 16 = 10240 voxels.
  VoxelMapParams p;
  p.resolution_m = 0.02;
  VoxelMap map(p);
  const CameraIntrinsics k;  // 1280 x 720, f = 696
  const MapUpdateResult r = integrate(map, k, from(Vector3d(0.9, 0, 0)), cube(kHalf));
  ASSERT_TRUE(r.updated) << r.message;
  EXPECT_EQ(map.dims(), Vector3i(40, 16, 16));
  EXPECT_TRUE(map.bounds().min().isApprox(Vector3d(-0.64, -0.16, -0.16), 1e-9));
  EXPECT_TRUE(map.bounds().max().isApprox(Vector3d(0.16, 0.16, 0.16), 1e-9));
  // The front layer of B is exactly the face (16 x 16 Occupied). Rays from a camera on the
  // axis diverge, so they enter B only through its front layer, which is all Occupied: free
  // rays stop there and rays with a return turn occluded, so everything behind is Unknown
  // and there is no Empty voxel, hence no Frontier either.
  EXPECT_EQ(r.counts.occupied, 256);
  EXPECT_EQ(r.counts.unknown, 10240 - 256);
  EXPECT_EQ(r.counts.empty, 0);
  EXPECT_EQ(r.counts.frontier, 0);
  EXPECT_EQ(r.counts.none, 0);
  for (const Vector3d& c : map.centres(VoxelState::kOccupied)) EXPECT_NEAR(c.x(), 0.15, 1e-9);
  const VoxelCounts c = map.counts();
  EXPECT_EQ(c.occupied, r.counts.occupied);
  EXPECT_EQ(c.unknown, r.counts.unknown);
}

// Cube seen from +x inside a larger B given up front: Occupied face layer, Empty in front,
// Unknown behind, Frontier on the rim only.
TEST(VoxelMap, CubeOneFaceStatesInLargerBox) {
  VoxelMapParams p;
  p.resolution_m = 0.02;
  VoxelMap map(p);
  // x in [-0.7, 0.5] (indices -35..24), y, z in [-0.5, 0.5] (-25..24): 60 x 50 x 50. It
  // contains the first frame's enlarged AABB (x >= -0.64), so the first frame leaves it as is.
  map.reserve_bounds(Eigen::AlignedBox3d(Vector3d(-0.7, -0.5, -0.5), Vector3d(0.5, 0.5, 0.5)));
  ASSERT_EQ(map.dims(), Vector3i(60, 50, 50));
  const CameraIntrinsics k;
  const Pose T = from(Vector3d(0.9, 0, 0));
  const MapUpdateResult r = integrate(map, k, T, cube(kHalf));
  ASSERT_TRUE(r.updated) << r.message;
  EXPECT_EQ(map.dims(), Vector3i(60, 50, 50));
  EXPECT_EQ(r.counts.occupied, 256);  // voxel x = 7, y, z = -8..7 (see the test above)

  // The occupied layer [0.14, 0.16] x [-0.16, 0.16]^2 casts the shadow
  // S = {x < 0.16, |y|, |z| <= 0.16 (0.9 - x) / 0.74} (its silhouette is its front face at
  // depth 0.74) for the free rays, which stop at it. The rays with a return only fill the
  // narrower shadow of the face's pixels, C = {|y|, |z| <= 0.1498 (0.9 - x) / 0.75}. Per
  // voxel, by its corners (S and C are convex):
  //  - Occupied iff x index 7 and y, z index in -8..7;
  //  - in front (x index >= 8) or in the face layer outside the face, inside the frustum: free
  //    along every ray -> Empty;
  //  - behind (x index <= 6), all corners inside C (so entirely behind the face): Unknown;
  //  - behind, all corners beyond the same side plane of S, inside the frustum: no ray to it
  //    passes an Occupied voxel -> Empty;
  //  - the rest straddles the boundary of S or lies between C and S: Empty, Unknown,
  //    Frontier or (between C and S, where a free ray stops at the Occupied rim and no ray
  //    with a return passes) None.
  const double s = 0.16 / 0.74;
  int64_t certain_empty = 0, certain_unknown = 0, straddling = 0;
  int ring_frontier = 0;
  for_each_voxel(map, [&](const Vector3i& l) {
    const Vector3i g = global_index(map, l);
    const VoxelState st = map.state(l);
    const bool face = g.x() == 7 && g.y() >= -8 && g.y() <= 7 && g.z() >= -8 && g.z() <= 7;
    if (face) {
      EXPECT_EQ(st, VoxelState::kOccupied);
      return;
    }
    EXPECT_NE(st, VoxelState::kOccupied);
    const bool in_view = inside_frustum(map, l, k, T);
    if (g.x() >= 7) {
      if (in_view) {
        EXPECT_EQ(st, VoxelState::kEmpty) << g.transpose();
        ++certain_empty;
      }
      return;
    }
    int inside = 0, beyond[4] = {0, 0, 0, 0};
    const Vector3d c = map.centre(l);
    for (int i = 0; i < 8; ++i) {
      const Vector3d q = c + 0.01 * Vector3d((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
      const double w = s * (0.9 - q.x()), w_cube = 0.1498 / 0.75 * (0.9 - q.x());
      inside += (std::abs(q.y()) <= w_cube && std::abs(q.z()) <= w_cube);
      beyond[0] += q.y() > w;
      beyond[1] += q.y() < -w;
      beyond[2] += q.z() > w;
      beyond[3] += q.z() < -w;
    }
    if (inside == 8) {
      EXPECT_EQ(st == VoxelState::kUnknown || st == VoxelState::kFrontier, true) << g.transpose();
      ++certain_unknown;
    } else if (std::max({beyond[0], beyond[1], beyond[2], beyond[3]}) == 8) {
      if (in_view) {
        EXPECT_EQ(st, VoxelState::kEmpty) << g.transpose();
        ++certain_empty;
      }
    } else {
      ++straddling;
    }
    // Frontier: only in the layer right behind the face (x index 6: the only Unknown voxels
    // next to an Occupied one) and only on its rim: the ring y or z index in {-8, 7} is
    // next to the Empty voxels beside the face (x 7, y or z index -9 / 8), the middle
    // (y, z in -7..6) only sees Occupied and Unknown voxels.
    if (st == VoxelState::kFrontier) {
      EXPECT_EQ(g.x(), 6) << g.transpose();
      EXPECT_FALSE(g.y() >= -7 && g.y() <= 6 && g.z() >= -7 && g.z() <= 6) << g.transpose();
    }
    const bool ring = g.x() == 6 && g.y() >= -8 && g.y() <= 7 && g.z() >= -8 && g.z() <= 7 &&
                      (g.y() == -8 || g.y() == 7 || g.z() == -8 || g.z() == 7);
    if (ring) {
      EXPECT_EQ(st, VoxelState::kFrontier) << g.transpose();
      ++ring_frontier;
    }
  });
  // The ring: 4 * 16 - 4 = 60 voxels. The only other candidates are the 68 voxels of the ring
  // just outside it (x index 6, y or z index -9 / 8, e.g. x in [0.12, 0.14], y in
  // [0.16, 0.18]): they straddle the shadow boundary S (y = 0.1643 .. 0.1686 m across the
  // voxel), and are Frontier only if no free ray crosses their outer part. Free rays leaving
  // the Occupied front face at y > 0.16 (more than 0.16 / 0.74 * 696 = 150.5 px from the image
  // centre) reach x = 0.12 at y < 0.18 for up to 0.18 / 0.78 * 696 = 160.6 px: a 10 px wide
  // band, wider than the sample ray spacing (3 px here: d_max = 1.749 m, the bound
  // 696 * 0.02 / (sqrt 2 * 1.749) = 5.6 px floored and halved to 2, raised to the 3 px that
  // keeps a 1280 x 720 image within 102,400 sample rays), so free sample rays cross every outer
  // ring voxel: they are Empty and Frontier is exactly the 60 voxel ring.
  EXPECT_EQ(map.last_ray_stride_px(), 3);
  EXPECT_EQ(ring_frontier, 60);
  EXPECT_EQ(r.counts.frontier, 60);
  // The other totals against the per-voxel geometry above: every certain voxel is checked
  // individually, and the straddling ones can only add to either side.
  EXPECT_GE(r.counts.empty, certain_empty);
  EXPECT_LE(r.counts.empty, certain_empty + straddling);
  EXPECT_GE(r.counts.unknown + r.counts.frontier, certain_unknown);
  EXPECT_LE(r.counts.unknown + r.counts.frontier, certain_unknown + straddling);
  EXPECT_EQ(r.counts.none + r.counts.empty + r.counts.occupied + r.counts.unknown +
                r.counts.frontier,
            60 * 50 * 50);
  // Right behind the face centre, x index 6 down to -35 (B's back face): Unknown.
  for (int x = -35; x <= 6; ++x) {
    const VoxelState st = map.state_at(Vector3d((x + 0.5) * 0.02, 0.0, 0.0));
    EXPECT_TRUE(st == VoxelState::kUnknown) << x;
  }
  // The column in front of the face centre, x index 8..24, is Empty.
  for (int x = 8; x <= 24; ++x) {
    EXPECT_EQ(map.state_at(Vector3d((x + 0.5) * 0.02, 0.01, 0.01)), VoxelState::kEmpty) << x;
  }
  std::printf("cube from +x in 60x50x50 B: empty %lld (certain %lld), unknown %lld, frontier %lld"
              " (certain unknown %lld, straddling %lld)\n",
              (long long)r.counts.empty, (long long)certain_empty, (long long)r.counts.unknown,
              (long long)r.counts.frontier, (long long)certain_unknown, (long long)straddling);
}

// A plane at a known depth, every voxel by hand. The plane x = 1/64 m fills the view of the
// wide camera at x = 0.5 m looking along -x, planar depth 0.5 - 1/64 = 0.484375 m at every
// pixel. The working volume (= B, reserved up front) is x -0.125..0.3125, y and z -0.125..0.125 m
// at 1/32 m voxels (binary fractions: the lattice is exact): 14 x 8 x 8 = 896 voxels, x index -4
// to 9. By the rules:
//  - Occupied: the plane's layer, x index 0 (x 0..1/32): all 8 x 8 = 64 voxels hold points;
//  - Empty: the 9 layers in front of it, x index 1..9: every ray leaves them before its return
//    (they end at x = 1/32 > 1/64) and meets no Occupied voxel first: 9 x 64 = 576;
//  - Unknown: the 4 layers behind it, x index -4..-1: behind the surface up to where the rays
//    leave B: 4 x 64 = 256;
//  - no Frontier (no Unknown voxel has an Empty 26-neighbour: layer 1 is two layers away), no None.
// Then a frame from x = -0.5 m with no return but at the centre pixel (which meets the plane):
// its free rays clear the 4 layers behind the plane, up to the Occupied layer where they stop
// (rule 4); the layers beyond it stay as they were: 64 Occupied, 832 Empty, nothing else.
// The rays walked one per pixel (reference_rays) give the same map, voxel for voxel.
TEST(VoxelMap, PlaneStatesByHand) {
  const double res = 1.0 / 32;
  const Eigen::AlignedBox3d volume(Vector3d(-0.125, -0.125, -0.125), Vector3d(0.3125, 0.125, 0.125));
  const CameraIntrinsics k = wide_camera();
  const HitFn wall = plane(Vector3d(1, 0, 0), 1.0 / 64);
  VoxelMapParams p;
  p.resolution_m = res;
  VoxelMap map(p);
  p.reference_rays = true;
  p.ray_stride_px = 1;
  VoxelMap ref(p);
  auto frame = [&](VoxelMap& m, const Pose& T, const std::vector<float>& depth) {
    DepthView view;
    view.depth_m = &depth;
    view.intrinsics = k;
    view.object_T_camera = T;
    view.working_volume = volume;
    return m.integrate(view);
  };
  const Pose front = from(Vector3d(0.5, 0, 0));
  const std::vector<float> seen = render(k, front, wall);
  for (VoxelMap* m : {&map, &ref}) {
    m->reserve_bounds(volume);
    const MapUpdateResult r = frame(*m, front, seen);
    ASSERT_TRUE(r.updated) << r.message;
    ASSERT_EQ(m->dims(), Vector3i(14, 8, 8));
    EXPECT_EQ(r.counts.occupied, 64);
    EXPECT_EQ(r.counts.empty, 576);
    EXPECT_EQ(r.counts.unknown, 256);
    EXPECT_EQ(r.counts.frontier, 0);
    EXPECT_EQ(r.counts.none, 0);
  }
  for_each_voxel(map, [&](const Vector3i& l) {
    const int x = global_index(map, l).x();
    const VoxelState want = x == 0 ? VoxelState::kOccupied : x > 0 ? VoxelState::kEmpty : VoxelState::kUnknown;
    EXPECT_EQ(map.state(l), want) << l.transpose();
  });
  EXPECT_EQ(all_states(map), all_states(ref));

  const Pose back = from(Vector3d(-0.5, 0, 0));
  std::vector<float> none(static_cast<size_t>(k.width) * k.height, 0.0f);
  none[static_cast<size_t>(k.cy) * k.width + static_cast<size_t>(k.cx)] = static_cast<float>(0.5 + 1.0 / 64);
  for (VoxelMap* m : {&map, &ref}) {
    const MapUpdateResult r = frame(*m, back, none);
    ASSERT_TRUE(r.updated) << r.message;
    EXPECT_EQ(r.counts.occupied, 64);
    EXPECT_EQ(r.counts.empty, 832);
    EXPECT_EQ(r.counts.unknown + r.counts.frontier + r.counts.none, 0);
  }
  for_each_voxel(map, [&](const Vector3i& l) {
    const int x = global_index(map, l).x();
    EXPECT_EQ(map.state(l), x == 0 ? VoxelState::kOccupied : VoxelState::kEmpty) << l.transpose();
  });
  EXPECT_EQ(all_states(map), all_states(ref));
}

// Six axis views of the cube with a wide camera: the shell is Occupied, the inside Unknown,
// everything else seen Empty, no Frontier left.
TEST(VoxelMap, SixAxisViewsLeaveNoFrontier) {
  VoxelMapParams p;
  p.resolution_m = 0.02;
  VoxelMap map(p);
  map.reserve_bounds(Eigen::AlignedBox3d(Vector3d(-0.4, -0.4, -0.4), Vector3d(0.4, 0.4, 0.4)));
  const CameraIntrinsics k = wide_camera();
  const Vector3d eyes[6] = {{0.9, 0, 0}, {-0.9, 0, 0}, {0, 0.9, 0},
                            {0, -0.9, 0}, {0, 0, 0.9}, {0, 0, -0.9}};
  MapUpdateResult r;
  for (const Vector3d& e : eyes) {
    r = integrate(map, k, from(e), cube(kHalf));
    ASSERT_TRUE(r.updated) << r.message;
  }
  // The shell: voxels of [-8, 7]^3 with an index at -8 or 7 = 16^3 - 14^3 = 1352; the inside
  // 14^3 = 2744 voxels are never seen.
  EXPECT_EQ(r.counts.frontier, 0);
  EXPECT_EQ(r.counts.occupied, 16 * 16 * 16 - 14 * 14 * 14);
  EXPECT_EQ(r.counts.unknown, 14 * 14 * 14);
  for_each_voxel(map, [&](const Vector3i& l) {
    const Vector3i g = global_index(map, l);
    const bool in_cube = (g.array() >= -8).all() && (g.array() <= 7).all();
    const bool inside = (g.array() >= -7).all() && (g.array() <= 6).all();
    const VoxelState st = map.state(l);
    if (inside) {
      EXPECT_EQ(st, VoxelState::kUnknown);
    } else if (in_cube) {
      EXPECT_EQ(st, VoxelState::kOccupied);
    } else {
      EXPECT_TRUE(st == VoxelState::kEmpty || st == VoxelState::kNone) << g.transpose();
    }
  });
}

// A sphere seen from one side: Occupied only near the visible hemisphere, Unknown behind.
TEST(VoxelMap, SphereOneSide) {
  const double res = 0.02, r_s = kHalf, d = 0.9;
  VoxelMapParams p;
  p.resolution_m = res;
  VoxelMap map(p);
  const CameraIntrinsics k;
  const MapUpdateResult r = integrate(map, k, from(Vector3d(d, 0, 0)), sphere(r_s));
  ASSERT_TRUE(r.updated) << r.message;
  // A voxel holding a surface point has its centre within sqrt(3)/2 res of that point. The
  // visible points p satisfy p . eye >= r^2 (the tangent circle at x = r^2 / d = 0.025).
  const double tol = std::sqrt(3.0) / 2.0 * res + 1e-9;
  const auto occ = map.centres(VoxelState::kOccupied);
  ASSERT_GT(occ.size(), 0u);
  for (const Vector3d& c : occ) {
    EXPECT_NEAR(c.norm(), r_s, tol) << c.transpose();
    EXPECT_GE(c.x(), r_s * r_s / d - tol) << c.transpose();
  }
  // The visible cap has area 2 pi r h with h = r - r^2/d = 0.125: 0.1178 m^2; seen along x
  // its voxels number at least its projected area / res^2 (pi 0.148^2 / 0.0004 = 172) and at
  // most about area * (1 + slope) / res^2; just a sanity window here.
  EXPECT_GT(occ.size(), 172u);
  EXPECT_LT(occ.size(), 1200u);
  // Behind the sphere along the axis: inside and in the shadow -> Unknown.
  for (double x : {0.0, -0.1, -0.2, -0.4, -0.6}) {
    EXPECT_EQ(map.state_at(Vector3d(x + 0.001, 0.001, 0.001)), VoxelState::kUnknown) << x;
  }
  // In front of the sphere's rim, inside B (the occupied AABB reaches y, z = +-0.16):
  // the corner (0.15, 0.15, 0.15) is 0.26 m from the centre and its sight line misses the
  // sphere -> Empty.
  EXPECT_EQ(map.state_at(Vector3d(0.15, 0.15, 0.15)), VoxelState::kEmpty);
  EXPECT_GT(r.counts.empty, 0);
  EXPECT_GT(r.counts.frontier, 0);
  EXPECT_GT(r.counts.unknown, r.counts.occupied);
  // Frontier voxels border both Occupied and Empty voxels, so they lie near the sphere: their
  // centres are within 2 voxels of the surface (they are next to an Occupied voxel).
  for (const Vector3d& c : map.centres(VoxelState::kFrontier)) {
    EXPECT_NEAR(c.norm(), r_s, std::sqrt(3.0) * res + tol) << c.transpose();
  }
}

// The two frontier rules (VoxelMapParams::frontier_empty) on the same sphere seen
// from one side (obliquely, from (0.9, 0.3, 0.2) m: 126 and 56 frontier voxels), checked voxel by voxel against the definition: Frontier = Unknown-or-Frontier
// with an Occupied voxel among the 26 neighbours and an Empty one among the 26 (paper) or the
// 6 face neighbours (ours). Every other state is the same in both maps; the face rule keeps
// only part of the paper's frontier (the rim beside the shadow), dropping the voxels behind the
// visible surface that touch the free space in front of it only along an edge or at a corner.
TEST(VoxelMap, FaceNeighbourFrontierFollowsItsDefinition) {
  VoxelMapParams p26, p6;
  p26.resolution_m = p6.resolution_m = 0.02;
  p6.frontier_empty = FrontierEmpty::kFaceNeighbours;
  VoxelMap m26(p26), m6(p6);
  const CameraIntrinsics k;
  const MapUpdateResult r26 = integrate(m26, k, from(Vector3d(0.9, 0.3, 0.2)), sphere(kHalf));
  const MapUpdateResult r6 = integrate(m6, k, from(Vector3d(0.9, 0.3, 0.2)), sphere(kHalf));
  ASSERT_TRUE(r26.updated && r6.updated);
  ASSERT_EQ(m26.dims(), m6.dims());
  auto at = [](const VoxelMap& m, const Vector3i& l) { return m.state(l); };  // local index; outside B: None
  auto has = [&](const VoxelMap& m, const Vector3i& l, VoxelState want, bool faces_only) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int manhattan = std::abs(dx) + std::abs(dy) + std::abs(dz);
          if (manhattan == 0 || (faces_only && manhattan != 1)) continue;
          if (at(m, l + Vector3i(dx, dy, dz)) == want) return true;
        }
    return false;
  };
  int64_t f26 = 0, f6 = 0;
  for_each_voxel(m26, [&](const Vector3i& l) {
    const VoxelState a = at(m26, l), b = at(m6, l);
    const bool unknownish = a == VoxelState::kUnknown || a == VoxelState::kFrontier;
    if (!unknownish) {
      EXPECT_EQ(a, b) << l.transpose();
      return;
    }
    ASSERT_TRUE(b == VoxelState::kUnknown || b == VoxelState::kFrontier) << l.transpose();
    const bool occ = has(m26, l, VoxelState::kOccupied, false);
    EXPECT_EQ(a == VoxelState::kFrontier, occ && has(m26, l, VoxelState::kEmpty, false)) << l.transpose();
    EXPECT_EQ(b == VoxelState::kFrontier, occ && has(m26, l, VoxelState::kEmpty, true)) << l.transpose();
    f26 += a == VoxelState::kFrontier;
    f6 += b == VoxelState::kFrontier;
  });
  EXPECT_EQ(f26, r26.counts.frontier);
  EXPECT_EQ(f6, r6.counts.frontier);
  EXPECT_GT(f6, 0);
  EXPECT_LT(f6, f26);
  std::printf("frontier voxels: 26 neighbours %lld, 6 face neighbours %lld\n", (long long)f26, (long long)f6);
}

// Frames without a valid pixel change nothing (whatever no_return_is_free says: a frame
// with no return at all carries no pose-checked evidence, see voxel_map.hpp).
TEST(VoxelMap, EmptyAndNanFramesLeaveTheMapUnchanged) {
  const CameraIntrinsics k = small_camera();
  const Pose T = from(Vector3d(0.9, 0.2, 0.1));
  const std::vector<float> zeros(k.width * k.height, 0.0f);
  const std::vector<float> nans(k.width * k.height, std::numeric_limits<float>::quiet_NaN());
  const std::vector<float> far(k.width * k.height, 7.0f);  // beyond max range: ignored
  for (bool free : {false, true}) {
    VoxelMapParams p;
    p.resolution_m = 0.03;
    p.no_return_is_free = free;
    VoxelMap map(p);
    {  // before any frame: no B either
      DepthView v{&zeros, k, DepthRange{}, T};
      const MapUpdateResult r = map.integrate(v);
      EXPECT_FALSE(r.updated);
      EXPECT_NE(r.message.find("no valid depth pixel"), std::string::npos) << r.message;
      EXPECT_TRUE(map.empty());
    }
    ASSERT_TRUE(integrate(map, k, T, sphere(kHalf)).updated);
    const auto before = all_states(map);
    const Eigen::AlignedBox3d b = map.bounds();
    for (const auto* depth : {&zeros, &nans, &far}) {
      DepthView v{depth, k, DepthRange{}, from(Vector3d(-0.9, 0, 0))};
      const MapUpdateResult r = map.integrate(v);
      EXPECT_FALSE(r.updated);
      EXPECT_NE(r.message.find("map unchanged"), std::string::npos) << r.message;
      EXPECT_NE(r.message.find("no valid depth pixel"), std::string::npos) << r.message;
      EXPECT_EQ(all_states(map), before);
      EXPECT_TRUE(map.bounds().isApprox(b));
    }
  }
}

// B: first frame = occupied AABB with doubled diagonal; never shrinks; covers gamma around
// Frontier voxels after later frames.
TEST(VoxelMap, BoundingBoxRules) {
  for (double res : {0.01, 0.02, 0.03}) {
    VoxelMapParams p;
    p.resolution_m = res;
    p.gamma_m = 0.1;
    VoxelMap map(p);
    const CameraIntrinsics k = small_camera();
    // An oblique first view so the extension runs along all three axes.
    const MapUpdateResult r0 = integrate(map, k, from(Vector3d(0.6, 0.5, 0.4)), cube(kHalf));
    ASSERT_TRUE(r0.updated);
    Eigen::AlignedBox3d occ;
    for (const Vector3d& c : map.centres(VoxelState::kOccupied)) {
      occ.extend(c - Vector3d::Constant(res / 2));
      occ.extend(c + Vector3d::Constant(res / 2));
    }
    Eigen::AlignedBox3d b = map.bounds();
    Eigen::AlignedBox3d b_tol = b;
    b_tol.extend(b.min() - Vector3d::Constant(1e-9)).extend(b.max() + Vector3d::Constant(1e-9));
    EXPECT_TRUE(b_tol.contains(occ));
    // Snapping the extended faces outward to the lattice adds < 1 voxel per extended axis.
    EXPECT_GE(b.diagonal().norm(), 2 * occ.diagonal().norm() - 1e-9) << res;
    EXPECT_LE(b.diagonal().norm(), 2 * occ.diagonal().norm() + std::sqrt(3.0) * res) << res;
    // Extended away from the camera only: the faces toward the camera stay at the AABB.
    EXPECT_NEAR(b.max().x(), occ.max().x(), 1e-9);
    EXPECT_NEAR(b.max().y(), occ.max().y(), 1e-9);
    EXPECT_NEAR(b.max().z(), occ.max().z(), 1e-9);
    EXPECT_LT(b.min().x(), occ.min().x());

    const Vector3d eyes[] = {{-0.5, 0.7, 0.2}, {0.1, -0.9, -0.3}, {0.0, 0.2, 0.95},
                             {-0.8, -0.3, -0.5}};
    bool saw_frontier = false;
    for (const Vector3d& e : eyes) {
      const MapUpdateResult r = integrate(map, k, from(e), cube(kHalf));
      ASSERT_TRUE(r.updated);
      const Eigen::AlignedBox3d nb = map.bounds();
      EXPECT_TRUE(nb.contains(b)) << "B shrank";
      for (const Vector3d& c : map.centres(VoxelState::kOccupied)) EXPECT_TRUE(nb.contains(c));
      const auto fr = map.centres(VoxelState::kFrontier);
      saw_frontier = saw_frontier || !fr.empty();
      for (const Vector3d& c : fr) {
        const Eigen::AlignedBox3d g(c - Vector3d::Constant(p.gamma_m),
                                    c + Vector3d::Constant(p.gamma_m));
        EXPECT_TRUE(nb.contains(g)) << c.transpose();
      }
      b = nb;
    }
    EXPECT_TRUE(saw_frontier);
  }
}

// A frame whose frontier voxels sit on B's boundary makes B grow by gamma around them.
TEST(VoxelMap, FrontierNearBoundaryGrowsBoxByGamma) {
  VoxelMapParams p;
  p.resolution_m = 0.02;
  p.gamma_m = 0.1;
  VoxelMap map(p);
  const CameraIntrinsics k;
  ASSERT_TRUE(integrate(map, k, from(Vector3d(0.9, 0, 0)), cube(kHalf)).updated);
  const Eigen::AlignedBox3d b1 = map.bounds();  // [-0.64, 0.16] x [-0.16, 0.16]^2
  const MapUpdateResult r = integrate(map, k, from(Vector3d(0, 0.9, 0)), cube(kHalf));
  ASSERT_TRUE(r.updated);
  ASSERT_GT(r.counts.frontier, 0);
  const Eigen::AlignedBox3d b2 = map.bounds();
  EXPECT_TRUE(b2.contains(b1));
  EXPECT_GT(b2.volume(), b1.volume());
  for (const Vector3d& c : map.centres(VoxelState::kFrontier)) {
    EXPECT_TRUE(b2.contains(Eigen::AlignedBox3d(c - Vector3d::Constant(0.1),
                                                c + Vector3d::Constant(0.1))))
        << c.transpose();
  }
  // The new voxels are None (only the old B has states).
  for_each_voxel(map, [&](const Vector3i& l) {
    if (!b1.contains(map.centre(l))) {
      EXPECT_EQ(map.state(l), VoxelState::kNone);
    }
  });
}

// Every voxel in the frustum is decided (each along the sample ray nearest to its projected
// centre, which crosses it): a wall filling the image (rays with a return) then free rays from
// behind it, with a rolled camera so the voxel lattice is at an angle to the pixel lattice.
TEST(VoxelMap, ProjectedVoxelsCoverTheFrustum) {
  for (double res : {0.005, 0.01, 0.02, 0.03}) {
    VoxelMapParams p;
    p.resolution_m = res;
    VoxelMap map(p);
    // The full-size camera: at 0.005 m the quarter-size one has voxels smaller than a pixel
    // at the far side of B (f res / (sqrt(2) d_max) < 1), where not even the nearest pixel's
    // ray is sure to cross a voxel.
    const CameraIntrinsics k;
    const Vector3d up(0.0, std::sin(0.6), std::cos(0.6));  // 34 degree roll
    const Pose T1 = look_at(Vector3d(0.2, 0.02, -0.03), Vector3d(0.0, 0.05, 0.0), up);
    // The wall x = 0.001 (inside voxel layer 0 for every res here).
    const MapUpdateResult r1 = integrate(map, k, T1, plane(Vector3d::UnitX(), 0.001));
    ASSERT_TRUE(r1.updated);
    if (res >= 0.01) {
      EXPECT_GT(map.last_ray_stride_px(), 1) << res;  // sample rays sparser than the pixels
    }
    {  // the guarantee holds when one ray per pixel is fine enough: f res / (sqrt 2 d_max) >= 1
      double d_max = 0;
      for (int c = 0; c < 8; ++c) {
        const auto corner = map.bounds().corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
        d_max = std::max(d_max, (corner - T1.translation()).norm());
      }
      ASSERT_GE(k.fx * res / (std::sqrt(2.0) * d_max), 1.0) << res;
    }
    int64_t checked = 0;
    for_each_voxel(map, [&](const Vector3i& l) {
      if (!inside_frustum(map, l, k, T1)) return;
      ++checked;
      const Vector3i g = global_index(map, l);
      const VoxelState st = map.state(l);
      if (g.x() == 0) {
        EXPECT_EQ(st, VoxelState::kOccupied) << res << " " << g.transpose();
      } else {
        EXPECT_EQ(st, VoxelState::kUnknown) << res << " " << g.transpose();
      }
    });
    EXPECT_GT(checked, 1000);
    std::printf("res %.3f: wall frame, sample rays every %d px, %lld voxels inside the frustum checked, ", res,
                map.last_ray_stride_px(), (long long)checked);
    // Free rays from behind B: every pixel without return except the centre one, which lands
    // on the wall (an Occupied voxel already).
    const Eigen::AlignedBox3d b = map.bounds();
    const Vector3d eye(b.min().x() - 0.3, 0.03, 0.01);
    const Vector3d up2(0.0, std::sin(-0.4), std::cos(-0.4));
    const Pose T2 = look_at(eye, Vector3d(0.001, 0.03, 0.01), up2);
    std::vector<float> depth(k.width * k.height, 0.0f);
    depth[static_cast<size_t>(k.cy) * k.width + static_cast<size_t>(k.cx)] =
        static_cast<float>(0.001 - eye.x());
    DepthView v{&depth, k, DepthRange{}, T2};
    ASSERT_TRUE(map.integrate(v).updated);
    checked = 0;
    for_each_voxel(map, [&](const Vector3i& l) {
      if (!b.contains(map.centre(l)) || !inside_frustum(map, l, k, T2)) return;
      const Vector3i g = global_index(map, l);
      if (g.x() >= 0) return;  // the wall and (outside B) beyond
      ++checked;
      EXPECT_EQ(map.state(l), VoxelState::kEmpty) << res << " " << g.transpose();
    });
    EXPECT_GT(checked, 1000);
    std::printf("free frame every %d px, %lld checked\n", map.last_ray_stride_px(), (long long)checked);
  }
}

// The projection against rays walked through B, one per pixel (reference_rays, ray_stride_px = 1:
// the rules read literally). gamma = 0 and a reserved B keep both maps on the same B (B then only
// grows by Occupied voxels, which both record from every pixel), so the states can be compared
// voxel by voxel after every frame. At most 1 % of the classified voxels differ (0.61 % at most
// here, 1280 x 720 at 0.03 m), every one on an interface of the reference map.
TEST(VoxelMap, ProjectionMatchesPerPixelRays) {
  struct Case {
    const char* name;
    HitFn hit;
  };
  const Case objects[] = {{"cube", cube(kHalf)}, {"sphere", sphere(kHalf)}};
  const Vector3d eyes[] = {{0.9, 0, 0}, {0.3, 0.75, 0.4}, {-0.6, -0.2, 0.65}};
  // The quarter-size camera (f = 174) only at 0.03 m: finer voxels are about a pixel at the far
  // side of B; the full-size one at all three resolutions.
  for (const CameraIntrinsics& k : {small_camera(), CameraIntrinsics{}}) {
    for (double res : {0.03, 0.02, 0.01}) {
      if (k.width < 1280 && res < 0.03) continue;
      const int n_eyes = k.width < 1280 ? 3 : 2;  // (the reference at full size is slow)
      for (const Case& c : objects) {
        if (k.width == 1280 && res < 0.02 && std::string(c.name) == "cube") continue;
        VoxelMapParams p;
        p.resolution_m = res;
        p.gamma_m = 0.0;
        VoxelMap fast(p);
        p.ray_stride_px = 1;
        p.reference_rays = true;
        VoxelMap ref(p);
        const Eigen::AlignedBox3d box(Vector3d::Constant(-0.5), Vector3d::Constant(0.5));
        fast.reserve_bounds(box);
        ref.reserve_bounds(box);
        for (int i_eye = 0; i_eye < n_eyes; ++i_eye) {
          const Vector3d& e = eyes[i_eye];
          const MapUpdateResult rf = integrate(fast, k, from(e), c.hit);
          const MapUpdateResult rr = integrate(ref, k, from(e), c.hit);
          ASSERT_TRUE(rf.updated && rr.updated);
          ASSERT_EQ(fast.dims(), ref.dims());
          ASSERT_TRUE(fast.bounds().isApprox(ref.bounds()));
          int64_t differ = 0, classified = 0, missed = 0, off_interface = 0;
          int64_t empty_vs_unknown = 0, unknown_vs_empty = 0, frontier_flip = 0;
          for_each_voxel(ref, [&](const Vector3i& l) {
            const VoxelState a = fast.state(l), b = ref.state(l);
            if (b != VoxelState::kNone) ++classified;
            if (a == b) return;
            ++differ;
            if (a == VoxelState::kNone) {
              ++missed;
            } else if (b == VoxelState::kEmpty && a != VoxelState::kEmpty) {
              ++empty_vs_unknown;
            } else if (a == VoxelState::kEmpty) {
              ++unknown_vs_empty;
            } else {
              ++frontier_flip;
            }
            // Every difference lies on an interface of the reference map: a voxel with a
            // 26-neighbour in another state (the edge of a shadow, of the frustum, or a
            // Frontier/Unknown decided by such a neighbour), never inside a uniform region.
            bool interface = false;
            for (int dz = -1; dz <= 1 && !interface; ++dz)
              for (int dy = -1; dy <= 1 && !interface; ++dy)
                for (int dx = -1; dx <= 1 && !interface; ++dx)
                  interface = ref.state(l + Vector3i(dx, dy, dz)) != b;
            if (!interface) ++off_interface;
          });
          EXPECT_EQ(rf.counts.occupied, rr.counts.occupied);
          std::printf("%4dx%-4d %-6s res %.2f eye (%5.2f %5.2f %5.2f) sample rays every %d px: %7lld voxels"
                      " projected vs %6lld rays;"
                      " E/U/F fast %lld/%lld/%lld ref %lld/%lld/%lld; differ %lld of %lld"
                      " (None in fast %lld, ref Empty fast Unknown/Frontier %lld, ref"
                      " Unknown/Frontier fast Empty %lld, Unknown<->Frontier %lld); ref %.0f ms\n",
                      k.width, k.height, c.name, res, e.x(), e.y(), e.z(),
                      fast.last_ray_stride_px(), (long long)rf.projected, (long long)rr.rays, (long long)rf.counts.empty,
                      (long long)rf.counts.unknown, (long long)rf.counts.frontier,
                      (long long)rr.counts.empty, (long long)rr.counts.unknown,
                      (long long)rr.counts.frontier, (long long)differ, (long long)classified,
                      (long long)missed, (long long)empty_vs_unknown,
                      (long long)unknown_vs_empty, (long long)frontier_flip, rr.time_s * 1e3);
          EXPECT_LE(differ, classified / 100) << c.name << " " << res;
          EXPECT_EQ(off_interface, 0) << c.name << " " << res;
        }
      }
    }
  }
}

// Two runs give the same map (each voxel is written by one worker, and every decision reads only
// the frame and the map before the phase, so the result does not depend on the workers).
TEST(VoxelMap, Deterministic) {
  VoxelMapParams p;
  p.resolution_m = 0.01;
  VoxelMap a(p), b(p);
  const CameraIntrinsics k;
  for (const Vector3d& e : {Vector3d(0.9, 0, 0), Vector3d(0.2, 0.6, 0.6)}) {
    integrate(a, k, from(e), sphere(kHalf));
    integrate(b, k, from(e), sphere(kHalf));
  }
  EXPECT_EQ(all_states(a), all_states(b));
}

// A square patch of the plane x = 1/64 m (|y|, |z| < 0.0624 m) seen head-on from x = 0.5 m,
// in a working volume (= B) of x -0.125..0.3125, y and z -0.125..0.125 m at 1/32 m voxels
// (binary fractions: the lattice is exact): 14 x 8 x 8 = 896 cells. By hand: Occupied is the
// patch's 4 x 4 = 16 cells of layer x 0..1/32; the 9 layers in front of it (x 1/32..0.3125,
// 9 x 64 = 576 cells) are all seen free; the cells straight behind the patch's centre are in its
// shadow (Unknown or Frontier).
TEST(VoxelMap, WriteOctomapHoldsOnlyWhatWasObserved) {
  const double res = 1.0 / 32;
  VoxelMapParams p;
  p.resolution_m = res;
  VoxelMap map(p);
  const Eigen::AlignedBox3d volume(Vector3d(-0.125, -0.125, -0.125), Vector3d(0.3125, 0.125, 0.125));
  map.reserve_bounds(volume);
  const CameraIntrinsics k = wide_camera();
  const Pose T = from(Vector3d(0.5, 0, 0));
  const HitFn flat = plane(Vector3d(1, 0, 0), 1.0 / 64);
  const HitFn patch = [&](const Vector3d& o, const Vector3d& d) {
    const double t = flat(o, d);
    const Vector3d q = o + t * d;
    return (std::abs(q.y()) < 0.0624 && std::abs(q.z()) < 0.0624) ? t : std::nan("");
  };
  const std::vector<float> depth = render(k, T, patch);
  DepthView view;
  view.depth_m = &depth;
  view.intrinsics = k;
  view.object_T_camera = T;
  view.working_volume = volume;
  const MapUpdateResult r = map.integrate(view);
  ASSERT_TRUE(r.updated) << r.message;
  ASSERT_EQ(map.dims(), Vector3i(14, 8, 8));
  EXPECT_EQ(r.counts.occupied, 16);
  ASSERT_GT(r.counts.unknown + r.counts.frontier, 0);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("pbnbv_voxel_map_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  map.write_octomap((dir / "map.ot").string());
  map.write_states_ply((dir / "map.states.ply").string());
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read((dir / "map.ot").string()));
  ASSERT_TRUE(tree);
  // A plain OcTree: octomap_server's default type and MoveIt's only accepted id.
  EXPECT_EQ(tree->getTreeType(), "OcTree");
  auto* color = dynamic_cast<octomap::OcTree*>(tree.get());
  ASSERT_NE(color, nullptr) << tree->getTreeType();
  EXPECT_NEAR(color->getResolution(), res, 1e-12);
  // The tree holds exactly the Occupied cells (occupied) and the Empty ones (free).
  int64_t occupied = 0, free = 0;
  for (auto it = color->begin_leafs(); it != color->end_leafs(); ++it) {
    const int64_t n = std::llround(std::pow(it.getSize() / res, 3));  // in case a reader prunes
    (color->isNodeOccupied(*it) ? occupied : free) += n;
    const octomap::point3d c = it.getCoordinate();
    const VoxelState s = map.state_at(Vector3d(c.x(), c.y(), c.z()));
    EXPECT_EQ(s, color->isNodeOccupied(*it) ? VoxelState::kOccupied : VoxelState::kEmpty) << c;
  }
  EXPECT_EQ(occupied, 16);
  EXPECT_EQ(free, r.counts.empty);
  // The patch: occupied. x 1/64, y and z -3/64 .. 3/64 in steps of 1/32.
  for (int j = -2; j < 2; ++j) {
    for (int l = -2; l < 2; ++l) {
      const auto* node = color->search(1.0 / 64, (j + 0.5) * res, (l + 0.5) * res);
      ASSERT_NE(node, nullptr) << j << " " << l;
      EXPECT_TRUE(color->isNodeOccupied(node)) << j << " " << l;
    }
  }
  // In front of it: free, all 576 cells.
  int front_free = 0;
  for (int i = 1; i < 10; ++i) {
    for (int j = -4; j < 4; ++j) {
      for (int l = -4; l < 4; ++l) {
        const auto* node = color->search((i + 0.5) * res, (j + 0.5) * res, (l + 0.5) * res);
        front_free += node != nullptr && !color->isNodeOccupied(node);
      }
    }
  }
  EXPECT_EQ(front_free, 576);
  // Straight behind the patch's centre (4 layers x 2 x 2 cells): in its shadow, not in the tree.
  for (int i = -4; i < 0; ++i) {
    for (int j = -1; j < 1; ++j) {
      for (int l = -1; l < 1; ++l) {
        const Vector3d c((i + 0.5) * res, (j + 0.5) * res, (l + 0.5) * res);
        const VoxelState s = map.state_at(c);
        EXPECT_TRUE(s == VoxelState::kUnknown || s == VoxelState::kFrontier) << to_string(s) << " at " << c.transpose();
        EXPECT_EQ(color->search(c.x(), c.y(), c.z()), nullptr) << c.transpose();
      }
    }
  }
  // Every Unknown and Frontier cell is absent: a consumer reads it as unknown, never occupied.
  for (const VoxelState s : {VoxelState::kUnknown, VoxelState::kFrontier}) {
    for (const Vector3d& c : map.centres(s)) EXPECT_EQ(color->search(c.x(), c.y(), c.z()), nullptr) << to_string(s);
  }

  // The states file: every cell of B once, with its state and colour.
  std::ifstream in(dir / "map.states.ply", std::ios::binary);
  std::string line, header;
  std::size_t vertices = 0;
  while (std::getline(in, line) && line != "end_header") {
    header += line + "\n";
    if (line.rfind("element vertex ", 0) == 0) vertices = std::stoul(line.substr(15));
  }
  EXPECT_NE(header.find("property uchar state\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"),
            std::string::npos) << header;
  ASSERT_EQ(vertices, 896u);
  int64_t per_state[5] = {0, 0, 0, 0, 0};
  for (std::size_t i = 0; i < vertices; ++i) {
    float xyz[3];
    unsigned char srgb[4];
    in.read(reinterpret_cast<char*>(xyz), 12);
    in.read(reinterpret_cast<char*>(srgb), 4);
    ASSERT_TRUE(in) << "cut short at cell " << i;
    ASSERT_LE(srgb[0], 4);
    const VoxelState s = static_cast<VoxelState>(srgb[0]);
    EXPECT_EQ(map.state_at(Vector3d(xyz[0], xyz[1], xyz[2])), s);
    EXPECT_EQ((Rgb{srgb[1], srgb[2], srgb[3]}), state_colour(s));
    ++per_state[srgb[0]];
  }
  EXPECT_EQ(per_state[static_cast<int>(VoxelState::kOccupied)], 16);
  EXPECT_EQ(per_state[static_cast<int>(VoxelState::kEmpty)], r.counts.empty);
  EXPECT_EQ(per_state[static_cast<int>(VoxelState::kUnknown)], r.counts.unknown);
  EXPECT_EQ(per_state[static_cast<int>(VoxelState::kFrontier)], r.counts.frontier);
  EXPECT_EQ(per_state[static_cast<int>(VoxelState::kNone)], r.counts.none);

  // OctoMap's own tool reads it (it crashed on the ColorOcTree this file used to be): the tree
  // against itself differs by nothing (KLD 0), and it counts the observed cells as leaves.
  const std::string compare = "compare_octrees " + (dir / "map.ot").string() + " " + (dir / "map.ot").string() + " 2>&1";
  FILE* pipe = ::popen(compare.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string said;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) said += buf;
  const int status = ::pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << compare << " (octomap-tools, scripts/test):\n" << said;
  EXPECT_NE(said.find("Expanded num. leafs: " + std::to_string(16 + r.counts.empty) + "\n"), std::string::npos) << said;
  EXPECT_NE(said.find("KLD: 0\n"), std::string::npos) << said;
  std::filesystem::remove_all(dir);
}

TEST(VoxelMap, RejectsBadInput) {
  VoxelMapParams p;
  p.resolution_m = 0;
  EXPECT_THROW(VoxelMap{p}, std::invalid_argument);
  p.resolution_m = 0.02;
  p.gamma_m = -1;
  EXPECT_THROW(VoxelMap{p}, std::invalid_argument);
  p.gamma_m = 0.1;
  VoxelMap map(p);
  const CameraIntrinsics k = small_camera();
  const std::vector<float> wrong(10, 1.0f);
  DepthView v{&wrong, k, DepthRange{}, Pose::Identity()};
  EXPECT_THROW(map.integrate(v), std::invalid_argument);
  v.depth_m = nullptr;
  EXPECT_THROW(map.integrate(v), std::invalid_argument);
  EXPECT_STREQ(to_string(VoxelState::kFrontier), "Frontier");
}

}  // namespace
// A cube standing on a ground plane (the turntable top at z = -0.15), seen obliquely from above:
// with the working volume above the ground, the ground's points are not Occupied and B never
// reaches below the ground; the ground still clears the rays that meet it beside the cube.
TEST(VoxelMap, WorkingVolumeKeepsTheGroundOutOfTheMap) {
  const CameraIntrinsics k = small_camera();
  const HitFn cube_fn = cube(kHalf);
  const HitFn ground = plane(Vector3d::UnitZ(), -kHalf);
  const HitFn scene = [&](const Vector3d& o, const Vector3d& d) {
    const double a = cube_fn(o, d), b = ground(o, d);
    if (std::isnan(a)) return b;
    if (std::isnan(b)) return a;
    return std::min(a, b);
  };
  const Pose T = from(Vector3d(0.7, 0.2, 0.5));
  const std::vector<float> depth = render(k, T, scene);
  const double res = 0.03;
  VoxelMapParams p;
  p.resolution_m = res;
  DepthView view;
  view.depth_m = &depth;
  view.intrinsics = k;
  view.object_T_camera = T;

  // Without a working volume the ground is Occupied, far beyond the cube.
  VoxelMap unlimited(p);
  unlimited.integrate(view);
  int ground_occupied = 0;
  for (const auto& c : unlimited.centres(VoxelState::kOccupied)) ground_occupied += c.z() < -kHalf + 0.5 * res;
  EXPECT_GT(ground_occupied, 100);

  // With it (the ground plus 4 mm clearance is its floor) only the cube is.
  VoxelMap map(p);
  view.working_volume = Eigen::AlignedBox3d(Vector3d(-0.5, -0.5, -kHalf + 0.004), Vector3d(0.5, 0.5, 0.5));
  const MapUpdateResult r = map.integrate(view);
  ASSERT_TRUE(r.updated) << r.message;
  const auto occupied = map.centres(VoxelState::kOccupied);
  ASSERT_FALSE(occupied.empty());
  for (const auto& c : occupied) {
    // Every Occupied voxel touches the cube (its centre within half a voxel diagonal of it).
    const Vector3d outside = (c.cwiseAbs() - Vector3d::Constant(kHalf)).cwiseMax(0.0);
    EXPECT_LE(outside.norm(), std::sqrt(3.0) / 2 * res + 1e-9) << c.transpose();
  }
  // B stays inside the working volume (up to the voxel the floor cuts through).
  EXPECT_GE(map.bounds().min().z(), -kHalf + 0.004 - res - 1e-9);
  EXPECT_LE(map.bounds().max().x(), 0.5 + res);
  // The ground beside the cube cleared free space above it: Empty voxels exist in B.
  EXPECT_GT(map.counts().empty, 0);
  // All points outside the volume: the map is unchanged and says so.
  VoxelMap nothing(p);
  view.working_volume = Eigen::AlignedBox3d(Vector3d(2, 2, 2), Vector3d(3, 3, 3));
  const MapUpdateResult none = nothing.integrate(view);
  EXPECT_FALSE(none.updated);
  EXPECT_NE(none.message.find("working volume"), std::string::npos) << none.message;
  EXPECT_TRUE(nothing.empty());
}

}  // namespace pbnbv

namespace pbnbv {
namespace {

// A restarted mapping service continues from the saved map: the restored map has B and every
// cell of the saved one, and the next frame leaves both identical.
TEST(VoxelMap, ASavedMapRestoresAndContinuesIdentically) {
  VoxelMapParams p;
  p.resolution_m = 0.02;
  VoxelMap map(p);
  const CameraIntrinsics k = small_camera();
  ASSERT_TRUE(integrate(map, k, from(Vector3d(0.6, 0.5, 0.4)), cube(kHalf)).updated);
  VoxelMap restored = VoxelMap::restore(map.serialise(), p, "maps/state.bin");
  EXPECT_EQ(restored.dims(), map.dims());
  EXPECT_TRUE(restored.bounds().isApprox(map.bounds()));
  EXPECT_EQ(all_states(restored), all_states(map));
  EXPECT_EQ(restored.counts().occupied, map.counts().occupied);
  ASSERT_TRUE(integrate(map, k, from(Vector3d(-0.6, 0.3, 0.5)), cube(kHalf)).updated);
  ASSERT_TRUE(integrate(restored, k, from(Vector3d(-0.6, 0.3, 0.5)), cube(kHalf)).updated);
  EXPECT_EQ(restored.dims(), map.dims());
  EXPECT_EQ(all_states(restored), all_states(map));
  // An empty map round-trips too.
  EXPECT_TRUE(VoxelMap::restore(VoxelMap(p).serialise(), p, "empty").empty());
}

TEST(VoxelMap, ABadSavedMapIsNamed) {
  VoxelMapParams p;
  p.resolution_m = 0.02;
  VoxelMap map(p);
  ASSERT_TRUE(integrate(map, small_camera(), from(Vector3d(0.6, 0.5, 0.4)), cube(kHalf)).updated);
  const std::string bytes = map.serialise();
  const auto error = [&](const std::string& b, const VoxelMapParams& q) {
    try {
      VoxelMap::restore(b, q, "maps/state.bin");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error("not a map", p), "maps/state.bin is not a saved voxel map");
  EXPECT_NE(error(bytes.substr(0, 20), p).find("maps/state.bin is cut short"), std::string::npos);
  EXPECT_NE(error(bytes.substr(0, bytes.size() - 1), p).find("cells for a grid of"), std::string::npos);
  VoxelMapParams coarse = p;
  coarse.resolution_m = 0.03;
  EXPECT_NE(error(bytes, coarse).find("was saved at resolution 0.020000 m, the map is at 0.030000 m"), std::string::npos);
  std::string bad_cell = bytes;
  bad_cell.back() = 9;
  EXPECT_NE(error(bad_cell, p).find("a cell state 9"), std::string::npos);
}

// A grid from a message with dims whose product overflows (4996 x 951255040 x 0: zero cells, so
// the count matched, and empty() multiplied in int; found by fuzz_messages): refused per axis.
TEST(VoxelGrid, DimsBeyondTheirBoundAreRefusedBeforeTheyAreMultiplied) {
  VoxelGrid g;
  g.dims = Eigen::Vector3i(4996, 951255040, 0);
  g.resolution_m = 0.03;
  try {
    g.validate("VOXEL_MAP of view 3");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("VOXEL_MAP of view 3: dims 4996 x 951255040 x 0 must be at most 65536 per axis"),
              std::string::npos) << e.what();
  }
  g.dims = Eigen::Vector3i(65536, 65536, 0);
  EXPECT_NO_THROW(g.validate("grid"));
  EXPECT_TRUE(g.empty());
}

}  // namespace
}  // namespace pbnbv

namespace pbnbv {
namespace {

// Ten views of the 0.15 m sphere from 0.9 m through a noisy camera: depth noise 0.002 z (1.5 mm
// on the sphere), and 0.2 % of the pixels read at a random depth in front of what they see
// (speckles floating in free space). Through the depth filter, as the mapping service takes
// frames, no Occupied voxel lies in free space (every one holds the sphere's surface: its centre
// within sqrt(3)/2 res + 3 sigma of it) and no Frontier voxel is farther than a voxel more.
// Without the filter the speckles make Occupied voxels in free space: the filter is what holds.
TEST(VoxelMap, TenNoisyViewsOfASphereMakeNoOccupiedOrFrontierVoxelInFreeSpace) {
  const double res = 0.02;
  const CameraIntrinsics k = small_camera();
  const double sigma_max = 0.002 * 0.9;
  const double tol = std::sqrt(3.0) / 2.0 * res + 3 * sigma_max;
  for (const bool filtered : {true, false}) {
    VoxelMapParams p;
    p.resolution_m = res;
    VoxelMap map(p);
    std::mt19937_64 rng(17);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int view = 0; view < 10; ++view) {
      const double azimuth = 2 * M_PI * view / 10, elevation = (view % 2 ? 0.35 : -0.2);
      const Vector3d eye = 0.9 * Vector3d(std::cos(elevation) * std::cos(azimuth),
                                          std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const Pose T = from(eye);
      std::vector<float> depth = render(k, T, sphere(kHalf));
      for (float& z : depth) {
        if (z > 0 && uniform(rng) < 0.002) {
          z = static_cast<float>(0.3 + uniform(rng) * (z - 0.35));  // a speck between the camera and the sphere
        } else if (z > 0) {
          z = static_cast<float>(z + 0.002 * z * noise(rng));
        }
      }
      if (filtered) filter_depth(depth, k);
      DepthView v;
      v.depth_m = &depth;
      v.intrinsics = k;
      v.object_T_camera = T;
      ASSERT_TRUE(map.integrate(v).updated);
    }
    int stray_occupied = 0, stray_frontier = 0;
    for (const Vector3d& c : map.centres(VoxelState::kOccupied)) stray_occupied += std::abs(c.norm() - kHalf) > tol;
    for (const Vector3d& c : map.centres(VoxelState::kFrontier)) {
      stray_frontier += std::abs(c.norm() - kHalf) > tol + std::sqrt(3.0) * res;
    }
    if (filtered) {
      EXPECT_EQ(stray_occupied, 0);
      EXPECT_EQ(stray_frontier, 0);
      EXPECT_GT(map.centres(VoxelState::kOccupied).size(), 500u);
    } else {
      EXPECT_GT(stray_occupied, 10);
    }
  }
}

}  // namespace
}  // namespace pbnbv
