#pragma once
// Candidate and fixed view sets, as optical-frame camera poses in the object frame.
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

}  // namespace pbnbv
