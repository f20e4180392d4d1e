#pragma once
// How close a model of an object is to its true surface, as multi-view stereo benchmarks report
// it (Knapitsch et al. 2017, Tanks and Temples):
//   accuracy      distance from each model point to the reference surface (point to triangle);
//   completeness  distance from each reference sample to the model (to the nearest cloud point,
//                 or point to triangle for a model mesh);
//   precision     fraction of model points within the threshold t of the reference;
//   recall        fraction of reference samples within t of the model;
//   F-score       2 P R / (P + R) (0 when both are 0).
// A model mesh is sampled uniformly by area at the stated density, like the reference; a cloud
// is used point by point. Distances in metres; fractions in [0, 1].
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/geometry/mesh.hpp"
#include "core/geometry/mesh_tree.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/metrics/metrics_options.hpp"

namespace pbnbv {

struct MetricParams {
  double threshold_m = kMetricThreshold.value;
  double samples_per_cm2 = kMetricSampleDensity.value;  // on meshes (reference and model)
  std::uint64_t seed = 1;                               // sample_surface seed: runs are comparable

  // Throws std::invalid_argument naming the setting and its range.
  void validate() const;
};

// Summary of a set of distances, metres. The median is the middle value (the mean of the two
// middle ones for an even count); p95 the smallest distance with at least 95 % of them at or
// below it (nearest rank).
struct DistanceStats {
  std::size_t count = 0;
  double mean_m = 0, median_m = 0, rmse_m = 0, p95_m = 0, max_m = 0;
};
// Throws std::invalid_argument for no distances.
DistanceStats distance_stats(std::vector<double> distances);

struct SurfaceMetrics {
  std::string model;               // "cloud" or "mesh"
  double threshold_m = 0;
  DistanceStats accuracy;          // model points (or samples) -> reference surface
  DistanceStats completeness;      // reference samples -> model
  double precision = 0, recall = 0, f_score = 0;
  std::size_t skipped_points = 0;  // non-finite model points, left out
};

// Number of samples a mesh of `area_m2` gets at `samples_per_cm2` (rounded, at least 1). Throws
// std::invalid_argument when that exceeds 20 million (a density too high for the mesh's size).
std::size_t sample_count(double area_m2, double samples_per_cm2);

// The reference surface, built once (its tree and its samples) and compared with any number of
// models. Queries are const.
class ReferenceSurface {
 public:
  // `hints`: how the trees of the reference and of a model mesh start their distance queries
  // (core/geometry/mesh_tree.hpp); every kind gives the same figures. kSurface (the default)
  // also keeps the samples in Morton order (core/geometry/spatial_order.hpp), so the queries
  // that start from them (completeness) walk each tree in order; kCgal keeps them in the order
  // drawn: the metrics as computed before kSurface, for the tests and benchmarks that compare
  // the two. Throws std::invalid_argument (starting with "reference mesh") for a mesh with no
  // triangle of non-zero area, a bad index or vertex, or bad params.
  explicit ReferenceSurface(const TriangleMesh& mesh, const MetricParams& params = {},
                            DistanceHints hints = DistanceHints::kSurface);

  const MetricParams& params() const { return params_; }
  // sample_surface(mesh, sample_count(area, density), seed), in the order `hints` says.
  const std::vector<Eigen::Vector3d>& samples() const { return samples_; }
  double area_m2() const { return area_m2_; }

  // Throws std::invalid_argument for a cloud without a finite point.
  SurfaceMetrics compare_cloud(const PointCloud& cloud) const;
  // Throws std::invalid_argument (starting with "model mesh") for a mesh with no triangle of
  // non-zero area or a bad index or vertex.
  SurfaceMetrics compare_mesh(const TriangleMesh& mesh) const;

 private:
  SurfaceMetrics finish(const char* model, std::vector<double> accuracy, std::vector<double> completeness,
                        std::size_t skipped) const;

  MetricParams params_;
  MeshTree tree_;
  double area_m2_ = 0;
  std::vector<Eigen::Vector3d> samples_;
};

// One-shot forms.
SurfaceMetrics cloud_metrics(const TriangleMesh& reference, const PointCloud& cloud, const MetricParams& params = {});
SurfaceMetrics mesh_metrics(const TriangleMesh& reference, const TriangleMesh& model, const MetricParams& params = {});

}  // namespace pbnbv
