#pragma once
// Triangle meshes: the paper's normalisation, primitives, surface sampling and
// point-to-surface distances. Reading and writing mesh files: core/io/mesh_file.hpp.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/base/enum_names.hpp"

namespace pbnbv {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;  // indices into vertices, counter-clockwise outward
};

// Which axis of the mesh file points up in the world.
enum class UpAxis { kZ, kY, kX };
template <>
struct EnumNames<UpAxis> {
  static constexpr std::string_view what = "up axis";
  static constexpr std::array<NamedValue<UpAxis>, 3> names{{{UpAxis::kZ, "z"}, {UpAxis::kY, "y"}, {UpAxis::kX, "x"}}};
};


// What normalisation did, so anyone can map the mesh file's coordinates to the object frame:
//   p_object = scale * (up_rotation * p_file) - centre_m
struct MeshNormalisation {
  std::string source_path;
  UpAxis up = UpAxis::kZ;
  Eigen::Matrix3d up_rotation = Eigen::Matrix3d::Identity();  // file axes -> object axes
  double scale = 1.0;                                          // isotropic
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();          // scaled bbox centre, removed
  Eigen::Vector3d extent_m = Eigen::Vector3d::Zero();          // bbox edge lengths after
  std::size_t num_vertices = 0;
  std::size_t num_triangles = 0;
};

// Normalises in place as in the paper: rotate so `up` becomes +z, scale isotropically so the
// shortest bounding-box edge is `shortest_edge_m`, move the bounding-box centre to the origin.
MeshNormalisation normalise_mesh(TriangleMesh& mesh, double shortest_edge_m, UpAxis up);

// Throws std::invalid_argument "<what>: mesh triangle i has vertex index v outside [0, n)" for
// the first triangle that refers to a vertex that does not exist.
void check_triangle_indices(const TriangleMesh& mesh, const std::string& what);

// Axis-aligned bounding box corners of the mesh.
void mesh_bounds(const TriangleMesh& mesh, Eigen::Vector3d& lo, Eigen::Vector3d& hi);

// Meshes with known geometry, for tests and the built-in objects.
TriangleMesh make_icosphere(double radius_m, int subdivisions);   // centred at the origin
TriangleMesh make_box(const Eigen::Vector3d& size_m);             // centred at the origin

// Total surface area, m^2.
double mesh_area(const TriangleMesh& mesh);

// `n` points uniformly distributed by area on the surface, deterministic for a seed. With
// `face_normals`, it also receives each point's triangle normal ((b - a) x (c - a), unit length;
// zero on a zero-area triangle); the points do not depend on whether it is asked for.
std::vector<Eigen::Vector3d> sample_surface(const TriangleMesh& mesh, std::size_t n,
                                            std::uint64_t seed,
                                            std::vector<Eigen::Vector3d>* face_normals = nullptr);

// Exact Euclidean distance from each point to the nearest point of the mesh surface
// (triangles, not vertices): MeshTree (mesh_tree.hpp) built for this one batch. Throws
// std::invalid_argument naming the bad triangle or point (see MeshTree); no points: empty.
std::vector<double> distances_to_surface(const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3d>& points);

}  // namespace pbnbv
