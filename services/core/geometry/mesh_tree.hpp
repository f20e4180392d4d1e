#pragma once
// The one AABB tree over a triangle mesh (CGAL's, kept inside mesh_tree.cpp): built once from a
// TriangleMesh, then asked for distances to the surface and whether a segment or a ray hits it.
// Every query is const and may run on several threads at once.
#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/geometry/mesh.hpp"

namespace pbnbv {

// How a distance query finds its first candidate, the point whose distance bounds the search of
// the tree (a tree node farther than it is never opened). Every kind gives the same distances,
// exact to the last bit but for a point equally near two triangles (then either one's rounding);
// they differ in speed only. Intersection tests use none of them.
enum class DistanceHints {
  // No index: the query's projection onto the first triangle. Nothing to build; for a tree asked
  // mostly for intersections, or for a few distances.
  kNone,
  // CGAL's own k-d tree of one vertex per triangle (AABB_tree::accelerate_distance_queries) and
  // CGAL's search, the queries of a batch taken in the caller's order: how distances were asked
  // before kSurface, kept as the yardstick of its tests and benchmarks (mesh_tree_bench).
  kCgal,
  // A k-d tree (nanoflann) of points spread over the triangles (each triangle's centroid, more
  // on a large one); the query's projection onto the triangle of the nearest of them starts the
  // search, which then skips a triangle whose plane is already farther than the best point, and
  // a batch is taken in Morton order (spatial_order.hpp). Costs about as much to build as a few
  // thousand queries.
  kSurface,
};

class MeshTree {
 public:
  // Builds the tree over the mesh's triangles of non-zero area (zero-area ones cannot be hit and
  // are never the nearest), and the index `hints` asks for. Throws std::invalid_argument
  // starting with `what` for a triangle index outside the vertices, a non-finite vertex of a
  // triangle, or a mesh with no triangle of non-zero area.
  explicit MeshTree(const TriangleMesh& mesh, DistanceHints hints = DistanceHints::kNone,
                    const std::string& what = "MeshTree");
  ~MeshTree();
  MeshTree(MeshTree&&) noexcept;
  MeshTree& operator=(MeshTree&&) noexcept;
  MeshTree(const MeshTree&) = delete;
  MeshTree& operator=(const MeshTree&) = delete;

  // Triangles in the tree (those of non-zero area).
  std::size_t num_triangles() const;
  DistanceHints hints() const;

  // Euclidean distance from `point` to the nearest point of the surface (triangles, not
  // vertices), metres. Throws std::invalid_argument for a non-finite point.
  double distance_m(const Eigen::Vector3d& point) const;
  // distance_m of every point (in the caller's order), on the workers of core/base/parallel.hpp.
  // Throws std::invalid_argument naming points[i] for a non-finite point.
  std::vector<double> distances_m(const std::vector<Eigen::Vector3d>& points) const;

  // Whether the closed segment from a to b meets a triangle.
  bool segment_hits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
  // Whether the ray from `origin` along `direction` (non-zero) meets a triangle.
  bool ray_hits(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbnbv
