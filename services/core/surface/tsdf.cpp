// TSDF fusion of registered frames (surface.hpp) and marching cubes with PCL's tables.
#include <pcl/surface/marching_cubes.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "core/base/parallel.hpp"
#include "core/surface/surface.hpp"

namespace pbnbv {

namespace {

constexpr int kBlock = 8;  // voxels per block edge
constexpr int kBlockVoxels = kBlock * kBlock * kBlock;
// A normal's neighbours lie at least this many sigmas of the frame's depth noise apart (noise
// tilts it by about a quarter radian), at most kMaxNormalStep splat pixels. Chosen on the tune
// half's D435 frames (8 objects, 1.5-3.6 mm measured noise, 1.4-2.6 mm pixels): fixed steps of 1,
// 2, 3 and 5 pixels gave 3 and 5 alike and best, 1 worst; this rule gives 3-8 there, and 1 for an
// exact camera (its meshes unchanged).
constexpr double kNormalBaselineSigmas = 4.0;
constexpr int kMaxNormalStep = 8;

// Grid coordinates packed into one key (20 bits each, offset so negatives fit; bits 60-61 free
// for an edge's axis).
using Key = std::uint64_t;
constexpr std::int64_t kOffset = 1 << 19;
Key pack(const Eigen::Vector3i& g) {
  return (Key(g.x() + kOffset) << 40) | (Key(g.y() + kOffset) << 20) | Key(g.z() + kOffset);
}
int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

struct Block {
  Eigen::Vector3i origin;  // grid coordinates of voxel (0, 0, 0)
  std::array<float, kBlockVoxels> sdf;     // truncated distance / truncation, in [-1, 1]
  std::array<float, kBlockVoxels> weight;  // 0: never seen
};
int local_index(int x, int y, int z) { return (z * kBlock + y) * kBlock + x; }

// A frame's points splatted into a (coarser) image of its camera: the nearest point per pixel.
struct SplatImage {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<int> index;    // point per pixel, -1: none
  std::vector<float> depth;  // that point's depth along the camera's axis, m; infinity: none
};

SplatImage splat(const SurfaceFrame& f, const CameraIntrinsics& k, int scale) {
  SplatImage im;
  im.width = (k.width + scale - 1) / scale;
  im.height = (k.height + scale - 1) / scale;
  im.fx = k.fx / scale;
  im.fy = k.fy / scale;
  im.cx = (k.cx + 0.5) / scale - 0.5;
  im.cy = (k.cy + 0.5) / scale - 0.5;
  im.index.assign(std::size_t(im.width) * im.height, -1);
  im.depth.assign(im.index.size(), std::numeric_limits<float>::infinity());
  const Pose camera_T_object = f.object_T_camera.inverse();
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    const Eigen::Vector3d q = camera_T_object * f.points[i].cast<double>();
    if (!(q.z() > 0)) continue;
    const int u = int(std::lround(im.fx * q.x() / q.z() + im.cx));
    const int v = int(std::lround(im.fy * q.y() / q.z() + im.cy));
    if (u < 0 || v < 0 || u >= im.width || v >= im.height) continue;
    const std::size_t p = std::size_t(v) * im.width + u;
    if (q.z() < im.depth[p]) {
      im.depth[p] = float(q.z());
      im.index[p] = int(i);
    }
  }
  return im;
}

// The frame's depth noise, measured on its own splat: the second difference of the depths of
// three neighbours in a row, z(u-1) - 2 z(u) + z(u+1), is 6^(1/2) sigma of noise on a smooth
// surface (a surface's curvature adds little at a pixel's spacing); its median absolute value over
// the frame, steps across depth edges (beyond `max_step_m`) left out, gives sigma robustly. An
// exact camera reads close to 0. Returns the sigma in m, 0 when there are too few triples.
double measured_depth_noise(const SplatImage& im, double max_step_m) {
  const std::vector<float>& z = im.depth;
  std::vector<float> second;
  for (int v = 0; v < im.height; ++v)
    for (int u = 1; u + 1 < im.width; ++u) {
      const std::size_t p = std::size_t(v) * im.width + u;
      const float a = z[p - 1], b = z[p], c = z[p + 1];
      if (!(std::abs(a - b) < max_step_m) || !(std::abs(c - b) < max_step_m)) continue;  // an empty pixel fails too
      second.push_back(std::abs(a - 2 * b + c));
    }
  if (second.size() < 100) return 0;
  std::nth_element(second.begin(), second.begin() + second.size() / 2, second.end());
  return 1.4826 * second[second.size() / 2] / std::sqrt(6.0);
}

// A unit normal per point from its splat neighbours `step` pixels away (the cross product of the
// differences to the points left/right and above/below, either side when one is missing), turned
// to the camera; zero where the neighbours are missing or farther than `max_step_m` (a depth edge).
// A noisy camera's normals need the wider step: at one pixel the noise tilts them at random.
std::vector<Eigen::Vector3f> image_normals(const SurfaceFrame& f, const SplatImage& im, int step,
                                           double max_step_m) {
  std::vector<Eigen::Vector3f> n(f.points.size(), Eigen::Vector3f::Zero());
  const float step2 = float(max_step_m * max_step_m);
  const Eigen::Vector3f eye = f.object_T_camera.translation().cast<float>();
  auto at = [&](int u, int v) {
    return u < 0 || v < 0 || u >= im.width || v >= im.height ? -1 : im.index[std::size_t(v) * im.width + u];
  };
  // The difference across the pixel along (du, dv): both neighbours when there, else one side.
  auto across = [&](int u, int v, int du, int dv, const Eigen::Vector3f& p, Eigen::Vector3f& d) {
    const int a = at(u + du, v + dv), b = at(u - du, v - dv);
    const bool ok_a = a >= 0 && (f.points[a] - p).squaredNorm() < step2;
    const bool ok_b = b >= 0 && (f.points[b] - p).squaredNorm() < step2;
    if (!ok_a && !ok_b) return false;
    d = (ok_a ? f.points[a] : p) - (ok_b ? f.points[b] : p);
    return true;
  };
  for (int v = 0; v < im.height; ++v)
    for (int u = 0; u < im.width; ++u) {
      const int i = at(u, v);
      if (i < 0) continue;
      Eigen::Vector3f du, dv;
      if (!across(u, v, step, 0, f.points[i], du) || !across(u, v, 0, step, f.points[i], dv)) continue;
      Eigen::Vector3f c = du.cross(dv);
      const float l = c.norm();
      if (!(l > 0)) continue;
      c /= l;
      n[i] = (eye - f.points[i]).dot(c) < 0 ? Eigen::Vector3f(-c) : c;
    }
  return n;
}

// The median depth of a frame's points (every 16th), along its camera's axis; 0 without points.
double median_depth(const SurfaceFrame& f) {
  if (f.points.empty()) return 0;
  const Pose camera_T_object = f.object_T_camera.inverse();
  std::vector<double> z;
  for (std::size_t i = 0; i < f.points.size(); i += 16) z.push_back((camera_T_object * f.points[i].cast<double>()).z());
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  return z[z.size() / 2];
}

// Camera pixels per splat pixel: a splat pixel about as wide as the points' spacing at the
// frame's median depth (median_depth(f), computed once per frame by the caller).
int image_scale(const SurfaceFrame& f, double depth_m, const SurfaceSettings& s) {
  if (s.point_spacing_m <= 0 || f.points.empty()) return 1;
  const double pixel_m = depth_m / s.camera.fx;
  return std::max(1, int(std::lround(s.point_spacing_m / pixel_m)));
}

// The frame's measured noise and its normals' step: neighbours at least kNormalBaselineSigmas x
// the noise apart, so that noise tilts a normal by about a quarter radian (1 pixel for an exact
// camera).
FrameNoise frame_noise(const SplatImage& im, double depth_m, double trunc) {
  FrameNoise n;
  n.pixel_m = depth_m / im.fx;
  n.sigma_m = measured_depth_noise(im, 2.0 * trunc);
  n.normal_step = n.pixel_m > 0 ? std::clamp(int(std::ceil(kNormalBaselineSigmas * n.sigma_m / n.pixel_m)), 1, kMaxNormalStep) : 1;
  return n;
}

}  // namespace

FrameNoise tsdf_frame_noise(const SurfaceFrame& f, const SurfaceSettings& s) {
  s.validate();
  if (f.points.empty()) return {};
  const double depth_m = median_depth(f);
  return frame_noise(splat(f, s.camera, image_scale(f, depth_m, s)), depth_m, s.truncation_voxels * s.voxel_m);
}

void SurfaceSettings::validate() const {
  kMeshVoxel.checked(voxel_m);
  kMeshTruncation.checked(truncation_voxels);
  kPoissonDepth.checked(poisson_depth);
  kMeshNormalNeighbours.checked(normal_neighbours);
  kMeshFillHoles.checked(fill_holes_m);
  camera.validate();
  if (!(point_spacing_m >= 0)) throw std::invalid_argument("point spacing " + std::to_string(point_spacing_m) + " m is negative");
}

namespace {

// The TSDF's blocks of voxels, found by their block index.
struct BlockGrid {
  std::unordered_map<Key, int> block_of;
  std::vector<Block> blocks;
};

// Blocks within the truncation distance `trunc` of any point; returns, per frame, the blocks
// near its own points (the ones its integration updates).
std::vector<std::vector<int>> allocate_blocks(const std::vector<SurfaceFrame>& frames, double v, double trunc,
                                              std::size_t num_points, BlockGrid& grid) {
  // Blocks within the truncation distance of any point; each frame updates the ones near its
  // own points (as its depth image would: farther free space is left alone).
  std::unordered_map<Key, int>& block_of = grid.block_of;
  std::vector<Block>& blocks = grid.blocks;
  std::vector<std::vector<int>> frame_blocks(frames.size());
  block_of.reserve(num_points / 8);
  for (std::size_t fi = 0; fi < frames.size(); ++fi) {
    std::vector<char> listed(blocks.size(), 0);
    for (const auto& p : frames[fi].points) {
      if (!p.allFinite()) continue;
      const Eigen::Vector3d lo = (p.cast<double>().array() - trunc) / v, hi = (p.cast<double>().array() + trunc) / v;
      Eigen::Vector3i b0, b1;
      for (int a = 0; a < 3; ++a) {
        b0[a] = floor_div(int(std::floor(lo[a])), kBlock);
        b1[a] = floor_div(int(std::ceil(hi[a])), kBlock);
      }
      for (int z = b0.z(); z <= b1.z(); ++z)
        for (int y = b0.y(); y <= b1.y(); ++y)
          for (int x = b0.x(); x <= b1.x(); ++x) {
            const auto [it, added] = block_of.try_emplace(pack({x, y, z}), int(blocks.size()));
            if (added) {
              Block b;
              b.origin = Eigen::Vector3i(x, y, z) * kBlock;
              b.sdf.fill(1.0f);
              b.weight.fill(0.0f);
              blocks.push_back(b);
              listed.push_back(0);
            }
            if (!listed[it->second]) {
              listed[it->second] = 1;
              frame_blocks[fi].push_back(it->second);
            }
          }
    }
  }
  return frame_blocks;
}

// One frame into the blocks it touches, in parallel: each voxel's signed distance to the frame's
// surface (its splat at `scale` camera pixels a splat pixel, its points' median depth `depth_m`),
// truncated, averaged with the weights.
FrameNoise integrate_frame(const SurfaceFrame& f, const SurfaceSettings& s, int scale, double depth_m, double v,
                           double trunc, const std::vector<int>& touched, BlockGrid& grid) {
  const SplatImage im = splat(f, s.camera, scale);
  const FrameNoise noise = frame_noise(im, depth_m, trunc);
  const std::vector<Eigen::Vector3f> normals = image_normals(f, im, noise.normal_step, 2.0 * trunc * noise.normal_step);
  const Pose camera_T_object = f.object_T_camera.inverse();
  parallel_for(touched.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t bi = begin; bi < end; ++bi) {
      Block& b = grid.blocks[touched[bi]];
      for (int z = 0; z < kBlock; ++z)
        for (int y = 0; y < kBlock; ++y)
          for (int x = 0; x < kBlock; ++x) {
            const Eigen::Vector3d pw = (b.origin + Eigen::Vector3i(x, y, z)).cast<double>() * v;
            const Eigen::Vector3d q = camera_T_object * pw;
            if (!(q.z() > 0)) continue;
            const double uf = im.fx * q.x() / q.z() + im.cx, vf = im.fy * q.y() / q.z() + im.cy;
            const int u = int(std::lround(uf)), w = int(std::lround(vf));
            // The pixel's point, else the nearest filled neighbour (the splat has gaps).
            int idx = -1;
            static constexpr int kDu[9] = {0, 1, -1, 0, 0, 1, -1, 1, -1}, kDv[9] = {0, 0, 0, 1, -1, 1, 1, -1, -1};
            for (int n = 0; n < 9 && idx < 0; ++n) {
              const int uu = u + kDu[n], vv = w + kDv[n];
              if (uu < 0 || vv < 0 || uu >= im.width || vv >= im.height) continue;
              idx = im.index[std::size_t(vv) * im.width + uu];
            }
            if (idx < 0) continue;
            const Eigen::Vector3d p = f.points[idx].cast<double>();
            const double along = (camera_T_object * p).z() - q.z();  // > 0: the voxel is in front
            if (along < -trunc) continue;                              // hidden behind the surface
            // Point-to-plane where the point has a normal, else along the ray.
            double d = along > trunc || normals[idx].isZero() ? along : normals[idx].cast<double>().dot(pw - p);
            d = std::clamp(d, -trunc, trunc) / trunc;
            const int li = local_index(x, y, z);
            const float wsum = b.weight[li] + 1.0f;
            b.sdf[li] = float((b.sdf[li] * b.weight[li] + d) / wsum);
            b.weight[li] = wsum;
          }
    }
  }, 16);
  return noise;
}

TriangleMesh extract_surface(const BlockGrid& grid, double v) {
  // Marching cubes over every cube whose eight corners were seen. Corner c of the cube at grid
  // point g is g + offset(c) in PCL's numbering; edge e joins corners kEdge[e].
  auto corner_offset = [](int c) {
    return Eigen::Vector3i(((c & 1) ^ ((c >> 1) & 1)), (c >> 2) & 1, (c >> 1) & 1);
  };
  static constexpr int kEdge[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                       {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  auto lookup = [&](const Eigen::Vector3i& g, float& sdf) {
    const Eigen::Vector3i bk(floor_div(g.x(), kBlock), floor_div(g.y(), kBlock), floor_div(g.z(), kBlock));
    const auto it = grid.block_of.find(pack(bk));
    if (it == grid.block_of.end()) return false;
    const Block& b = grid.blocks[it->second];
    const Eigen::Vector3i l = g - b.origin;
    const int li = local_index(l.x(), l.y(), l.z());
    sdf = b.sdf[li];
    return b.weight[li] > 0;
  };
  TriangleMesh mesh;
  std::unordered_map<Key, int> vertex_of_edge;  // key: the edge's lower grid point and axis
  vertex_of_edge.reserve(grid.blocks.size() * 64);
  for (const Block& b : grid.blocks) {
    for (int z = 0; z < kBlock; ++z)
      for (int y = 0; y < kBlock; ++y)
        for (int x = 0; x < kBlock; ++x) {
          const Eigen::Vector3i g = b.origin + Eigen::Vector3i(x, y, z);
          std::array<float, 8> val;
          bool seen = true;
          const bool inside = x < kBlock - 1 && y < kBlock - 1 && z < kBlock - 1;
          for (int c = 0; c < 8 && seen; ++c) {
            const Eigen::Vector3i o = corner_offset(c);
            if (inside) {
              const int li = local_index(x + o.x(), y + o.y(), z + o.z());
              val[c] = b.sdf[li];
              seen = b.weight[li] > 0;
            } else {
              seen = lookup(g + o, val[c]);
            }
          }
          if (!seen) continue;
          int cube = 0;
          for (int c = 0; c < 8; ++c)
            if (val[c] < 0) cube |= 1 << c;
          if (pcl::edgeTable[cube] == 0) continue;
          // A sign change between two truncated values is no surface (free space against the
          // far side of a thin wall seen from elsewhere).
          bool spurious = false;
          for (int e = 0; e < 12; ++e) {
            const float a = val[kEdge[e][0]], c = val[kEdge[e][1]];
            if ((pcl::edgeTable[cube] & (1 << e)) && std::abs(a) >= 1.0f && std::abs(c) >= 1.0f) spurious = true;
          }
          if (spurious) continue;
          std::array<int, 12> vid;
          for (int e = 0; e < 12; ++e) {
            if (!(pcl::edgeTable[cube] & (1 << e))) continue;
            const int ca = kEdge[e][0], cb = kEdge[e][1];
            const Eigen::Vector3i ga = g + corner_offset(ca), gb = g + corner_offset(cb);
            const Eigen::Vector3i lo = ga.cwiseMin(gb);
            int axis = 0;
            while (ga[axis] == gb[axis]) ++axis;
            const Key key = pack(lo) | (Key(axis) << 60);
            const auto [it, added] = vertex_of_edge.try_emplace(key, int(mesh.vertices.size()));
            if (added) {
              const double t = double(val[ca]) / (double(val[ca]) - double(val[cb]));
              mesh.vertices.push_back((ga.cast<double>() + t * (gb - ga).cast<double>()) * v);
            }
            vid[e] = it->second;
          }
          for (int i = 0; pcl::triTable[cube][i] != -1; i += 3) {
            // PCL's table winds triangles counter-clockwise seen from the positive (outer) side.
            mesh.triangles.emplace_back(vid[pcl::triTable[cube][i]], vid[pcl::triTable[cube][i + 1]],
                                        vid[pcl::triTable[cube][i + 2]]);
          }
        }
  }
  return mesh;
}

}  // namespace

TriangleMesh fuse_tsdf(const std::vector<SurfaceFrame>& frames, const SurfaceSettings& s, SurfaceStats* stats) {
  s.validate();
  const double v = s.voxel_m;
  const double trunc = s.truncation_voxels * v;
  std::size_t num_points = 0;
  for (const auto& f : frames) num_points += f.points.size();
  if (num_points == 0) throw std::invalid_argument("TSDF fusion: the frames hold no points");
  BlockGrid grid;
  const std::vector<std::vector<int>> frame_blocks = allocate_blocks(frames, v, trunc, num_points, grid);
  // Integration, frame by frame, blocks in parallel.
  std::vector<int> scales, steps;
  std::vector<double> sigmas;
  for (std::size_t fi = 0; fi < frames.size(); ++fi) {
    if (frames[fi].points.empty()) continue;
    const double depth_m = median_depth(frames[fi]);
    const int scale = image_scale(frames[fi], depth_m, s);
    scales.push_back(scale);
    const FrameNoise n = integrate_frame(frames[fi], s, scale, depth_m, v, trunc, frame_blocks[fi], grid);
    sigmas.push_back(n.sigma_m);
    steps.push_back(n.normal_step);
  }
  TriangleMesh mesh = extract_surface(grid, v);
  if (stats) {
    stats->frames = frames.size();
    stats->points = num_points;
    stats->voxels = grid.blocks.size() * kBlockVoxels;
    if (!scales.empty()) {
      auto median = [](auto& x) {
        std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
        return x[x.size() / 2];
      };
      stats->image_scale = median(scales);
      stats->depth_noise_m = median(sigmas);
      stats->normal_step = median(steps);
    }
  }
  return mesh;
}

}  // namespace pbnbv
