// Information gain by ray casting (raycast.hpp).
#include "core/planning/raycast.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "core/base/parallel.hpp"
#include "core/geometry/voxel_traversal.hpp"

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

struct Caster {
  const VoxelGrid& grid;
  const RaycastParams& p;
  std::vector<uint32_t> stamp;  // per voxel: tag of the last view that counted it

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
    const VoxelLattice lattice{grid.dims, res};
    const Eigen::Vector3d o_grid = o - grid.origin_m;  // relative to the grid's min corner
    const double t_near = p.range.min_m, t_far = p.range.max_m;
    int64_t unknown = 0;
    const VoxelState* cells = grid.cells.data();
    uint32_t* st = stamp.data();
    for (double v = rect.v0 + 0.5 * sv; v < rect.v1; v += sv) {
      for (double u = rect.u0 + 0.5 * su; u < rect.u1; u += su) {
        // Pixel centre (u - 0.5, v - 0.5) in the image convention of back_project; t is the
        // planar depth, so the depth range bounds it directly.
        const Eigen::Vector3d d = R * Eigen::Vector3d((u - 0.5 - p.camera.cx) / p.camera.fx,
                                                      (v - 0.5 - p.camera.cy) / p.camera.fy, 1.0);
        ++g.rays;
        // The unobserved voxels (None, Unknown, Frontier) along the ray, each once per view, up
        // to the first Occupied voxel, where the ray leaves the grid or the depth range.
        traverse_voxels(lattice, o_grid, d, t_near, t_far, [&](int64_t lin, double t_in, double) {
          if (t_in >= t_far) return false;
          const VoxelState s = cells[lin];
          if (s == VoxelState::kOccupied) return false;
          if (s != VoxelState::kEmpty && st[lin] != tag) {
            st[lin] = tag;
            ++unknown;
          }
          return true;
        });
      }
    }
    g.unknown = unknown;
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
  // Views handed out in chunks to the workers (core/base/parallel.hpp), each worker with its own
  // stamps, made on its first chunk; a view's tag is its place in `todo`, so the gains do not
  // depend on which worker cast them.
  const int workers = worker_count(todo.size(), 1, params.threads);
  std::vector<std::unique_ptr<Caster>> casters(static_cast<std::size_t>(workers));
  parallel_for(todo.size(), [&](std::size_t begin, std::size_t end, int w) {
    if (!casters[w]) casters[w].reset(new Caster{grid, params, std::vector<uint32_t>(grid.cells.size(), 0)});
    for (std::size_t k = begin; k < end; ++k) {
      const int i = todo[k];
      out[i] = casters[w]->view(views[i], static_cast<uint32_t>(k + 1));
    }
  }, 1, workers);
  return out;
}

}  // namespace pbnbv
