// Accuracy, completeness and F-score of a model against a reference mesh: the distances come
// from the one mesh tree (CGAL's AABB tree, started from its surface hints) and the one k-d tree of
// cloud points (nanoflann), each query run on the workers of core/base/parallel.hpp. The figures
// do not depend on the order of the distances (distance_stats sorts them; the fractions count).
#include "core/metrics/surface_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "core/base/parallel.hpp"
#include "core/geometry/spatial_order.hpp"
#include "core/perception/neighbours.hpp"

namespace pbnbv {

namespace {

constexpr double kMaxSamples = 20e6;

double fraction_within(const std::vector<double>& d, double t) {
  const auto n = std::count_if(d.begin(), d.end(), [t](double x) { return x <= t; });
  return static_cast<double>(n) / static_cast<double>(d.size());
}

}  // namespace

void MetricParams::validate() const {
  kMetricThreshold.checked(threshold_m);
  kMetricSampleDensity.checked(samples_per_cm2);
}

DistanceStats distance_stats(std::vector<double> d) {
  if (d.empty()) throw std::invalid_argument("distance_stats: no distances");
  DistanceStats s;
  s.count = d.size();
  std::sort(d.begin(), d.end());
  double sum = 0, sum2 = 0;
  for (double x : d) {
    sum += x;
    sum2 += x * x;
  }
  const std::size_t n = d.size();
  s.mean_m = sum / static_cast<double>(n);
  s.rmse_m = std::sqrt(sum2 / static_cast<double>(n));
  s.median_m = n % 2 == 1 ? d[n / 2] : 0.5 * (d[n / 2 - 1] + d[n / 2]);
  // Nearest rank: the ceil(0.95 n)-th smallest.
  const std::size_t rank = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(n)));
  s.p95_m = d[std::max<std::size_t>(rank, 1) - 1];
  s.max_m = d.back();
  return s;
}

std::size_t sample_count(double area_m2, double samples_per_cm2) {
  const double n = std::round(area_m2 * 1e4 * samples_per_cm2);
  if (!(n <= kMaxSamples)) {
    throw std::invalid_argument(fmt::format("--sample-density {} per cm^2 on {:.1f} cm^2 of surface is {:.0f} samples, "
                                            "more than {:.0f}: lower the density",
                                            samples_per_cm2, area_m2 * 1e4, n, kMaxSamples));
  }
  return std::max<std::size_t>(1, static_cast<std::size_t>(n));
}

ReferenceSurface::ReferenceSurface(const TriangleMesh& mesh, const MetricParams& params, DistanceHints hints)
    : params_((params.validate(), params)), tree_(mesh, hints, "reference mesh"), area_m2_(mesh_area(mesh)) {
  samples_ = sample_surface(mesh, sample_count(area_m2_, params_.samples_per_cm2), params_.seed);
  if (hints == DistanceHints::kSurface) {
    const std::vector<std::uint32_t> order = morton_order(samples_, "reference samples");
    std::vector<Eigen::Vector3d> sorted(samples_.size());
    for (std::size_t k = 0; k < order.size(); ++k) sorted[k] = samples_[order[k]];
    samples_ = std::move(sorted);
  }
}

SurfaceMetrics ReferenceSurface::compare_cloud(const PointCloud& cloud) const {
  std::vector<Eigen::Vector3d> points;
  points.reserve(cloud.size());
  for (const auto& p : cloud) {
    if (p.allFinite()) points.push_back(p.cast<double>());
  }
  if (points.empty()) {
    throw std::invalid_argument(cloud.empty() ? "model cloud: no points" : "model cloud: no finite point");
  }
  std::vector<double> accuracy = tree_.distances_m(points);

  const NeighbourIndex index(cloud);
  std::vector<double> completeness(samples_.size());
  parallel_for(
      samples_.size(),
      [&](std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
          float d2 = 0;
          index.nearest(samples_[i].cast<float>(), std::numeric_limits<float>::infinity(), d2);
          completeness[i] = std::sqrt(static_cast<double>(d2));
        }
      },
      1024);
  return finish("cloud", std::move(accuracy), std::move(completeness), cloud.size() - points.size());
}

SurfaceMetrics ReferenceSurface::compare_mesh(const TriangleMesh& mesh) const {
  const MeshTree model(mesh, tree_.hints(), "model mesh");
  const std::vector<Eigen::Vector3d> model_samples =
      sample_surface(mesh, sample_count(mesh_area(mesh), params_.samples_per_cm2), params_.seed + 1);
  return finish("mesh", tree_.distances_m(model_samples), model.distances_m(samples_), 0);
}

SurfaceMetrics ReferenceSurface::finish(const char* model, std::vector<double> accuracy,
                                        std::vector<double> completeness, std::size_t skipped) const {
  SurfaceMetrics m;
  m.model = model;
  m.threshold_m = params_.threshold_m;
  m.precision = fraction_within(accuracy, params_.threshold_m);
  m.recall = fraction_within(completeness, params_.threshold_m);
  m.f_score = m.precision + m.recall > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;
  m.accuracy = distance_stats(std::move(accuracy));
  m.completeness = distance_stats(std::move(completeness));
  m.skipped_points = skipped;
  return m;
}

SurfaceMetrics cloud_metrics(const TriangleMesh& reference, const PointCloud& cloud, const MetricParams& params) {
  return ReferenceSurface(reference, params).compare_cloud(cloud);
}

SurfaceMetrics mesh_metrics(const TriangleMesh& reference, const TriangleMesh& model, const MetricParams& params) {
  return ReferenceSurface(reference, params).compare_mesh(model);
}

}  // namespace pbnbv
