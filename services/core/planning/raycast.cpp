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

// The rays of one view (raycast.hpp): one per `spacing_voxels` voxel footprints at the distance from
// the camera to B's centre, never finer than a pixel, over the image rectangle B projects to.
// visit(ray) is called for each, with the ray's direction d (o + t d, t the planar depth) and the
// camera centre o relative to the grid's min corner. Returns the spacing in pixels (0: no ray).
template <typename Visit>
double for_each_ray(const VoxelGrid& grid, const CameraIntrinsics& camera, const DepthRange& range,
                    double spacing_voxels, const Pose& object_T_camera, Visit&& visit) {
  const Eigen::AlignedBox3d box = grid.bounds();
  const PixelRect rect = projected_box(box, camera, object_T_camera);
  if (rect.empty()) return 0;
  const Eigen::Vector3d o = object_T_camera.translation();
  const Eigen::Matrix3d R = object_T_camera.linear();
  const double dist = std::max((box.center() - o).norm(), range.min_m);
  const double su = std::max(1.0, camera.fx * grid.resolution_m * spacing_voxels / dist);
  const double sv = std::max(1.0, camera.fy * grid.resolution_m * spacing_voxels / dist);
  const Eigen::Vector3d o_grid = o - grid.origin_m;  // relative to the grid's min corner
  for (double v = rect.v0 + 0.5 * sv; v < rect.v1; v += sv) {
    for (double u = rect.u0 + 0.5 * su; u < rect.u1; u += su) {
      // Pixel centre (u - 0.5, v - 0.5) in the image convention of back_project; t is the
      // planar depth, so the depth range bounds it directly.
      visit(o_grid, Eigen::Vector3d(R * Eigen::Vector3d((u - 0.5 - camera.cx) / camera.fx,
                                                         (v - 0.5 - camera.cy) / camera.fy, 1.0)));
    }
  }
  return su;
}

// Walks one ray through the unobserved voxels (None, Unknown, Frontier) up to the first Occupied
// voxel, where it leaves the grid or the depth range: unobserved(linear index) for each.
template <typename Unobserved>
void walk_unobserved(const VoxelGrid& grid, const VoxelLattice& lattice, const DepthRange& range,
                     const Eigen::Vector3d& o_grid, const Eigen::Vector3d& d, Unobserved&& unobserved) {
  const VoxelState* cells = grid.cells.data();
  const double t_far = range.max_m;
  traverse_voxels(lattice, o_grid, d, range.min_m, t_far, [&](int64_t lin, double t_in, double) {
    if (t_in >= t_far) return false;
    const VoxelState s = cells[lin];
    if (s == VoxelState::kOccupied) return false;
    if (s != VoxelState::kEmpty) unobserved(lin);
    return true;
  });
}

struct Caster {
  const VoxelGrid& grid;
  const RaycastParams& p;
  std::vector<uint32_t> stamp;  // per voxel: tag of the last view that counted it

  RaycastGain view(const Pose& object_T_camera, uint32_t tag) {
    RaycastGain g;
    const VoxelLattice lattice{grid.dims, grid.resolution_m};
    int64_t unknown = 0;
    uint32_t* st = stamp.data();
    // Each unobserved voxel once per view, however many of its rays cross it.
    g.spacing_px = for_each_ray(grid, p.camera, p.range, p.ray_spacing_voxels, object_T_camera,
                                [&](const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
                                  ++g.rays;
                                  walk_unobserved(grid, lattice, p.range, o, d, [&](int64_t lin) {
                                    if (st[lin] != tag) {
                                      st[lin] = tag;
                                      ++unknown;
                                    }
                                  });
                                });
    g.unknown = unknown;
    return g;
  }
};

// The views of `views` that `active` selects (all when empty), checking its size.
std::vector<int> active_views(const std::vector<Pose>& views, const std::vector<uint8_t>& active, const char* what) {
  if (!active.empty() && active.size() != views.size()) {
    throw std::invalid_argument(std::string(what) + ": active has " + std::to_string(active.size()) + " entries for " +
                                std::to_string(views.size()) + " views");
  }
  std::vector<int> todo;
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (active.empty() || active[i]) todo.push_back(static_cast<int>(i));
  }
  return todo;
}

}  // namespace

std::vector<RaycastGain> raycast_gains(const VoxelGrid& grid, const std::vector<Pose>& views,
                                       const std::vector<uint8_t>& active, const RaycastParams& params) {
  grid.validate("raycast: voxel grid");
  params.validate();
  const std::vector<int> todo = active_views(views, active, "raycast");
  std::vector<RaycastGain> out(views.size());
  if (grid.empty() || views.empty()) return out;
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

void UnobservedRayParams::validate() const {
  camera.validate();
  range.validate();
  if (!(std::isfinite(saturation_voxels) && saturation_voxels > 0)) {
    throw std::invalid_argument("unobserved rays: saturation_voxels = " + std::to_string(saturation_voxels) +
                                " must be a positive number");
  }
  if (!(std::isfinite(ray_spacing_voxels) && ray_spacing_voxels > 0)) {
    throw std::invalid_argument("unobserved rays: ray_spacing_voxels = " + std::to_string(ray_spacing_voxels) +
                                " must be a positive number");
  }
  if (threads < 0) throw std::invalid_argument("unobserved rays: threads = " + std::to_string(threads) + " must be >= 0");
}

std::vector<double> unobserved_ray_scores(const VoxelGrid& grid, const std::vector<Pose>& views,
                                          const std::vector<uint8_t>& active, const UnobservedRayParams& params) {
  grid.validate("unobserved rays: voxel grid");
  params.validate();
  const std::vector<int> todo = active_views(views, active, "unobserved rays");
  std::vector<double> out(views.size(), 0.0);
  if (grid.empty() || views.empty()) return out;
  const VoxelLattice lattice{grid.dims, grid.resolution_m};
  parallel_for(todo.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t k = begin; k < end; ++k) {
      double sum = 0;
      for_each_ray(grid, params.camera, params.range, params.ray_spacing_voxels, views[todo[k]],
                   [&](const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
                     int n = 0;
                     walk_unobserved(grid, lattice, params.range, o, d, [&](int64_t) { ++n; });
                     sum += 1.0 - std::exp(-n / params.saturation_voxels);
                   });
      out[todo[k]] = sum;
    }
  }, 1, worker_count(todo.size(), 1, params.threads));
  return out;
}

VoxelGrid coarsened(const VoxelGrid& grid, int factor) {
  if (factor < 1) throw std::invalid_argument("coarsened: factor " + std::to_string(factor) + " must be >= 1");
  if (factor == 1 || grid.empty()) return grid;
  VoxelGrid c;
  c.origin_m = grid.origin_m;
  c.resolution_m = grid.resolution_m * factor;
  c.dims = (grid.dims + Eigen::Vector3i::Constant(factor - 1)) / factor;
  c.cells.assign(static_cast<std::size_t>(c.dims.prod()), VoxelState::kEmpty);
  for (int z = 0; z < grid.dims.z(); ++z) {
    for (int y = 0; y < grid.dims.y(); ++y) {
      for (int x = 0; x < grid.dims.x(); ++x) {
        const VoxelState s = grid.at(x, y, z);
        VoxelState& t = c.cells[x / factor + int64_t(c.dims.x()) * (y / factor + int64_t(c.dims.y()) * (z / factor))];
        if (s == VoxelState::kOccupied) {
          t = s;
        } else if (s != VoxelState::kEmpty && t == VoxelState::kEmpty) {
          t = VoxelState::kUnknown;
        }
      }
    }
  }
  return c;
}

}  // namespace pbnbv
