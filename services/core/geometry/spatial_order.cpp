#include "core/geometry/spatial_order.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "core/base/parallel.hpp"

namespace pbnbv {

namespace {

constexpr double kLastCell = 1023.0;  // 2^10 - 1

// The 10 low bits of x spread to every third bit (bit k to bit 3k).
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x3ffULL;
  x = (x | x << 16) & 0x30000ffULL;
  x = (x | x << 8) & 0x300f00fULL;
  x = (x | x << 4) & 0x30c30c3ULL;
  x = (x | x << 2) & 0x9249249ULL;
  return x;
}

}  // namespace

std::vector<std::uint32_t> morton_order(const std::vector<Eigen::Vector3d>& points, const std::string& what) {
  if (points.size() > 0xffffffffULL) {
    throw std::invalid_argument(what + ": " + std::to_string(points.size()) + " points, more than 2^32 - 1");
  }
  if (points.empty()) return {};
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) throw std::invalid_argument(what + ": points[" + std::to_string(i) + "] is not finite");
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  const double edge = (hi - lo).maxCoeff();
  const double cells_per_m = edge > 0.0 ? kLastCell / edge : 0.0;  // all points alike: one cell
  // The code in the high 32 bits, the index in the low ones: one integer sort.
  std::vector<std::uint64_t> keyed(points.size());
  parallel_for(points.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t i = begin; i < end; ++i) {
      // In [0, 2^10 - 1] but for rounding, which the clamp takes care of.
      const Eigen::Vector3d g = ((points[i] - lo) * cells_per_m).cwiseMax(0.0).cwiseMin(kLastCell);
      const std::uint64_t code = spread_bits(static_cast<std::uint64_t>(g.x())) |
                                 spread_bits(static_cast<std::uint64_t>(g.y())) << 1 |
                                 spread_bits(static_cast<std::uint64_t>(g.z())) << 2;
      keyed[i] = code << 32 | i;
    }
  }, 8192);
  // Points given in this order (samples kept sorted) need no sort.
  if (!std::is_sorted(keyed.begin(), keyed.end())) std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(keyed.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) order[k] = static_cast<std::uint32_t>(keyed[k]);
  return order;
}

}  // namespace pbnbv
