#pragma once
// The minimum-volume enclosing ellipsoid of a point set (Khachiyan's algorithm with
// Todd-Yildirim away steps, on an active set; docs/method.md "Ellipsoids").
#include <Eigen/Core>
#include <vector>

#include "core/planning/ellipsoid.hpp"

namespace pbnbv {

// Minimum-volume enclosing ellipsoid of the points (Khachiyan's algorithm, tolerance `tol`).
// Fewer than 4 affinely independent points (or degenerate, e.g. planar) sets get the principal
// frame of the points with semi-axes sqrt(3) x their half extents and thin directions 1e-9 m
// (fit_ellipsoids pads such clusters with voxel corners first).
Ellipsoid minimum_volume_ellipsoid(const std::vector<Eigen::Vector3d>& points, double tol = 1e-4);

}  // namespace pbnbv
