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

class MeshTree {
 public:
  // Builds the tree over the mesh's triangles of non-zero area (zero-area ones cannot be hit and
  // are never the nearest). `distance_hints`: also build CGAL's k-d tree of points on the
  // triangles, which makes each distance query faster and costs about as much as a few dozen
  // queries (the distances are the same either way); intersection tests do not use it. Throws
  // std::invalid_argument starting with `what` for a triangle index outside the vertices, a
  // non-finite vertex of a triangle, or a mesh with no triangle of non-zero area.
  explicit MeshTree(const TriangleMesh& mesh, bool distance_hints = false,
                    const std::string& what = "MeshTree");
  ~MeshTree();
  MeshTree(MeshTree&&) noexcept;
  MeshTree& operator=(MeshTree&&) noexcept;
  MeshTree(const MeshTree&) = delete;
  MeshTree& operator=(const MeshTree&) = delete;

  // Triangles in the tree (those of non-zero area).
  std::size_t num_triangles() const;

  // Euclidean distance from `point` to the nearest point of the surface (triangles, not
  // vertices), metres. Throws std::invalid_argument for a non-finite point.
  double distance_m(const Eigen::Vector3d& point) const;
  // distance_m of every point, on the workers of core/base/parallel.hpp. Throws
  // std::invalid_argument naming points[i] for the first non-finite point met.
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
