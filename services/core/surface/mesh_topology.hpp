#pragma once
// What a triangle mesh's connectivity says: boundary edges (used by one triangle) and the loops
// they form (the holes), non-manifold edges, watertightness, enclosed volume; vertex normals.
#include <Eigen/Core>
#include <vector>

#include "core/geometry/colour_image.hpp"
#include "core/geometry/mesh.hpp"

namespace pbnbv {

struct MeshTopology {
  std::size_t edges = 0;
  std::size_t boundary_edges = 0;      // used by exactly one triangle
  std::size_t non_manifold_edges = 0;  // used by three or more
  std::size_t boundary_loops = 0;      // closed chains of boundary edges (holes, open rims)
  double boundary_length_m = 0;        // their total length
  bool watertight = false;             // triangles, no boundary and no non-manifold edge
  double area_m2 = 0;
  double volume_m3 = 0;  // signed (divergence theorem): > 0 for outward triangles; exact when watertight
};

MeshTopology mesh_topology(const TriangleMesh& mesh);

// Closes every boundary loop no longer than `max_boundary_m` with a fan of triangles from its
// centroid (oriented like the surface around it). Returns the number of holes filled.
std::size_t fill_small_holes(TriangleMesh& mesh, double max_boundary_m);

// Unit normal per vertex: the area-weighted mean of its triangles' normals (zero when isolated).
std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh);

// Keeps the connected components (sharing vertices) with at least `min_triangles` triangles;
// unused vertices are dropped. Returns the number of triangles removed.
std::size_t remove_small_components(TriangleMesh& mesh, std::size_t min_triangles);

// Binary little-endian PLY: float x y z nx ny nz per vertex (and uchar red green blue with
// `colours`, one per vertex), faces as vertex_indices lists, a comment giving units and frame.
// Written atomically (temporary file + rename); throws naming the path on error, and
// std::invalid_argument when normals or colours are not one per vertex.
void write_mesh_ply(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& normals,
                    const std::string& path, const std::vector<Rgb>& colours = {});

}  // namespace pbnbv
