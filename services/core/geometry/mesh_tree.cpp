#include "core/geometry/mesh_tree.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <nanoflann.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "core/base/parallel.hpp"
#include "core/geometry/spatial_order.hpp"

namespace pbnbv {

namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

K::Point_3 point(const Eigen::Vector3d& p) { return K::Point_3(p.x(), p.y(), p.z()); }
Eigen::Vector3d vec(const K::Point_3& p) { return {p.x(), p.y(), p.z()}; }

// Distance queries per worker below which another worker does not pay for its start.
constexpr std::size_t kQueriesPerWorker = 1000;

// kSurface's hint points: on each triangle, the centroids of the n^2 small triangles that cutting
// each of its edges into n parts makes (n = 1: its centroid), n = the square root of the
// triangle's area over the mean triangle's, rounded (at least 1): points about as far apart on a
// large triangle as on a mean one, at most 2.25 per triangle all told.
struct HintPoints {
  std::vector<Eigen::Vector3d> xyz;
  std::vector<std::uint32_t> triangle;  // index in MeshTree::Impl::triangles
  // nanoflann's dataset adaptor
  std::size_t kdtree_get_point_count() const { return xyz.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return xyz[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;  // nanoflann computes it
  }
};
using HintDistance = nanoflann::L2_Simple_Adaptor<double, HintPoints, double, std::uint32_t>;
using HintTree = nanoflann::KDTreeSingleIndexAdaptor<HintDistance, HintPoints, 3, std::uint32_t>;

HintPoints hint_points(const std::vector<Triangle>& triangles) {
  std::vector<double> area(triangles.size());
  double total = 0;
  for (std::size_t i = 0; i < triangles.size(); ++i) total += area[i] = std::sqrt(triangles[i].squared_area());
  const double mean = total / static_cast<double>(triangles.size());
  HintPoints h;
  h.xyz.reserve(triangles.size());
  h.triangle.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const Eigen::Vector3d a = vec(triangles[i][0]), ab = vec(triangles[i][1]) - a, ac = vec(triangles[i][2]) - a;
    const int n = std::max(1, static_cast<int>(std::lround(std::sqrt(area[i] / mean))));
    const auto add = [&](double u, double v) {  // barycentric (in units of 1/n) along ab and ac
      h.xyz.push_back(a + (u / n) * ab + (v / n) * ac);
      h.triangle.push_back(static_cast<std::uint32_t>(i));
    };
    for (int u = 0; u < n; ++u) {
      for (int v = 0; u + v < n; ++v) {
        add(u + 1.0 / 3, v + 1.0 / 3);                     // the small triangle pointing as the big one
        if (u + v < n - 1) add(u + 2.0 / 3, v + 2.0 / 3);  // the one upside down beside it
      }
    }
  }
  return h;
}

// nanoflann result set keeping the single nearest point.
struct NearestHint {
  double d2 = std::numeric_limits<double>::infinity();
  std::uint32_t index = 0;
  std::size_t size() const { return 1; }
  bool full() const { return true; }
  double worstDist() const { return d2; }
  bool addPoint(double d, std::uint32_t i) {
    if (d < d2) {
      d2 = d;
      index = i;
    }
    return true;
  }
};

// The search for the nearest point of the surface: CGAL's Projection_traits
// (AABB_traversal_traits.h), with the same answer (a triangle's point is taken when it is not
// farther than the best one so far; a node is opened when its box is not farther), the best
// point's squared distance kept rather than recomputed at every node, and a triangle whose
// plane is already farther than the best point skipped before its projection (its points are no
// nearer than its plane; only a triangle as near as the best point to within rounding can be
// skipped wrongly, and its distance is the best one's but for the last bits).
class NearestTriangle {
 public:
  using Node = CGAL::AABB_node<Tree::AABB_traits>;
  // Starts from the query's projection onto `first`.
  NearestTriangle(const K::Point_3& q, TriangleIterator first)
      : best_(K().construct_projected_point_3_object()(*first, q)), d2_(CGAL::squared_distance(q, best_)) {}

  bool go_further() const { return true; }

  void intersection(const K::Point_3& q, const Primitive& primitive) {
    const Triangle& t = *primitive.id();
    const K::Vector_3 n = CGAL::cross_product(t[1] - t[0], t[2] - t[0]);
    const double s = n * (q - t[0]);  // the plane's distance times |n|
    const double n2 = n.squared_length();
    if (n2 > 0.0 && s * s > d2_ * n2) return;
    const K::Point_3 p = K().construct_projected_point_3_object()(t, q);
    const double d2 = CGAL::squared_distance(q, p);
    if (d2 > d2_ || p == best_) return;
    best_ = p;
    d2_ = d2;
  }

  bool do_intersect(const K::Point_3& q, const Node& node) const {
    const CGAL::Bbox_3& b = node.bbox();
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      if (q[k] < b.min(k)) d2 += (b.min(k) - q[k]) * (b.min(k) - q[k]);
      else if (q[k] > b.max(k)) d2 += (q[k] - b.max(k)) * (q[k] - b.max(k));
    }
    return d2 <= d2_;
  }

  double squared_distance() const { return d2_; }

 private:
  K::Point_3 best_;
  double d2_;
};

}  // namespace

struct MeshTree::Impl {
  std::string what;
  DistanceHints hints = DistanceHints::kNone;
  std::vector<Triangle> triangles;  // the tree's primitives point into this
  Tree tree;
  HintPoints hint_points;              // kSurface
  std::unique_ptr<HintTree> hint_tree;  // kSurface, over hint_points

  double squared_distance(const K::Point_3& q) const {
    if (hints == DistanceHints::kCgal) return tree.squared_distance(q);
    TriangleIterator first = triangles.cbegin();
    if (hint_tree) {
      NearestHint nearest;
      const double xyz[3] = {q.x(), q.y(), q.z()};
      hint_tree->findNeighbors(nearest, xyz, nanoflann::SearchParams());
      first += hint_points.triangle[nearest.index];
    }
    NearestTriangle search(q, first);
    tree.traversal(q, search);
    return search.squared_distance();
  }
};

MeshTree::MeshTree(const TriangleMesh& mesh, DistanceHints hints, const std::string& what)
    : impl_(std::make_unique<Impl>()) {
  impl_->what = what;
  impl_->hints = hints;
  check_triangle_indices(mesh, what);
  impl_->triangles.reserve(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    if (!(a.allFinite() && b.allFinite() && c.allFinite())) {
      throw std::invalid_argument(what + ": mesh triangle " + std::to_string(i) + " has a non-finite vertex");
    }
    if ((b - a).cross(c - a).squaredNorm() == 0.0) continue;  // zero area: CGAL rejects it
    impl_->triangles.emplace_back(point(a), point(b), point(c));
  }
  if (impl_->triangles.empty()) {
    throw std::invalid_argument(what + ": mesh has no triangle of non-zero area (" +
                                std::to_string(mesh.triangles.size()) + " triangles)");
  }
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  // Built now or never: a query never builds anything, so queries stay const and thread-safe.
  if (hints == DistanceHints::kCgal) {
    impl_->tree.accelerate_distance_queries();
  } else {
    impl_->tree.do_not_accelerate_distance_queries();
  }
  if (hints == DistanceHints::kSurface) {
    impl_->hint_points = hint_points(impl_->triangles);
    // Leaves of at most 10 points, nanoflann's default (as NeighbourIndex's, core/perception).
    impl_->hint_tree = std::make_unique<HintTree>(3, impl_->hint_points, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  }
}

MeshTree::~MeshTree() = default;
MeshTree::MeshTree(MeshTree&&) noexcept = default;
MeshTree& MeshTree::operator=(MeshTree&&) noexcept = default;

std::size_t MeshTree::num_triangles() const { return impl_->triangles.size(); }
DistanceHints MeshTree::hints() const { return impl_->hints; }

double MeshTree::distance_m(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) throw std::invalid_argument(impl_->what + ": the query point is not finite");
  return std::sqrt(impl_->squared_distance(point(p)));
}

std::vector<double> MeshTree::distances_m(const std::vector<Eigen::Vector3d>& points) const {
  std::vector<double> out(points.size());
  const Impl& impl = *impl_;
  if (impl.hints == DistanceHints::kCgal) {  // the caller's order, as before kSurface
    parallel_for(points.size(), [&](std::size_t begin, std::size_t end, int) {
      for (std::size_t i = begin; i < end; ++i) {
        const Eigen::Vector3d& p = points[i];
        if (!p.allFinite()) {
          throw std::invalid_argument(impl.what + ": points[" + std::to_string(i) + "] is not finite");
        }
        out[i] = std::sqrt(impl.squared_distance(point(p)));
      }
    }, kQueriesPerWorker);
    return out;
  }
  const std::vector<std::uint32_t> order = morton_order(points, impl.what);  // names a non-finite point
  parallel_for(points.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t i = order[k];
      out[i] = std::sqrt(impl.squared_distance(point(points[i])));
    }
  }, kQueriesPerWorker);
  return out;
}

bool MeshTree::segment_hits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  if (!a.allFinite() || !b.allFinite()) {
    throw std::invalid_argument(impl_->what + ": a segment end is not finite");
  }
  if (a == b) return impl_->tree.do_intersect(point(a));  // a point: CGAL's segment needs a != b
  return impl_->tree.do_intersect(K::Segment_3(point(a), point(b)));
}

bool MeshTree::ray_hits(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
  if (!origin.allFinite() || !direction.allFinite() || direction.squaredNorm() == 0.0) {
    throw std::invalid_argument(impl_->what + ": a ray needs a finite origin and a finite, non-zero direction");
  }
  return impl_->tree.do_intersect(K::Ray_3(point(origin), K::Vector_3(direction.x(), direction.y(), direction.z())));
}

}  // namespace pbnbv
