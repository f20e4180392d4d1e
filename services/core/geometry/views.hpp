#pragma once
// Candidate and fixed view sets, as optical-frame camera poses in the object frame.
#include <cstdint>
#include <vector>

#include "core/base/pose.hpp"

namespace pbnbv {

// `n` views on a horizontal ring of radius `radius_m` around `centre`, at `elevation_rad` above
// the horizontal plane through the centre, evenly spaced in azimuth starting at
// `start_azimuth_rad`, each looking at the centre.
std::vector<Pose> ring_views(int n, double radius_m, double elevation_rad,
                             double start_azimuth_rad, const Eigen::Vector3d& centre);

// The paper's candidate set: `alpha` parallels equally spaced in polar angle (from +z) over the
// band [polar_min_rad, polar_max_rad], parallel i at polar angle
// polar_min + (i + 0.5) * (polar_max - polar_min) / alpha; `n` views shared among parallels in
// proportion to their circumference (largest remainders, at least one each), evenly spaced in
// azimuth on each; sphere of radius `radius_m` around `centre`; each view looks at the centre.
// Hemisphere: band [0, pi/2]; full sphere: [0, pi].
std::vector<Pose> sphere_band_views(int n, int alpha, double radius_m,
                                    const Eigen::Vector3d& centre, double polar_min_rad,
                                    double polar_max_rad);

// `n` points drawn uniformly on the sphere of radius `radius_m` around the origin, or on its
// upper half (z >= 0) with `upper_half`: z uniform on [-r, r] (or [0, r]) and the azimuth
// uniform on [0, 2 pi) (Archimedes: uniform z is uniform area). Deterministic for a seed on any
// platform (mt19937_64, its 53 high bits as the uniform number; no standard-library
// distribution); the draws for n are the first n of those for n + 1, and the same seed gives the
// same directions at any radius. Throws std::invalid_argument for n < 0 or a radius that is not
// positive and finite.
std::vector<Eigen::Vector3d> uniform_sphere_points(int n, double radius_m, bool upper_half, std::uint64_t seed);

}  // namespace pbnbv
