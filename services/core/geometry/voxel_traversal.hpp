#pragma once
// The one voxel traversal: the cells of a regular 3-D grid that a ray crosses, in the order it
// crosses them, with the ray parameter where it enters and leaves each (the 3-D DDA of Amanatides
// & Woo, "A fast voxel traversal algorithm for ray tracing", 1987). Used by the voxel map update
// (core/mapping) and the ray-casting baseline (core/planning). Header only, so that the caller's
// visitor inlines into the stepping loop (the map update runs it for every ray of every frame).
//
// Conventions: coordinates are relative to the grid's min corner, in the unit of `cell_m`; the ray
// is o + t d (d need not be unit length: with d = R (x_n, y_n, 1) the parameter t is the planar
// depth); cell (x, y, z) covers [x, x + 1) * cell_m along x, likewise y and z, and its linear
// index is x + nx (y + ny z). Where the ray passes exactly through an edge or a corner (it meets
// two or three boundaries at the same t) it steps across x first, then y, then z: it visits one
// of the cells that share the edge, not all of them.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace pbnbv {

// A regular grid of dims.x() x dims.y() x dims.z() cubic cells of edge cell_m, min corner at the
// origin of the coordinates given to VoxelWalk.
struct VoxelLattice {
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  double cell_m = 1.0;
};

// The walk of one ray through a VoxelLattice, one cell at a time. Construct, test entered(), then
// read cell() / t_in() / t_out() and call next() until it returns false (the ray left the grid).
class VoxelWalk {
 public:
  // Clips [t_min, t_max] to the grid's box (slab test; an axis with |d_i| < 1e-15 is treated as
  // parallel to it) and places the walk in the cell where the clipped ray starts (its index
  // clamped into the grid: the entry point lies on the box's surface up to rounding).
  VoxelWalk(const VoxelLattice& grid, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
            double t_max)
      : t_enter_(t_min), t_exit_(t_max), t_in_(t_min) {
    const double res = grid.cell_m;
    for (int i = 0; i < 3; ++i) {
      const double ext = grid.dims[i] * res;
      if (std::abs(d[i]) < 1e-15) {
        if (o[i] < 0.0 || o[i] > ext) {
          t_exit_ = -std::numeric_limits<double>::infinity();  // parallel to the slab, outside it
          return;
        }
        continue;
      }
      const double inv = 1.0 / d[i];
      double ta = -o[i] * inv, tb = (ext - o[i]) * inv;
      if (ta > tb) std::swap(ta, tb);
      t_enter_ = std::max(t_enter_, ta);
      t_exit_ = std::min(t_exit_, tb);
    }
    if (!entered()) return;
    t_in_ = t_enter_;
    const double t0 = t_enter_;
    ix_ = std::clamp(static_cast<int>(std::floor((o.x() + d.x() * t0) / res)), 0, grid.dims.x() - 1);
    iy_ = std::clamp(static_cast<int>(std::floor((o.y() + d.y() * t0) / res)), 0, grid.dims.y() - 1);
    iz_ = std::clamp(static_cast<int>(std::floor((o.z() + d.z() * t0) / res)), 0, grid.dims.z() - 1);
    const int64_t nx = grid.dims.x(), nxy = int64_t(grid.dims.x()) * grid.dims.y();
    setup(o.x(), d.x(), ix_, 1, res, sx_, lx_, tx_, dx_);
    setup(o.y(), d.y(), iy_, nx, res, sy_, ly_, ty_, dy_);
    setup(o.z(), d.z(), iz_, nxy, res, sz_, lz_, tz_, dz_);
    lin_ = ix_ + nx * iy_ + nxy * iz_;
    ux_ = static_cast<unsigned>(grid.dims.x());
    uy_ = static_cast<unsigned>(grid.dims.y());
    uz_ = static_cast<unsigned>(grid.dims.z());
  }

  // Whether the clipped ray has a part of positive length inside the grid (false for NaN).
  bool entered() const { return t_enter_ < t_exit_; }
  // The clipped parameter interval: where the ray enters the grid (or t_min) and leaves it (or
  // t_max).
  double t_enter() const { return t_enter_; }
  double t_exit() const { return t_exit_; }

  // The current cell: linear index, lattice index, where the ray entered it (t_enter() for the
  // first cell) and where it leaves it (the nearest boundary ahead).
  int64_t cell() const { return lin_; }
  Eigen::Vector3i index() const { return Eigen::Vector3i(ix_, iy_, iz_); }
  double t_in() const { return t_in_; }
  double t_out() const { return std::min(tx_, std::min(ty_, tz_)); }

  // Steps into the next cell across the boundary the ray meets first (ties: x, then y, then z);
  // false when that boundary is the grid's (the walk is over).
  bool next() {
    if (tx_ <= ty_ && tx_ <= tz_) {
      ix_ += sx_;
      if (static_cast<unsigned>(ix_) >= ux_) return false;
      lin_ += lx_;
      t_in_ = tx_;
      tx_ += dx_;
    } else if (ty_ <= tz_) {
      iy_ += sy_;
      if (static_cast<unsigned>(iy_) >= uy_) return false;
      lin_ += ly_;
      t_in_ = ty_;
      ty_ += dy_;
    } else {
      iz_ += sz_;
      if (static_cast<unsigned>(iz_) >= uz_) return false;
      lin_ += lz_;
      t_in_ = tz_;
      tz_ += dz_;
    }
    return true;
  }

 private:
  // Per axis: the step direction, the linear index step, the t of the next boundary and the t
  // per cell (infinite when the ray is parallel to the axis' boundaries).
  static void setup(double oi, double di, int i, int64_t stride, double res, int& s, int64_t& ls, double& tm,
                    double& td) {
    constexpr double kNever = std::numeric_limits<double>::infinity();
    if (di > 0) {
      s = 1;
      ls = stride;
      tm = ((i + 1) * res - oi) / di;
      td = res / di;
    } else if (di < 0) {
      s = -1;
      ls = -stride;
      tm = (i * res - oi) / di;
      td = -res / di;
    } else {
      s = 0;
      ls = 0;
      tm = kNever;
      td = kNever;
    }
  }

  double t_enter_, t_exit_, t_in_;
  int ix_ = 0, iy_ = 0, iz_ = 0;
  int sx_ = 0, sy_ = 0, sz_ = 0;
  int64_t lx_ = 0, ly_ = 0, lz_ = 0, lin_ = 0;
  double tx_ = 0, ty_ = 0, tz_ = 0, dx_ = 0, dy_ = 0, dz_ = 0;
  unsigned ux_ = 0, uy_ = 0, uz_ = 0;
};

// Calls visit(cell, t_in, t_out) for each cell the part [t_min, t_max) of the ray o + t d crosses
// inside the grid, in order (cell: the linear index; t_in, t_out: where the ray enters and leaves
// that cell), until visit returns false, the ray leaves the grid, or the next cell starts at or
// beyond t_max. Returns whether the ray entered the grid at all (VoxelWalk::entered()); visit is
// called at least once when it did.
template <class Visit>
bool traverse_voxels(const VoxelLattice& grid, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                     double t_max, Visit&& visit) {
  VoxelWalk walk(grid, o, d, t_min, t_max);
  if (!walk.entered()) return false;
  while (visit(walk.cell(), walk.t_in(), walk.t_out()) && walk.next() && walk.t_in() < t_max) {
  }
  return true;
}

}  // namespace pbnbv
