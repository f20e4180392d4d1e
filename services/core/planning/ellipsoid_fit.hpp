#pragma once
// Ellipsoids of occupied and frontier structure (docs/method.md "Ellipsoids", paper section
// III-C): the voxel centres of one class clustered by a Gaussian mixture with T chosen by BIC
// (gmm.hpp), then the minimum-volume enclosing ellipsoid (mvee.hpp) of each cluster, fitted to
// the voxels' extents.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/planning/gmm.hpp"
#include "core/planning/ellipsoid.hpp"
#include "core/mapping/map_options.hpp"
#include "core/planning/planning_options.hpp"

namespace pbnbv {

struct EllipsoidParams {
  int t_max = kTMax.value;
  uint64_t seed = kMixtureSeed.value;
  double voxel_m = kMapResolution.value;  // voxel edge: clusters are fitted to voxel corners (8 per centre)
};

// Clusters the voxel centres of one class and fits an ellipsoid to each cluster's voxel
// corners, so a one-voxel-thin cluster gives a thin, valid ellipsoid (only the corners that
// can be vertices of the cluster's convex hull are passed to the MVEE, which depends on
// nothing else). 0 voxels: no ellipsoid; 1, 2, 3 voxels: one ellipsoid around their corners.
// Returns the ellipsoids and, in `components`, the T chosen. The candidate T, then the
// clusters' MVEEs, run in parallel (parallel_for); the result does not depend on the timing.
std::vector<Ellipsoid> fit_ellipsoids(const std::vector<Eigen::Vector3d>& voxel_centres,
                                      EllipsoidClass cls, const EllipsoidParams& params,
                                      int* components = nullptr);

// Both classes, as fit_ellipsoids on each (the Occupied ellipsoids first, then the Frontier
// ones), the two fits running side by side: the same ellipsoids as one after the other, in less
// wall time, since each fit has serial parts (the EM continued with the chosen T, the labels).
// With no Frontier voxel nothing is fitted (no ellipsoid, both T 0): PB-NBV then has nothing to
// aim at (no frontier ellipsoid: planner.hpp's nothing-left rule) and the Occupied ellipsoids,
// which only take from F, would go unused.
std::vector<Ellipsoid> fit_both_classes(const std::vector<Eigen::Vector3d>& occupied,
                                        const std::vector<Eigen::Vector3d>& frontier,
                                        const EllipsoidParams& params, int* occupied_components = nullptr,
                                        int* frontier_components = nullptr);

}  // namespace pbnbv
