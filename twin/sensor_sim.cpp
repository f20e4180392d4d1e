#include "twin/sensor_sim.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pbnbv::twin {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kEdgeJump = 0.02;     // a depth edge: a neighbour nearer by more than 2 % of the depth
constexpr int kMultipathRadiusPx = 6;  // the neighbourhood whose mean depth a pixel is compared with
constexpr double kMultipathCap = 0.02; // a push of at most 2 % of the depth

// The second viewpoint, shadow_baseline_m along +x, sees pixel (u, z) at column u - f b / z. Walking
// a row from the right, a pixel is hidden when a pixel right of it lands at or left of it there.
int cast_shadows(const std::vector<float>& exact, std::vector<float>& out, const CameraIntrinsics& k, double baseline_m) {
  int shadowed = 0;
  const double fb = k.fx * baseline_m;
  for (int v = 0; v < k.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * k.width;
    double leftmost = std::numeric_limits<double>::infinity();
    for (int u = k.width - 1; u >= 0; --u) {
      const float z = exact[row + u];
      if (!(z > 0.0f)) continue;
      const double seen_at = u - fb / z;
      if (seen_at >= leftmost) {
        if (out[row + u] > 0.0f) ++shadowed;
        out[row + u] = 0.0f;
      } else {
        leftmost = seen_at;
      }
    }
  }
  return shadowed;
}

// Unit normal of the exact surface at (u, v) from central differences, camera frame; zero where a
// neighbour is missing or across an edge.
Eigen::Vector3d normal_at(const std::vector<float>& z, const CameraIntrinsics& k, int u, int v) {
  if (u < 1 || v < 1 || u + 1 >= k.width || v + 1 >= k.height) return Eigen::Vector3d::Zero();
  const auto at = [&](int uu, int vv) { return static_cast<double>(z[static_cast<std::size_t>(vv) * k.width + uu]); };
  const double c = at(u, v);
  const double l = at(u - 1, v), r = at(u + 1, v), up = at(u, v - 1), dn = at(u, v + 1);
  for (const double n : {l, r, up, dn}) {
    if (!(n > 0) || std::abs(n - c) > 0.1 * c) return Eigen::Vector3d::Zero();
  }
  const Eigen::Vector3d pl = back_project(k, u - 1, v, l), pr = back_project(k, u + 1, v, r);
  const Eigen::Vector3d pu = back_project(k, u, v - 1, up), pd = back_project(k, u, v + 1, dn);
  const Eigen::Vector3d n = (pr - pl).cross(pd - pu);
  return n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
}

// Mean exact depth over the (2r+1)^2 window of each pixel (valid readings only), by summed-area
// tables; 0 where the window has none.
std::vector<double> window_mean(const std::vector<float>& z, int w, int h, int r) {
  std::vector<double> sum(static_cast<std::size_t>(w + 1) * (h + 1), 0.0), count(sum.size(), 0.0);
  const auto at = [w](int u, int v) { return static_cast<std::size_t>(v) * (w + 1) + u; };
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float d = z[static_cast<std::size_t>(v) * w + u];
      const double valid = d > 0.0f ? 1.0 : 0.0;
      sum[at(u + 1, v + 1)] = sum[at(u, v + 1)] + sum[at(u + 1, v)] - sum[at(u, v)] + valid * d;
      count[at(u + 1, v + 1)] = count[at(u, v + 1)] + count[at(u + 1, v)] - count[at(u, v)] + valid;
    }
  }
  std::vector<double> mean(static_cast<std::size_t>(w) * h, 0.0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const int u0 = std::max(0, u - r), u1 = std::min(w, u + r + 1), v0 = std::max(0, v - r), v1 = std::min(h, v + r + 1);
      const double n = count[at(u1, v1)] - count[at(u0, v1)] - count[at(u1, v0)] + count[at(u0, v0)];
      const double s = sum[at(u1, v1)] - sum[at(u0, v1)] - sum[at(u1, v0)] + sum[at(u0, v0)];
      mean[static_cast<std::size_t>(v) * w + u] = n > 0 ? s / n : 0.0;
    }
  }
  return mean;
}

}  // namespace

SensorSimStats simulate_sensor(DepthImage& image, const CameraIntrinsics& k, const DepthSensorModel& model,
                               std::mt19937_64& rng) {
  SensorSimStats stats;
  const std::vector<float> exact = image.depth_m;
  for (const float z : exact) stats.valid_in += z > 0.0f;
  if (model.exact()) return stats;
  std::vector<float>& out = image.depth_m;
  const int w = image.width, h = image.height;
  const auto index = [w](int u, int v) { return static_cast<std::size_t>(v) * w + u; };

  if (model.shadow_baseline_m > 0) stats.shadowed = cast_shadows(exact, out, k, model.shadow_baseline_m);

  // Flying pixels: the far side of an edge reads between the two surfaces.
  std::vector<float> mixed = out;
  if (model.flying_pixels > 0) {
    constexpr int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const float z = exact[index(u, v)];
        if (!(z > 0.0f) || !(out[index(u, v)] > 0.0f)) continue;
        float nearest = z;
        for (int d = 0; d < 4; ++d) {
          const int uu = u + du[d], vv = v + dv[d];
          if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
          const float n = exact[index(uu, vv)];
          if (n > 0.0f && n < nearest) nearest = n;
        }
        if (z - nearest <= kEdgeJump * z || uniform01(rng) >= model.flying_pixels) continue;
        const double a = 0.1 + 0.8 * uniform01(rng);
        mixed[index(u, v)] = static_cast<float>(nearest + a * (z - nearest));
        ++stats.flying;
      }
    }
  }

  // Grazing surfaces and multipath, from the exact surface.
  const double limit_rad = model.grazing_limit_deg * kPi / 180.0;
  std::vector<double> mean;
  if (model.multipath_gain > 0) mean = window_mean(exact, w, h, kMultipathRadiusPx);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i = index(u, v);
      float& z = mixed[i];
      if (!(z > 0.0f) || !(out[i] > 0.0f)) {
        z = 0.0f;
        continue;
      }
      if (limit_rad < kPi / 2) {
        const Eigen::Vector3d n = normal_at(exact, k, u, v);
        if (n.squaredNorm() > 0) {
          const Eigen::Vector3d ray = back_project(k, u, v, 1.0).normalized();
          const double angle = std::acos(std::min(1.0, std::abs(n.dot(ray))));
          if (angle > limit_rad) {
            const double p = std::pow((angle - limit_rad) / (kPi / 2 - limit_rad), 2.0);
            if (uniform01(rng) < p) {
              z = 0.0f;
              ++stats.grazing;
              continue;
            }
          }
        }
      }
      if (model.multipath_gain > 0 && mean[i] > 0) {
        const double behind = exact[i] - mean[i];
        if (behind > 0) {
          const double push = std::min(model.multipath_gain * behind, kMultipathCap * exact[i]);
          z = static_cast<float>(z + push);
          stats.multipath += push > 1e-3;
        }
      }
    }
  }

  // Noise, rounding, dropout, range.
  for (float& z : mixed) {
    if (!(z > 0.0f)) continue;
    double d = z + model.axial_sigma_m(z) * standard_normal(rng);
    if (model.depth_unit_m > 0) d = std::round(d / model.depth_unit_m) * model.depth_unit_m;
    if ((model.dropout > 0 && uniform01(rng) < model.dropout) || d < model.range.min_m || d > model.range.max_m) {
      z = 0.0f;
      ++stats.dropped;
      continue;
    }
    z = static_cast<float>(d);
  }
  out = std::move(mixed);
  return stats;
}

}  // namespace pbnbv::twin
