#pragma once
// Internal to core/perception (includes PCL; only this folder's .cpp files may include it):
// NeighbourIndex (nanoflann) behind the pcl::search::KdTree interface PCL's ICP and normal
// estimation take, in place of the FLANN tree they build by default (with that tree,
// registration_bench took 2.3 to 2.9 times the CPU time, and the queries of neighbours_bench
// 2.2 to 4.8 times as long).
#include <pcl/point_cloud.h>
#include <pcl/search/kdtree.h>

#include <cstddef>
#include <limits>
#include <vector>

#include "core/perception/neighbours.hpp"

namespace pbnbv {

// Answers pcl::search queries from a NeighbourIndex over the input cloud's xyz. A query for a
// single neighbour (ICP's correspondences) only looks as far as set_k1_bound (m): with nothing
// nearer it reports a miss at distance FLT_MAX, which ICP's distance test drops, so far-off
// frames stay cheap.
template <typename PointT>
class IndexSearch : public pcl::search::KdTree<PointT> {
 public:
  using Base = pcl::search::KdTree<PointT>;
  using typename Base::IndicesConstPtr;
  using typename Base::PointCloudConstPtr;
  using pcl::search::Search<PointT>::nearestKSearch;
  using pcl::search::Search<PointT>::radiusSearch;
  using Ptr = pcl::shared_ptr<IndexSearch<PointT>>;

  IndexSearch() : Base(true) {}

  // Indexes the cloud's points (those in `indices` if given; the indices returned are the
  // cloud's either way).
  void setInputCloud(const PointCloudConstPtr& cloud,
                     const IndicesConstPtr& indices = IndicesConstPtr()) override {
    this->input_ = cloud;
    this->indices_ = indices;
    pbnbv::PointCloud xyz;
    if (cloud) {
      // Points outside `indices` are NaN, which NeighbourIndex leaves out.
      const Eigen::Vector3f nan = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
      xyz.assign(cloud->size(), indices ? nan : Eigen::Vector3f::Zero());
      if (indices) {
        for (const pcl::index_t i : *indices) xyz[static_cast<std::size_t>(i)] = (*cloud)[i].getVector3fMap();
      } else {
        for (std::size_t i = 0; i < cloud->size(); ++i) xyz[i] = (*cloud)[i].getVector3fMap();
      }
    }
    index_ = NeighbourIndex(xyz);
  }

  // The k nearest points, nearest first (k = 1: the nearest within the k1 bound, or a miss).
  int nearestKSearch(const PointT& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override {
    if (k != 1) {
      index_.knn(point.getVector3fMap(), k, k_indices, k_sqr_distances);
      return static_cast<int>(k_indices.size());
    }
    k_indices.resize(1);
    k_sqr_distances.resize(1);
    float d2;
    const int i = index_.nearest(point.getVector3fMap(), k1_bound_d2_, d2);
    if (i < 0) {
      k_indices[0] = 0;
      k_sqr_distances[0] = std::numeric_limits<float>::max();
      return index_.size() == 0 ? 0 : 1;
    }
    k_indices[0] = i;
    k_sqr_distances[0] = d2;
    return 1;
  }

  // Every point within `radius`, nearest first, at most max_nn of them (0: all).
  int radiusSearch(const PointT& point, double radius, pcl::Indices& k_indices,
                   std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override {
    index_.within(point.getVector3fMap(), static_cast<float>(radius * radius), k_indices, k_sqr_distances);
    if (max_nn > 0 && k_indices.size() > max_nn) {
      k_indices.resize(max_nn);
      k_sqr_distances.resize(max_nn);
    }
    return static_cast<int>(k_indices.size());
  }

  // Single-neighbour queries look only this far (m); unbounded by default.
  void set_k1_bound(double d) { k1_bound_d2_ = static_cast<float>(d * d); }
  const NeighbourIndex& index() const { return index_; }

 private:
  NeighbourIndex index_{pbnbv::PointCloud{}};
  float k1_bound_d2_ = std::numeric_limits<float>::infinity();
};

}  // namespace pbnbv
