#pragma once
// Nearest-neighbour queries over a fixed set of points (a k-d tree), and surface normals fitted
// to each point's nearest neighbours: what registration's ICP, its gates and its normals use.
#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <vector>

#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

// A static k-d tree over the points of a cloud. Queries are const and may run concurrently.
class NeighbourIndex {
 public:
  // Indexes the finite points of `points` (copied); results are indices into `points`.
  explicit NeighbourIndex(const PointCloud& points);
  ~NeighbourIndex();
  NeighbourIndex(NeighbourIndex&&) noexcept;
  NeighbourIndex& operator=(NeighbourIndex&&) noexcept;

  // Number of points indexed (the finite ones).
  std::size_t size() const;

  // The point nearest to q among those within sqrt(max_d2) m: its index (its squared distance
  // in d2), or -1 if there is none.
  int nearest(const Eigen::Vector3f& q, float max_d2, float& d2) const;

  // The min(k, size()) points nearest to q, nearest first: indices and squared distances.
  void knn(const Eigen::Vector3f& q, int k, std::vector<int>& indices, std::vector<float>& d2) const;

  // Every point within sqrt(r2) m of q, nearest first: indices and squared distances.
  void within(const Eigen::Vector3f& q, float r2, std::vector<int>& indices, std::vector<float>& d2) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A unit normal per point (PCL's NormalEstimationOMP over a NeighbourIndex): the plane fitted
// (least squares) to the point's `neighbours` nearest points, turned to face the origin;
// `curvature` = smallest eigenvalue / trace of their covariance. `valid` is 0 where no plane
// could be fitted (fewer than 3 neighbours, non-finite fit); the normal is then zero.
struct SurfaceNormals {
  std::vector<Eigen::Vector3f> normals;
  std::vector<float> curvature;
  std::vector<char> valid;
};
SurfaceNormals estimate_normals(const PointCloud& points, int neighbours);

}  // namespace pbnbv
