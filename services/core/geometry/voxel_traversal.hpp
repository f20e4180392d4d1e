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
// origin of the coordinates given to traverse_voxels; extent_m = dims * cell_m, kept so that a
// walk does not recompute it for every ray.
struct VoxelLattice {
  VoxelLattice(const Eigen::Vector3i& dims_in, double cell_m_in)
      : dims(dims_in), cell_m(cell_m_in), extent_m(dims_in.cast<double>() * cell_m_in) {}
  Eigen::Vector3i dims;
  double cell_m;
  Eigen::Vector3d extent_m;
};

namespace voxel_traversal_detail {

// One axis of the walk from cell i: the step direction, the linear index step, the t of the next
// boundary and the t per cell (infinite when the ray is parallel to the axis' boundaries).
inline void axis(double oi, double di, int i, int64_t stride, double res, int& s, int64_t& ls, double& tm,
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

}  // namespace voxel_traversal_detail

// What a visitor tells the walk after a cell: go on to the next cell, stop, or go on and hand the
// next cells over to the second visitor.
enum class VoxelVisit { kNext, kStop, kHandOver };

// The walk of the ray o + t d through the grid: calls first(cell, t_in, t_out) for each cell it
// crosses, in order, from where it enters the grid within [t_min, t_max]; once `first` returns
// kHandOver, the following cells go to then(cell, t_in, t_out) instead. The walk ends when a
// visitor returns kStop or the ray leaves the grid. cell: the linear index; t_in: where the ray
// enters the cell (for the first cell: where it enters the grid, or t_min); t_out: where it leaves
// the cell (the nearest boundary ahead). Returns whether the ray meets the grid within
// [t_min, t_max] over a positive length (false for NaN); `first` sees at least one cell when it
// does.
// [t_min, t_max] decides where the walk starts and whether it starts at all; where it ends along
// the ray is the visitors' choice (t_in, t_out), so that the loop carries no test a visitor does
// not need. Two visitors, because the map update walks a ray in two phases (free space up to the
// surface, then occluded space behind it) and each phase's loop then holds only its own tests.
// The grid's box is met by a slab test (an axis with |d_i| < 1e-15 counts as parallel to it); the
// first cell is the one holding the entry point, its index clamped into the grid (the entry point
// lies on the box's surface up to rounding).
// Always inlined, with all state in locals: in the caller the walk and the visitors become plain
// loops whose state stays in registers. (Measured with GCC 12 on the map update's ray casting,
// against the loop written out in the caller: a walk object holding this state as members stayed
// in memory, an out-of-line walk reloads the visitor's captures after every cell it writes (a
// byte store that may alias them), and one visitor with a phase flag plus an end test in the loop
// each cost 20-30 % more instructions.)
template <class First, class Then>
[[gnu::always_inline]] inline bool traverse_voxels(const VoxelLattice& grid, const Eigen::Vector3d& o,
                                                   const Eigen::Vector3d& d, double t_min, double t_max,
                                                   First&& first, Then&& then) {
  const double res = grid.cell_m;
  double t0 = t_min, t1 = t_max;
  for (int i = 0; i < 3; ++i) {
    const double ext = grid.extent_m[i];
    if (std::abs(d[i]) < 1e-15) {
      if (o[i] < 0.0 || o[i] > ext) return false;  // parallel to the slab, outside it
      continue;
    }
    const double inv = 1.0 / d[i];
    double ta = -o[i] * inv, tb = (ext - o[i]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (!(t0 < t1)) return false;

  // The entry cell. Clamped into the grid, truncation gives what floor() gives (a negative
  // coordinate ends at cell 0 either way) in one instruction: floor() without SSE4.1 takes about
  // ten, a tenth of a short ray's whole cost.
  int ix = std::clamp(static_cast<int>((o.x() + d.x() * t0) / res), 0, grid.dims.x() - 1);
  int iy = std::clamp(static_cast<int>((o.y() + d.y() * t0) / res), 0, grid.dims.y() - 1);
  int iz = std::clamp(static_cast<int>((o.z() + d.z() * t0) / res), 0, grid.dims.z() - 1);
  const int64_t nx = grid.dims.x(), nxy = int64_t(grid.dims.x()) * grid.dims.y();
  int sx, sy, sz;
  int64_t lx, ly, lz;
  double tx, ty, tz, dx, dy, dz;
  voxel_traversal_detail::axis(o.x(), d.x(), ix, 1, res, sx, lx, tx, dx);
  voxel_traversal_detail::axis(o.y(), d.y(), iy, nx, res, sy, ly, ty, dy);
  voxel_traversal_detail::axis(o.z(), d.z(), iz, nxy, res, sz, lz, tz, dz);
  int64_t lin = ix + nx * iy + nxy * iz;
  const unsigned ux = static_cast<unsigned>(grid.dims.x()), uy = static_cast<unsigned>(grid.dims.y()),
                 uz = static_cast<unsigned>(grid.dims.z());
  double t_in = t0;
  // Into the next cell across the boundary the ray meets first (ties: x, then y, then z); false
  // when that boundary is the grid's.
  auto step = [&]() -> bool {
    if (tx <= ty && tx <= tz) {
      ix += sx;
      if (static_cast<unsigned>(ix) >= ux) return false;
      lin += lx;
      t_in = tx;
      tx += dx;
    } else if (ty <= tz) {
      iy += sy;
      if (static_cast<unsigned>(iy) >= uy) return false;
      lin += ly;
      t_in = ty;
      ty += dy;
    } else {
      iz += sz;
      if (static_cast<unsigned>(iz) >= uz) return false;
      lin += lz;
      t_in = tz;
      tz += dz;
    }
    return true;
  };
  for (;;) {
    const VoxelVisit v = first(lin, t_in, std::min(tx, std::min(ty, tz)));
    if (v != VoxelVisit::kNext) {
      if (v == VoxelVisit::kStop || !step()) return true;
      break;  // handed over: the next cell is the second visitor's
    }
    if (!step()) return true;
  }
  for (;;) {
    if (then(lin, t_in, std::min(tx, std::min(ty, tz))) == VoxelVisit::kStop || !step()) return true;
  }
}

// The walk with one visitor: visit(cell, t_in, t_out) returns whether to go on (see above).
template <class Visit>
[[gnu::always_inline]] inline bool traverse_voxels(const VoxelLattice& grid, const Eigen::Vector3d& o,
                                                   const Eigen::Vector3d& d, double t_min, double t_max,
                                                   Visit&& visit) {
  return traverse_voxels(
      grid, o, d, t_min, t_max,
      [&](int64_t cell, double t_in, double t_out) { return visit(cell, t_in, t_out) ? VoxelVisit::kNext : VoxelVisit::kStop; },
      [](int64_t, double, double) { return VoxelVisit::kStop; });
}

}  // namespace pbnbv
