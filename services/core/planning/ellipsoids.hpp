#pragma once
// Ellipsoids of occupied and frontier structure (docs/method.md "Ellipsoids", paper III-C):
// Gaussian-mixture clustering with the number of components chosen by BIC, then the
// minimum-volume enclosing ellipsoid (MVEE) of each cluster, fitted to voxel extents.
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/mapping/map_options.hpp"
#include "core/planning/planning_options.hpp"

namespace pbnbv {

enum class EllipsoidClass : uint8_t { kOccupied = 0, kFrontier = 1 };

struct Ellipsoid {
  EllipsoidClass cls = EllipsoidClass::kOccupied;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: principal directions (rotation)
  Eigen::Vector3d semi_axes = Eigen::Vector3d::Zero();  // along the columns of `axes`, m
  int num_points = 0;
  // The quadric Q (4x4, X^T Q X = 0 on the surface, X homogeneous) and its dual Q* = Q^-1.
  Eigen::Matrix4d quadric() const;
  Eigen::Matrix4d dual_quadric() const;
};

struct GaussianMixture {
  std::vector<double> weights;
  std::vector<Eigen::Vector3d> means;
  std::vector<Eigen::Matrix3d> covariances;
  double log_likelihood = 0;  // of the data under the mixture
  double bic = 0;             // k ln(n) - 2 ln L, k = free parameters (T-1 + 3T + 6T)
  std::vector<int> labels;    // most probable component per point
};

// Fits a T-component full-covariance Gaussian mixture by EM (k-means++ initialisation,
// deterministic for `seed`; covariances regularised by `min_variance` on the diagonal).
GaussianMixture fit_gaussian_mixture(const std::vector<Eigen::Vector3d>& points, int components,
                                     uint64_t seed, double min_variance);

// Chooses T in [1, t_max] by the lowest BIC (T never above the number of points) and returns
// that mixture. The candidate T are fitted on up to two threads (same result as one).
GaussianMixture fit_mixture_by_bic(const std::vector<Eigen::Vector3d>& points, int t_max,
                                   uint64_t seed, double min_variance);

// Minimum-volume enclosing ellipsoid of the points (Khachiyan's algorithm, tolerance `tol`).
// Fewer than 4 affinely independent points (or degenerate, e.g. planar) sets are handled by the
// caller padding them (see fit_ellipsoids).
Ellipsoid minimum_volume_ellipsoid(const std::vector<Eigen::Vector3d>& points, double tol = 1e-4);

struct EllipsoidParams {
  int t_max = kTMax.value;
  uint64_t seed = kMixtureSeed.value;
  double voxel_m = kMapResolution.value;  // voxel edge: clusters are fitted to voxel corners (8 per centre)
};

// Clusters the voxel centres of one class and fits an ellipsoid to each cluster's voxel
// corners, so a one-voxel-thin cluster gives a thin, valid ellipsoid (only the corners that
// can be vertices of the cluster's convex hull are passed to the MVEE, which depends on
// nothing else). 0 voxels: no ellipsoid; 1, 2, 3 voxels: one ellipsoid around their corners.
// Returns the ellipsoids and, in `components`, the T chosen. Uses up to two threads (the
// candidate T, then the clusters' MVEEs); the result does not depend on their timing.
std::vector<Ellipsoid> fit_ellipsoids(const std::vector<Eigen::Vector3d>& voxel_centres,
                                      EllipsoidClass cls, const EllipsoidParams& params,
                                      int* components = nullptr);

}  // namespace pbnbv
