// Surface coverage of a scan (the paper's evaluation metric): fixed samples on the mesh, each
// covered once some cloud point lies within the radius of it.
//
// The samples never change, so they are indexed once in a dense uniform grid over their bounding
// box, cell edge = radius (enlarged if the grid would exceed kMaxCells cells), stored CSR-style:
// samples sorted by cell, with each cell's range of sorted positions. A cloud point is tested
// against the samples of the cells overlapping the cube of half-edge radius around it (at most
// 3 x 3 x 3 cells, 2 x 2 x 2 when the cell is at least twice the radius). Each cell also counts
// its uncovered samples, so fully covered cells cost one look-up; points outside the samples'
// box grown by the radius are dismissed before any cell look-up.
#include "eval/coverage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace pbnbv {

namespace {

constexpr double kMaxCells = 1 << 20;  // 4 MiB per per-cell array

void check_radius(double radius_m) {
  if (!(radius_m > 0.0) || !std::isfinite(radius_m)) {
    std::ostringstream os;
    os << "coverage: radius_m must be a positive finite distance in metres, got " << radius_m;
    throw std::invalid_argument(os.str());
  }
}

std::vector<Eigen::Vector3d> sample_mesh(const TriangleMesh& mesh, const CoverageParams& params) {
  if (params.num_samples == 0) {
    throw std::invalid_argument("coverage: num_samples must be > 0, got 0");
  }
  check_radius(params.radius_m);
  if (mesh.triangles.empty()) throw std::invalid_argument("coverage: the mesh has no triangles");
  if (!(mesh_area(mesh) > 0.0)) throw std::invalid_argument("coverage: the mesh has zero area");
  return sample_surface(mesh, params.num_samples, params.seed);
}

}  // namespace

CoverageEvaluator::CoverageEvaluator(const TriangleMesh& mesh, const CoverageParams& params)
    : CoverageEvaluator(sample_mesh(mesh, params), params.radius_m) {}

CoverageEvaluator::CoverageEvaluator(std::vector<Eigen::Vector3d> surface_points, double radius_m)
    : samples_(std::move(surface_points)), radius_(radius_m) {
  check_radius(radius_m);
  if (samples_.empty()) {
    throw std::invalid_argument("coverage: no surface samples (surface_points is empty)");
  }
  if (samples_.size() >= std::numeric_limits<uint32_t>::max()) {
    throw std::invalid_argument("coverage: too many surface samples");
  }
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    if (!samples_[i].allFinite()) {
      throw std::invalid_argument("coverage: surface sample " + std::to_string(i) +
                                  " is not finite");
    }
  }
  covered_.assign(samples_.size(), 0);
  build_grid();
}

void CoverageEvaluator::build_grid() {
  lo_ = samples_.front();
  hi_ = samples_.front();
  for (const auto& s : samples_) {
    lo_ = lo_.cwiseMin(s);
    hi_ = hi_.cwiseMax(s);
  }
  const Eigen::Vector3d extent = hi_ - lo_;
  if (!extent.allFinite()) throw std::invalid_argument("coverage: surface samples span too far");

  // Cell edge: the radius, grown until the grid has at most kMaxCells cells.
  cell_ = radius_;
  for (;;) {
    const Eigen::Array3d d = (extent.array() / cell_).floor() + 1.0;
    const double cells = d.prod();
    if (cells <= kMaxCells) {
      dims_ = d.cast<int>();
      break;
    }
    cell_ *= std::max(1.05, std::cbrt(cells / kMaxCells));
  }

  // Counting sort of the samples by cell (stable: caller's order within a cell).
  const std::size_t num_cells = static_cast<std::size_t>(dims_.prod());
  const std::size_t n = samples_.size();
  std::vector<uint32_t> cell_of(n);
  cell_start_.assign(num_cells + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Array3d f = ((samples_[i] - lo_).array() / cell_).floor();
    const int x = std::min(static_cast<int>(f.x()), dims_.x() - 1);
    const int y = std::min(static_cast<int>(f.y()), dims_.y() - 1);
    const int z = std::min(static_cast<int>(f.z()), dims_.z() - 1);
    cell_of[i] = static_cast<uint32_t>((static_cast<std::size_t>(z) * dims_.y() + y) * dims_.x() + x);
    ++cell_start_[cell_of[i] + 1];
  }
  cell_left_.assign(num_cells, 0);
  for (std::size_t c = 0; c < num_cells; ++c) {
    cell_left_[c] = cell_start_[c + 1];
    cell_start_[c + 1] += cell_start_[c];
  }
  sorted_points_.resize(n);
  sorted_index_.resize(n);
  sorted_covered_.assign(n, 0);
  std::vector<uint32_t> next(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const uint32_t pos = next[cell_of[i]]++;
    sorted_points_[pos] = samples_[i];
    sorted_index_[pos] = static_cast<uint32_t>(i);
  }
}

template <typename Vec>
void CoverageEvaluator::mark(const Vec& point) {
  const Eigen::Vector3d p = point.template cast<double>();
  if (!p.allFinite()) {
    ++rejected_;
    return;
  }
  const double r = radius_;
  if ((p.array() < lo_.array() - r).any() || (p.array() > hi_.array() + r).any()) return;
  // Cells overlapping the cube [p - r, p + r], clamped to the grid.
  const Eigen::Array3d a = ((p - lo_).array() - r) / cell_;
  const Eigen::Array3d b = ((p - lo_).array() + r) / cell_;
  const Eigen::Array3i c0 = a.floor().cast<int>().max(0);
  const Eigen::Array3i c1 = b.floor().cast<int>().min(dims_ - 1);
  const double r2 = r * r;
  for (int z = c0.z(); z <= c1.z(); ++z) {
    for (int y = c0.y(); y <= c1.y(); ++y) {
      const std::size_t row = (static_cast<std::size_t>(z) * dims_.y() + y) * dims_.x();
      for (int x = c0.x(); x <= c1.x(); ++x) {
        const std::size_t cell = row + static_cast<std::size_t>(x);
        if (cell_left_[cell] == 0) continue;
        for (uint32_t k = cell_start_[cell], end = cell_start_[cell + 1]; k < end; ++k) {
          if (sorted_covered_[k] || (sorted_points_[k] - p).squaredNorm() > r2) continue;
          sorted_covered_[k] = 1;
          covered_[sorted_index_[k]] = 1;
          --cell_left_[cell];
          ++num_covered_;
        }
      }
    }
  }
}

double CoverageEvaluator::add(const std::vector<Eigen::Vector3d>& cloud) {
  for (const auto& p : cloud) mark(p);
  return coverage_percent();
}

double CoverageEvaluator::add_cloud(const PointCloud& cloud) {
  for (const auto& p : cloud) mark(p);
  return coverage_percent();
}

double CoverageEvaluator::coverage_percent() const {
  return 100.0 * static_cast<double>(num_covered_) / static_cast<double>(samples_.size());
}

double CoverageEvaluator::coverage_percent(const std::vector<uint8_t>& mask) const {
  if (mask.size() != samples_.size()) {
    throw std::invalid_argument("coverage: mask has " + std::to_string(mask.size()) +
                                " entries, expected one per sample (" +
                                std::to_string(samples_.size()) + ")");
  }
  std::size_t selected = 0, hit = 0;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    if (!mask[i]) continue;
    ++selected;
    hit += covered_[i] ? 1 : 0;
  }
  return selected == 0 ? 0.0 : 100.0 * static_cast<double>(hit) / static_cast<double>(selected);
}

void CoverageEvaluator::reset() {
  std::fill(covered_.begin(), covered_.end(), 0);
  std::fill(sorted_covered_.begin(), sorted_covered_.end(), 0);
  for (std::size_t c = 0; c + 1 < cell_start_.size(); ++c) {
    cell_left_[c] = cell_start_[c + 1] - cell_start_[c];
  }
  num_covered_ = 0;
  rejected_ = 0;
}

double coverage_percent(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& cloud,
                        const CoverageParams& params) {
  CoverageEvaluator ev(mesh, params);
  return ev.add(cloud);
}

}  // namespace pbnbv
