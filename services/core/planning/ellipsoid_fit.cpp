// fit_ellipsoids: EM on a subsample of the voxel centres with T chosen by BIC, every voxel
// labelled by its most probable component, then the MVEE of each cluster's hull corners.
#include "core/planning/ellipsoid_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>
#include <utility>

#include "core/base/parallel.hpp"
#include "core/planning/mvee.hpp"

namespace pbnbv {

namespace {

using Points3 = Eigen::Matrix3Xd;
using Eigen::Vector3d;

}  // namespace

namespace {

// The corners of the voxels that can be vertices of their convex hull, so the MVEE of the
// returned corners equals that of all corners. A corner on the +x side of its voxel lies
// strictly inside a segment between two other corners unless the voxel is the last of the
// set along its x line (likewise -x/first, and y, z): only corners whose voxel is extreme on
// the corner's side along all three axis lines are kept (shared ones once). If the centres
// are not on a common lattice of pitch `voxel`, all corners are returned.
std::vector<Vector3d> hull_candidate_corners(const std::vector<Vector3d>& centres, double voxel) {
  const double h = 0.5 * voxel;
  const size_t n = centres.size();
  std::vector<Eigen::Vector3i> idx(n);
  bool lattice = voxel > 0;
  const Vector3d c0 = centres.empty() ? Vector3d::Zero() : centres[0];
  for (size_t i = 0; i < n && lattice; ++i) {
    const Vector3d q = (centres[i] - c0) / voxel;
    const Vector3d r = q.array().round();
    if ((q - r).cwiseAbs().maxCoeff() > 1e-3 || r.cwiseAbs().maxCoeff() > 1e6) lattice = false;
    idx[i] = r.cast<int>();
  }
  std::vector<Vector3d> corners;
  if (!lattice) {
    corners.reserve(8 * n);
    for (const auto& c : centres)
      for (int m = 0; m < 8; ++m)
        corners.push_back(c + Vector3d((m & 1) ? h : -h, (m & 2) ? h : -h, (m & 4) ? h : -h));
    return corners;
  }

  Eigen::Vector3i lo = idx[0], hi = idx[0];
  for (const auto& v : idx) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Matrix<int64_t, 3, 1> dims = (hi - lo).cast<int64_t>().array() + 1;
  // ext[i] bit 2a: voxel i is the first along its axis-a line; bit 2a+1: the last.
  std::vector<uint8_t> ext(n, 0);
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    auto mark = [&](auto& range_of) {
      for (const auto& v : idx) {
        auto& r = range_of(v);
        r.first = std::min(r.first, v[axis]);
        r.second = std::max(r.second, v[axis]);
      }
      for (size_t i = 0; i < n; ++i) {
        const auto& r = range_of(idx[i]);
        if (idx[i][axis] == r.first) ext[i] |= static_cast<uint8_t>(1u << (2 * axis));
        if (idx[i][axis] == r.second) ext[i] |= static_cast<uint8_t>(2u << (2 * axis));
      }
    };
    const std::pair<int, int> empty(std::numeric_limits<int>::max(), std::numeric_limits<int>::min());
    const int64_t cells = dims[a1] * dims[a2];
    if (cells <= 8 * static_cast<int64_t>(n) + 4096) {
      std::vector<std::pair<int, int>> grid(static_cast<size_t>(cells), empty);
      auto range_of = [&](const Eigen::Vector3i& v) -> std::pair<int, int>& {
        return grid[static_cast<size_t>((v[a1] - lo[a1]) * dims[a2] + (v[a2] - lo[a2]))];
      };
      mark(range_of);
    } else {
      std::unordered_map<uint64_t, std::pair<int, int>> map;
      map.reserve(2 * n);
      auto range_of = [&](const Eigen::Vector3i& v) -> std::pair<int, int>& {
        const uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(v[a1])) << 32) |
                             static_cast<uint32_t>(v[a2]);
        return map.emplace(key, empty).first->second;
      };
      mark(range_of);
    }
  }
  std::vector<std::array<int, 3>> ci;
  for (size_t i = 0; i < n; ++i) {
    for (int m = 0; m < 8; ++m) {
      bool keep = true;
      for (int a = 0; a < 3 && keep; ++a) keep = (ext[i] >> (2 * a + ((m >> a) & 1))) & 1u;
      if (keep) ci.push_back({idx[i][0] + (m & 1), idx[i][1] + ((m >> 1) & 1), idx[i][2] + ((m >> 2) & 1)});
    }
  }
  std::sort(ci.begin(), ci.end());
  ci.erase(std::unique(ci.begin(), ci.end()), ci.end());
  corners.reserve(ci.size());
  const Vector3d base = c0 - Vector3d::Constant(h);
  for (const auto& c : ci) corners.push_back(base + voxel * Vector3d(c[0], c[1], c[2]));
  return corners;
}

}  // namespace
std::vector<Ellipsoid> fit_ellipsoids(const std::vector<Eigen::Vector3d>& voxel_centres,
                                      EllipsoidClass cls, const EllipsoidParams& params,
                                      int* components) {
  std::vector<Ellipsoid> out;
  const size_t n = voxel_centres.size();
  if (components) *components = 0;
  if (n == 0) return out;
  const double voxel = params.voxel_m;
  if (n <= 3) {
    Ellipsoid e = minimum_volume_ellipsoid(hull_candidate_corners(voxel_centres, voxel));
    e.cls = cls;
    e.num_points = static_cast<int>(n);
    out.push_back(e);
    if (components) *components = 1;
    return out;
  }

  // EM on at most kMaxEmPoints centres (a seeded random subsample). The BIC search runs at
  // most kSearchIterations EM iterations per T; the chosen mixture is then continued with the
  // full stopping rule, and every voxel is labelled by its most probable component.
  constexpr size_t kMaxEmPoints = 500;
  constexpr int kSearchIterations = 10;
  const double min_variance = voxel * voxel / 12.0;  // variance of a uniform voxel
  std::vector<size_t> perm(n);
  std::iota(perm.begin(), perm.end(), size_t{0});
  const size_t m_em = std::min(n, kMaxEmPoints);
  if (n > m_em) {
    std::mt19937_64 rng(params.seed ^ 0x9e3779b97f4a7c15ULL);
    for (size_t i = 0; i < m_em; ++i) {
      std::uniform_int_distribution<size_t> pick(i, n - 1);
      std::swap(perm[i], perm[pick(rng)]);
    }
  }
  Points3 Xall = Eigen::Map<const Points3>(voxel_centres[0].data(), 3, static_cast<Eigen::Index>(n));
  const Vector3d offset = Xall.rowwise().mean();
  Xall.colwise() -= offset;
  Points3 Xem(3, static_cast<Eigen::Index>(m_em));
  for (size_t i = 0; i < m_em; ++i) Xem.col(static_cast<Eigen::Index>(i)) = Xall.col(static_cast<Eigen::Index>(perm[i]));
  EmOptions search;
  search.max_iterations = kSearchIterations;
  GaussianMixture g = mixture_by_bic(Xem, params.t_max, params.seed, min_variance, search, false);
  {
    EmOptions rest;
    rest.max_iterations = EmOptions{}.max_iterations - kSearchIterations;
    g = continue_em(Xem, g, min_variance, rest);
  }
  const int T = static_cast<int>(g.weights.size());
  if (components) *components = T;

  const std::vector<int> labels = most_probable_components(Xall, g, min_variance);
  std::vector<std::vector<Vector3d>> members(static_cast<size_t>(T));
  for (size_t i = 0; i < n; ++i) members[static_cast<size_t>(labels[i])].push_back(voxel_centres[i]);
  members.erase(std::remove_if(members.begin(), members.end(),
                               [](const std::vector<Vector3d>& m) { return m.empty(); }),
                members.end());  // clusters that end up empty are dropped
  out.resize(members.size());
  // Each cluster writes only its own slot.
  parallel_for(members.size(), [&](size_t begin, size_t end, int) {
    for (size_t k = begin; k < end; ++k) {
      const auto& m = members[k];
      Ellipsoid e = minimum_volume_ellipsoid(hull_candidate_corners(m, voxel));
      e.cls = cls;
      e.num_points = static_cast<int>(m.size());
      out[k] = e;
    }
  });
  return out;
}

std::vector<Ellipsoid> fit_both_classes(const std::vector<Eigen::Vector3d>& occupied,
                                        const std::vector<Eigen::Vector3d>& frontier,
                                        const EllipsoidParams& params, int* occupied_components,
                                        int* frontier_components) {
  std::vector<Ellipsoid> fits[2];
  int t[2] = {0, 0};
  if (frontier.empty()) {  // nothing to aim at: the plan will not score F (see the header)
    if (occupied_components) *occupied_components = 0;
    if (frontier_components) *frontier_components = 0;
    return {};
  }
  parallel_run(2, [&](int worker, int) {
    fits[worker] = worker == 0 ? fit_ellipsoids(occupied, EllipsoidClass::kOccupied, params, &t[0])
                               : fit_ellipsoids(frontier, EllipsoidClass::kFrontier, params, &t[1]);
  });
  if (occupied_components) *occupied_components = t[0];
  if (frontier_components) *frontier_components = t[1];
  fits[0].insert(fits[0].end(), fits[1].begin(), fits[1].end());
  return fits[0];
}

}  // namespace pbnbv
