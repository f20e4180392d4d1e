#include "core/perception/depth_filter.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace pbnbv {

DepthFilterStats filter_depth(std::vector<float>& depth_m, const CameraIntrinsics& k, const DepthFilterParams& p) {
  DepthFilterStats stats;
  const int w = k.width, h = k.height;
  if (depth_m.size() != static_cast<std::size_t>(w) * h) {
    throw std::invalid_argument("filter_depth: " + std::to_string(depth_m.size()) + " readings for a " +
                                std::to_string(w) + " x " + std::to_string(h) + " image");
  }
  if (!p.enabled) return stats;
  // The largest depth step between neighbours `step` pixels apart on a surface at the steepest
  // angle kept: the pixel's footprint z / f times tan(angle).
  const double slope = std::tan(p.max_incidence_deg * 3.14159265358979323846 / 180.0) / std::sqrt(k.fx * k.fy);
  const auto allowance = [slope](double z, double step) { return slope * z * step; };
  const auto index = [w](int u, int v) { return static_cast<std::size_t>(v) * w + u; };

  // Flying pixels, judged on the image as it came (a removal does not change its neighbours' verdicts).
  constexpr int pairs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
  std::vector<uint8_t> remove(depth_m.size(), 0);
  for (int v = 1; v + 1 < h; ++v) {
    for (int u = 1; u + 1 < w; ++u) {
      const float z = depth_m[index(u, v)];
      if (!(z > 0.0f)) continue;
      for (const auto& d : pairs) {
        const float a = depth_m[index(u - d[0], v - d[1])];
        const float b = depth_m[index(u + d[0], v + d[1])];
        if (!(a > 0.0f) || !(b > 0.0f)) continue;
        const double t = allowance(z, d[0] != 0 && d[1] != 0 ? std::sqrt(2.0) : 1.0);
        if ((a - z > t && z - b > t) || (b - z > t && z - a > t)) {
          remove[index(u, v)] = 1;
          break;
        }
      }
    }
  }
  for (std::size_t i = 0; i < depth_m.size(); ++i) {
    if (remove[i]) {
      depth_m[i] = 0.0f;
      ++stats.flying;
    }
  }

  // Speckles: flood fill over 4-neighbours whose depths differ by no more than the allowance.
  if (p.min_region_px > 1) {
    std::vector<int32_t> region(depth_m.size(), -1);
    std::vector<int> stack, members;
    int next = 0;
    for (std::size_t seed = 0; seed < depth_m.size(); ++seed) {
      if (!(depth_m[seed] > 0.0f) || region[seed] >= 0) continue;
      members.clear();
      stack.assign(1, static_cast<int>(seed));
      region[seed] = next;
      while (!stack.empty()) {
        const int i = stack.back();
        stack.pop_back();
        members.push_back(i);
        const int u = i % w, v = i / w;
        const float z = depth_m[i];
        const int nu[4] = {u - 1, u + 1, u, u}, nv[4] = {v, v, v - 1, v + 1};
        for (int n = 0; n < 4; ++n) {
          if (nu[n] < 0 || nv[n] < 0 || nu[n] >= w || nv[n] >= h) continue;
          const std::size_t j = index(nu[n], nv[n]);
          const float zj = depth_m[j];
          if (!(zj > 0.0f) || region[j] >= 0 || std::abs(zj - z) > allowance(std::min(z, zj), 1.0)) continue;
          region[j] = next;
          stack.push_back(static_cast<int>(j));
        }
      }
      ++next;
      if (static_cast<int>(members.size()) < p.min_region_px) {
        for (const int i : members) depth_m[static_cast<std::size_t>(i)] = 0.0f;
        stats.speckle_pixels += static_cast<int>(members.size());
        ++stats.speckles;
      }
    }
  }
  return stats;
}

}  // namespace pbnbv
