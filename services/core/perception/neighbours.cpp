// Nearest neighbours with nanoflann's k-d tree; normals by PCL's NormalEstimationOMP over it.
#include "core/perception/neighbours.hpp"

#include <pcl/features/normal_3d_omp.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <nanoflann.hpp>

#include <algorithm>
#include <limits>
#include <utility>

#include "core/base/parallel.hpp"
#include "core/perception/index_search.hpp"

namespace pbnbv {

namespace {

// The finite points, as nanoflann's dataset adaptor reads them.
struct Points {
  std::vector<Eigen::Vector3f> xyz;
  std::vector<int> ids;  // index in the caller's cloud of each point of xyz
  std::size_t kdtree_get_point_count() const { return xyz.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return xyz[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;  // nanoflann computes it
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Points, float, uint32_t>,
                                                 Points, 3, uint32_t>;

// nanoflann result set keeping the single nearest point closer than a bound (the bound
// shrinks as nearer points are found, which prunes the search).
struct NearestWithin {
  float bound_d2;
  uint32_t index = 0;
  bool found = false;
  std::size_t size() const { return found ? 1 : 0; }
  bool full() const { return true; }
  float worstDist() const { return bound_d2; }
  bool addPoint(float d2, uint32_t i) {
    if (d2 < bound_d2) {
      bound_d2 = d2;
      index = i;
      found = true;
    }
    return true;
  }
};

}  // namespace

struct NeighbourIndex::Impl {
  Points points;
  // Leaves of at most 10 points (nanoflann's default): in neighbours_bench, 16 was within the
  // noise of it, 4 and 32 slower (k-NN 142 and 174 ms against 125 ms).
  Tree tree{3, points, nanoflann::KDTreeSingleIndexAdaptorParams(10)};
  explicit Impl(Points p) : points(std::move(p)) {}
  Impl(const Impl&) = delete;
};

NeighbourIndex::NeighbourIndex(const PointCloud& cloud) {
  Points p;
  p.xyz.reserve(cloud.size());
  p.ids.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud[i].allFinite()) continue;
    p.xyz.push_back(cloud[i]);
    p.ids.push_back(static_cast<int>(i));
  }
  // The tree is built when Impl is constructed, over Impl's own copy of the points.
  impl_ = std::make_unique<Impl>(std::move(p));
}

NeighbourIndex::~NeighbourIndex() = default;
NeighbourIndex::NeighbourIndex(NeighbourIndex&&) noexcept = default;
NeighbourIndex& NeighbourIndex::operator=(NeighbourIndex&&) noexcept = default;

std::size_t NeighbourIndex::size() const { return impl_->points.xyz.size(); }

int NeighbourIndex::nearest(const Eigen::Vector3f& q, float max_d2, float& d2) const {
  NearestWithin r{max_d2};
  impl_->tree.findNeighbors(r, q.data(), nanoflann::SearchParams());
  d2 = r.bound_d2;
  return r.found ? impl_->points.ids[r.index] : -1;
}

void NeighbourIndex::knn(const Eigen::Vector3f& q, int k, std::vector<int>& indices,
                         std::vector<float>& d2) const {
  const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(std::max(k, 0)), size());
  std::vector<uint32_t> found(n);
  d2.resize(n);
  nanoflann::KNNResultSet<float, uint32_t> r(n);
  if (n > 0) {
    r.init(found.data(), d2.data());
    impl_->tree.findNeighbors(r, q.data(), nanoflann::SearchParams());
  }
  d2.resize(r.size());
  indices.resize(r.size());
  for (std::size_t i = 0; i < r.size(); ++i) indices[i] = impl_->points.ids[found[i]];
}

void NeighbourIndex::within(const Eigen::Vector3f& q, float r2, std::vector<int>& indices,
                            std::vector<float>& d2) const {
  std::vector<std::pair<uint32_t, float>> found;
  impl_->tree.radiusSearch(q.data(), r2, found, nanoflann::SearchParams(32, 0.0f, true));
  indices.resize(found.size());
  d2.resize(found.size());
  for (std::size_t i = 0; i < found.size(); ++i) {
    indices[i] = impl_->points.ids[found[i].first];
    d2[i] = found[i].second;
  }
}

SurfaceNormals estimate_normals(const PointCloud& points, int neighbours) {
  const std::size_t n = points.size();
  SurfaceNormals out;
  out.normals.assign(n, Eigen::Vector3f::Zero());
  out.curvature.assign(n, 0.0f);
  out.valid.assign(n, 0);
  if (n < 3) return out;
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  xyz->resize(n);
  for (std::size_t i = 0; i < n; ++i) (*xyz)[i].getVector3fMap() = points[i];
  // PCL's estimator (OpenMP inside) on the workers the thread policy gives: at least 2,000
  // points each (below that, starting threads costs more than it saves), at most 4. Its
  // neighbour search is the nanoflann index, as fast as our own loop over it was
  // (registration_bench 356 vs 363 ms CPU) and 1.6 times faster than with PCL's FLANN tree.
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> estimator(worker_count(n, 2000, 4));
  estimator.setInputCloud(xyz);
  estimator.setSearchMethod(IndexSearch<pcl::PointXYZ>::Ptr(new IndexSearch<pcl::PointXYZ>));
  estimator.setKSearch(std::min<int>(neighbours, static_cast<int>(n)));
  pcl::PointCloud<pcl::Normal> normals;
  estimator.compute(normals);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f v = normals[i].getNormalVector3fMap();
    if (!v.allFinite() || !(v.norm() > 0.5f)) continue;  // no plane (NaN), or not a unit normal
    out.normals[i] = v;
    out.curvature[i] = normals[i].curvature;
    out.valid[i] = 1;
  }
  return out;
}

}  // namespace pbnbv
