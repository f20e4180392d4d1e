// Candidate and fixed view sets. See views.hpp.
#include "core/geometry/views.hpp"
#include "core/base/units.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

namespace pbnbv {

namespace {

Eigen::Vector3d on_sphere(const Eigen::Vector3d& centre, double radius, double polar,
                          double azimuth) {
  return centre + radius * Eigen::Vector3d(std::sin(polar) * std::cos(azimuth),
                                           std::sin(polar) * std::sin(azimuth),
                                           std::cos(polar));
}
}  // namespace

std::vector<Pose> ring_views(int n, double radius_m, double elevation_rad,
                             double start_azimuth_rad, const Eigen::Vector3d& centre) {
  if (n < 1) throw std::invalid_argument("ring_views: n must be >= 1, got " + std::to_string(n));
  if (!(radius_m > 0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("ring_views: radius must be positive, got " +
                                std::to_string(radius_m));
  }
  std::vector<Pose> views;
  views.reserve(n);
  const double polar = kPi / 2 - elevation_rad;
  for (int k = 0; k < n; ++k) {
    const double az = start_azimuth_rad + 2.0 * kPi * k / n;
    views.push_back(look_at_z_up(on_sphere(centre, radius_m, polar, az), centre));
  }
  return views;
}

std::vector<Pose> sphere_band_views(int n, int alpha, double radius_m,
                                    const Eigen::Vector3d& centre, double polar_min_rad,
                                    double polar_max_rad) {
  if (alpha < 1) {
    throw std::invalid_argument("sphere_band_views: alpha must be >= 1, got " +
                                std::to_string(alpha));
  }
  if (n < alpha) {
    throw std::invalid_argument("sphere_band_views: n (" + std::to_string(n) +
                                ") must be >= alpha (" + std::to_string(alpha) + ")");
  }
  if (!(radius_m > 0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("sphere_band_views: radius must be positive, got " +
                                std::to_string(radius_m));
  }
  if (!(polar_min_rad >= 0 && polar_max_rad <= kPi + 1e-12 && polar_min_rad < polar_max_rad)) {
    throw std::invalid_argument("sphere_band_views: polar band must satisfy 0 <= min < max <= pi");
  }
  const double step = (polar_max_rad - polar_min_rad) / alpha;
  std::vector<double> polar(alpha), weight(alpha);
  for (int i = 0; i < alpha; ++i) {
    polar[i] = polar_min_rad + (i + 0.5) * step;
    weight[i] = std::sin(polar[i]);  // circumference of the parallel / (2 pi R)
  }
  const double wsum = std::accumulate(weight.begin(), weight.end(), 0.0);

  // Largest remainders with at least one view per parallel.
  std::vector<double> quota(alpha);
  std::vector<int> count(alpha);
  int assigned = 0;
  for (int i = 0; i < alpha; ++i) {
    quota[i] = n * weight[i] / wsum;
    count[i] = std::max(1, static_cast<int>(std::floor(quota[i])));
    assigned += count[i];
  }
  std::vector<int> order(alpha);
  std::iota(order.begin(), order.end(), 0);
  if (assigned < n) {
    // Hand out the rest by largest fractional remainder (ties: lower index first).
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return (quota[a] - count[a]) > (quota[b] - count[b]);
    });
    for (int k = 0; assigned < n; k = (k + 1) % alpha) {
      ++count[order[k]];
      ++assigned;
    }
  } else {
    // Too many because of the one-per-parallel minimum: take from the most over-served.
    while (assigned > n) {
      int best = -1;
      for (int i = 0; i < alpha; ++i) {
        if (count[i] <= 1) continue;
        if (best < 0 || (count[i] - quota[i]) > (count[best] - quota[best])) best = i;
      }
      --count[best];
      --assigned;
    }
  }

  std::vector<Pose> views;
  views.reserve(n);
  for (int i = 0; i < alpha; ++i) {
    for (int j = 0; j < count[i]; ++j) {
      const double az = 2.0 * kPi * j / count[i];
      views.push_back(look_at_z_up(on_sphere(centre, radius_m, polar[i], az), centre));
    }
  }
  return views;
}

std::vector<Eigen::Vector3d> uniform_sphere_points(int n, double radius_m, bool upper_half, std::uint64_t seed) {
  if (n < 0) throw std::invalid_argument("uniform_sphere_points: n must be >= 0, got " + std::to_string(n));
  if (!(radius_m > 0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("uniform_sphere_points: radius must be positive and finite, got " + std::to_string(radius_m));
  }
  std::mt19937_64 rng(seed);
  const auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };  // [0, 1)
  std::vector<Eigen::Vector3d> points;
  points.reserve(n);
  for (int i = 0; i < n; ++i) {
    const double z = upper_half ? uniform() : 2.0 * uniform() - 1.0;
    const double azimuth = 2.0 * M_PI * uniform();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    points.push_back(radius_m * Eigen::Vector3d(r * std::cos(azimuth), r * std::sin(azimuth), z));
  }
  return points;
}

}  // namespace pbnbv
