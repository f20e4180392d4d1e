#include "core/geometry/mesh_tree.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

#include "core/base/parallel.hpp"

namespace pbnbv {

namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

K::Point_3 point(const Eigen::Vector3d& p) { return K::Point_3(p.x(), p.y(), p.z()); }

// Distance queries per worker below which another worker does not pay for its start.
constexpr std::size_t kQueriesPerWorker = 1000;

}  // namespace

struct MeshTree::Impl {
  std::string what;
  std::vector<Triangle> triangles;  // the tree's primitives point into this
  Tree tree;
};

MeshTree::MeshTree(const TriangleMesh& mesh, bool distance_hints, const std::string& what)
    : impl_(std::make_unique<Impl>()) {
  impl_->what = what;
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
  if (distance_hints) {
    impl_->tree.accelerate_distance_queries();
  } else {
    impl_->tree.do_not_accelerate_distance_queries();
  }
}

MeshTree::~MeshTree() = default;
MeshTree::MeshTree(MeshTree&&) noexcept = default;
MeshTree& MeshTree::operator=(MeshTree&&) noexcept = default;

std::size_t MeshTree::num_triangles() const { return impl_->triangles.size(); }

double MeshTree::distance_m(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) throw std::invalid_argument(impl_->what + ": the query point is not finite");
  return std::sqrt(impl_->tree.squared_distance(point(p)));
}

std::vector<double> MeshTree::distances_m(const std::vector<Eigen::Vector3d>& points) const {
  std::vector<double> out(points.size());
  const Tree& tree = impl_->tree;
  parallel_for(points.size(), [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d& p = points[i];
      if (!p.allFinite()) {
        throw std::invalid_argument(impl_->what + ": points[" + std::to_string(i) + "] is not finite");
      }
      out[i] = std::sqrt(tree.squared_distance(point(p)));
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
