// Information gain by ray casting (raycast.hpp).
#include "core/planning/raycast.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace pbnbv {

void RaycastParams::validate() const {
  camera.validate();
  range.validate();
  if (!(std::isfinite(ray_spacing_voxels) && ray_spacing_voxels > 0)) {
    std::ostringstream os;
    os << "raycast: ray_spacing_voxels = " << ray_spacing_voxels << " must be a positive number";
    throw std::invalid_argument(os.str());
  }
  if (threads < 0) throw std::invalid_argument("raycast: threads = " + std::to_string(threads) + " must be >= 0");
}

PixelRect projected_box(const Eigen::AlignedBox3d& box, const CameraIntrinsics& k, const Pose& object_T_camera) {
  const Pose camera_T_object = object_T_camera.inverse();
  PixelRect r{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
              -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  int behind = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = camera_T_object * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    if (p.z() <= 1e-9) {
      ++behind;
      continue;
    }
    const double u = k.fx * p.x() / p.z() + k.cx + 0.5, v = k.fy * p.y() / p.z() + k.cy + 0.5;
    r.u0 = std::min(r.u0, u);
    r.u1 = std::max(r.u1, u);
    r.v0 = std::min(r.v0, v);
    r.v1 = std::max(r.v1, v);
  }
  if (behind == 8) return PixelRect{};  // all of it behind the camera
  if (behind > 0) return PixelRect{0, 0, double(k.width), double(k.height)};
  r.u0 = std::max(r.u0, 0.0);
  r.v0 = std::max(r.v0, 0.0);
  r.u1 = std::min(r.u1, double(k.width));
  r.v1 = std::min(r.v1, double(k.height));
  return r;
}

namespace {

// Slab test: the parameter interval [t0, t1] of o + t d inside the box (t0 > t1: a miss).
void clip_to_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
                 const Eigen::Vector3d& hi, double& t0, double& t1) {
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (o[a] < lo[a] || o[a] > hi[a]) {
        t0 = 1;
        t1 = 0;
        return;
      }
      continue;
    }
    double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
}

struct Caster {
  const VoxelGrid& grid;
  const RaycastParams& p;
  std::vector<uint32_t> stamp;  // per voxel: tag of the last view that counted it

  // Counts the unobserved voxels along one ray (grid units: position pg, direction qg; the ray
  // parameter t is planar depth in metres) in [t0, t1].
  int64_t cast(const Eigen::Vector3d& pg, const Eigen::Vector3d& qg, double t0, double t1, uint32_t tag) {
    const Eigen::Vector3i& n = grid.dims;
    Eigen::Vector3i i;
    for (int a = 0; a < 3; ++a) {
      i[a] = std::clamp(static_cast<int>(std::floor(pg[a] + t0 * qg[a])), 0, n[a] - 1);
    }
    const int64_t stride[3] = {1, int64_t(n.x()), int64_t(n.x()) * n.y()};
    int64_t lin = i.x() + stride[1] * i.y() + stride[2] * i.z();
    int step[3];
    double t_max[3], t_delta[3];
    for (int a = 0; a < 3; ++a) {
      if (qg[a] > 0) {
        step[a] = 1;
        t_max[a] = (i[a] + 1 - pg[a]) / qg[a];
        t_delta[a] = 1.0 / qg[a];
      } else if (qg[a] < 0) {
        step[a] = -1;
        t_max[a] = (i[a] - pg[a]) / qg[a];
        t_delta[a] = -1.0 / qg[a];
      } else {
        step[a] = 0;
        t_max[a] = t_delta[a] = std::numeric_limits<double>::infinity();
      }
    }
    int64_t count = 0;
    const VoxelState* cells = grid.cells.data();
    uint32_t* st = stamp.data();
    double t = t0;
    while (t < t1) {
      const VoxelState s = cells[lin];
      if (s == VoxelState::kOccupied) break;
      if (s != VoxelState::kEmpty && st[lin] != tag) {
        st[lin] = tag;
        ++count;
      }
      const int a = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
      t = t_max[a];
      i[a] += step[a];
      if (i[a] < 0 || i[a] >= n[a]) break;
      lin += step[a] * stride[a];
      t_max[a] += t_delta[a];
    }
    return count;
  }

  RaycastGain view(const Pose& object_T_camera, uint32_t tag) {
    RaycastGain g;
    const Eigen::AlignedBox3d box = grid.bounds();
    const PixelRect rect = projected_box(box, p.camera, object_T_camera);
    if (rect.empty()) return g;
    const Eigen::Vector3d o = object_T_camera.translation();
    const Eigen::Matrix3d R = object_T_camera.linear();
    const double res = grid.resolution_m;
    const double dist = std::max((box.center() - o).norm(), p.range.min_m);
    const double su = std::max(1.0, p.camera.fx * res * p.ray_spacing_voxels / dist);
    const double sv = std::max(1.0, p.camera.fy * res * p.ray_spacing_voxels / dist);
    g.spacing_px = su;
    const Eigen::Vector3d pg = (o - grid.origin_m) / res;
    const Eigen::Vector3d lo = box.min(), hi = box.max();
    for (double v = rect.v0 + 0.5 * sv; v < rect.v1; v += sv) {
      for (double u = rect.u0 + 0.5 * su; u < rect.u1; u += su) {
        // Pixel centre (u - 0.5, v - 0.5) in the image convention of back_project.
        const Eigen::Vector3d d = R * Eigen::Vector3d((u - 0.5 - p.camera.cx) / p.camera.fx,
                                                      (v - 0.5 - p.camera.cy) / p.camera.fy, 1.0);
        double t0 = p.range.min_m, t1 = p.range.max_m;
        clip_to_box(o, d, lo, hi, t0, t1);
        ++g.rays;
        if (t0 >= t1) continue;
        g.unknown += cast(pg, d / res, t0, t1, tag);
      }
    }
    return g;
  }
};

}  // namespace

std::vector<RaycastGain> raycast_gains(const VoxelGrid& grid, const std::vector<Pose>& views,
                                       const std::vector<uint8_t>& active, const RaycastParams& params) {
  grid.validate("raycast: voxel grid");
  params.validate();
  if (!active.empty() && active.size() != views.size()) {
    throw std::invalid_argument("raycast: active has " + std::to_string(active.size()) + " entries for " +
                                std::to_string(views.size()) + " views");
  }
  std::vector<RaycastGain> out(views.size());
  if (grid.empty() || views.empty()) return out;
  std::vector<int> todo;
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (active.empty() || active[i]) todo.push_back(static_cast<int>(i));
  }
  int threads = params.threads > 0 ? params.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::clamp(threads, 1, std::max<int>(1, static_cast<int>(todo.size())));
  std::atomic<std::size_t> next{0};
  auto work = [&]() {
    Caster c{grid, params, std::vector<uint32_t>(grid.cells.size(), 0)};
    for (std::size_t k = next++; k < todo.size(); k = next++) {
      const int i = todo[k];
      out[i] = c.view(views[i], static_cast<uint32_t>(k + 1));
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  return out;
}

}  // namespace pbnbv
