#pragma once
// Surface coverage of a scan, as the paper measures it: points sampled uniformly by area on the
// (normalised) ground-truth mesh; a sample is covered when the captured cloud has a point within
// a radius of it; coverage = covered / total * 100.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/geometry/point_cloud.hpp"
#include "core/geometry/mesh.hpp"

namespace pbnbv {

struct CoverageParams {
  std::size_t num_samples = 10000;  // surface samples (sample_surface)
  std::uint64_t seed = 1;           // sample_surface seed: fixed, so runs are comparable
  double radius_m = 0.005;          // a sample is covered by a cloud point within this distance
};

// Accumulates coverage as views arrive. The samples are fixed at construction and indexed by a
// uniform grid (cell edge >= radius), so add() costs a few cell look-ups per cloud point;
// samples already covered are not tested again.
class CoverageEvaluator {
 public:
  // Samples params.num_samples points on `mesh`. Throws std::invalid_argument naming the
  // parameter for num_samples == 0 or a radius that is not a positive finite number, and when
  // the mesh has no triangles or zero area.
  CoverageEvaluator(const TriangleMesh& mesh, const CoverageParams& params = {});
  // Uses the given surface samples. Throws std::invalid_argument for no samples, a non-finite
  // sample (naming its index) or a bad radius.
  explicit CoverageEvaluator(std::vector<Eigen::Vector3d> surface_points, double radius_m = 0.005);

  const std::vector<Eigen::Vector3d>& samples() const { return samples_; }
  double radius_m() const { return radius_; }

  // Marks the samples that have a point of `cloud` within the radius (distance <= radius;
  // accumulates over calls, as views arrive) and returns the coverage in percent after adding
  // it. Non-finite cloud points are skipped and counted in rejected_points().
  double add(const std::vector<Eigen::Vector3d>& cloud);
  // The same for the scanner's float clouds.
  double add_cloud(const PointCloud& cloud);

  // Percent of all samples covered.
  double coverage_percent() const;
  // Coverage over a subset of samples (e.g. the observable ones): mask[i] != 0 selects sample i;
  // percent of the selected ones covered. Throws std::invalid_argument if the mask size differs
  // from the number of samples; returns 0 when nothing is selected.
  double coverage_percent(const std::vector<uint8_t>& mask) const;

  const std::vector<uint8_t>& covered() const { return covered_; }  // per sample, 1 = covered
  std::size_t num_covered() const { return num_covered_; }
  std::size_t rejected_points() const { return rejected_; }  // non-finite points seen by add()

  // Back to nothing covered (the samples and grid are kept).
  void reset();

 private:
  void build_grid();
  template <typename Vec>
  void mark(const Vec& p);

  std::vector<Eigen::Vector3d> samples_;  // in the caller's order
  double radius_ = 0;
  std::vector<uint8_t> covered_;          // in the caller's order
  std::size_t num_covered_ = 0;
  std::size_t rejected_ = 0;

  // Dense grid over the samples' bounding box; samples sorted by cell (CSR layout).
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero();  // grid origin (samples' min corner)
  Eigen::Vector3d hi_ = Eigen::Vector3d::Zero();  // samples' max corner
  double cell_ = 0;                               // cell edge, >= radius_
  Eigen::Array3i dims_ = Eigen::Array3i::Ones();
  std::vector<uint32_t> cell_start_;              // cells + 1 offsets into sorted_*
  std::vector<uint32_t> cell_left_;               // uncovered samples per cell
  std::vector<Eigen::Vector3d> sorted_points_;    // samples in cell order
  std::vector<uint32_t> sorted_index_;            // sorted position -> index in samples_
  std::vector<uint8_t> sorted_covered_;           // covered flag in cell order
};

// One-shot: coverage of `cloud` on `mesh` in percent.
double coverage_percent(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& cloud,
                        const CoverageParams& params = {});

}  // namespace pbnbv
