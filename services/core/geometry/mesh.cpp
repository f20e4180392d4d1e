#include "core/geometry/mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <unordered_map>

#include "core/geometry/mesh_tree.hpp"

namespace pbnbv {

void check_triangle_indices(const TriangleMesh& mesh, const std::string& what) {
  const long long nv = static_cast<long long>(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[i][k];
      if (v < 0 || v >= nv) {
        throw std::invalid_argument(what + ": mesh triangle " + std::to_string(i) + " has vertex index " +
                                    std::to_string(v) + " outside [0, " + std::to_string(nv) + ")");
      }
    }
  }
}

void mesh_bounds(const TriangleMesh& mesh, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
  if (mesh.vertices.empty()) {
    lo.setZero();
    hi.setZero();
    return;
  }
  lo = hi = mesh.vertices.front();
  for (const auto& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
}

MeshNormalisation normalise_mesh(TriangleMesh& mesh, double shortest_edge_m, UpAxis up) {
  if (!(shortest_edge_m > 0.0) || !std::isfinite(shortest_edge_m)) {
    throw std::invalid_argument("normalise_mesh: shortest_edge_m must be positive and finite");
  }
  if (mesh.vertices.empty()) throw std::invalid_argument("normalise_mesh: mesh has no vertices");
  MeshNormalisation n;
  n.up = up;
  if (up == UpAxis::kY) {
    // (x, y, z) -> (x, -z, y): file +y becomes +z, a proper rotation about x by +90 degrees.
    n.up_rotation << 1, 0, 0,
                     0, 0, -1,
                     0, 1, 0;
  } else if (up == UpAxis::kX) {
    // (x, y, z) -> (-z, y, x): file +x becomes +z, a proper rotation about y by -90 degrees.
    n.up_rotation << 0, 0, -1,
                     0, 1, 0,
                     1, 0, 0;
  }
  for (auto& v : mesh.vertices) v = n.up_rotation * v;
  Eigen::Vector3d lo, hi;
  mesh_bounds(mesh, lo, hi);
  const double shortest = (hi - lo).minCoeff();
  if (!(shortest > 0.0)) {
    throw std::invalid_argument("normalise_mesh: bounding box has a zero-length edge");
  }
  n.scale = shortest_edge_m / shortest;
  n.centre_m = n.scale * 0.5 * (lo + hi);
  for (auto& v : mesh.vertices) v = n.scale * v - n.centre_m;
  mesh_bounds(mesh, lo, hi);
  n.extent_m = hi - lo;
  n.num_vertices = mesh.vertices.size();
  n.num_triangles = mesh.triangles.size();
  return n;
}

TriangleMesh make_icosphere(double radius_m, int subdivisions) {
  if (!(radius_m > 0.0) || subdivisions < 0 || subdivisions > 10) {
    throw std::invalid_argument("make_icosphere: radius must be > 0 and subdivisions in [0, 10]");
  }
  TriangleMesh m;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const double pts[12][3] = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0},
                             {0, -1, t}, {0, 1, t},  {0, -1, -t}, {0, 1, -t},
                             {t, 0, -1}, {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (const auto& p : pts) m.vertices.push_back(Eigen::Vector3d(p[0], p[1], p[2]).normalized());
  const int faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (const auto& f : faces) m.triangles.emplace_back(f[0], f[1], f[2]);
  for (int s = 0; s < subdivisions; ++s) {
    std::unordered_map<uint64_t, int> mid;
    mid.reserve(m.triangles.size() * 2);
    auto midpoint = [&](int a, int b) {
      const uint64_t key = (static_cast<uint64_t>(std::min(a, b)) << 32) |
                           static_cast<uint32_t>(std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const int id = static_cast<int>(m.vertices.size());
      m.vertices.push_back((m.vertices[static_cast<size_t>(a)] + m.vertices[static_cast<size_t>(b)])
                               .normalized());
      mid.emplace(key, id);
      return id;
    };
    std::vector<Eigen::Vector3i> next;
    next.reserve(m.triangles.size() * 4);
    for (const auto& tri : m.triangles) {
      const int a = midpoint(tri[0], tri[1]);
      const int b = midpoint(tri[1], tri[2]);
      const int c = midpoint(tri[2], tri[0]);
      next.emplace_back(tri[0], a, c);
      next.emplace_back(tri[1], b, a);
      next.emplace_back(tri[2], c, b);
      next.emplace_back(a, b, c);
    }
    m.triangles.swap(next);
  }
  for (auto& v : m.vertices) v *= radius_m;
  return m;
}

TriangleMesh make_box(const Eigen::Vector3d& size_m) {
  if (!(size_m.minCoeff() > 0.0) || !size_m.allFinite()) {
    throw std::invalid_argument("make_box: sizes must be positive and finite");
  }
  TriangleMesh m;
  const Eigen::Vector3d h = 0.5 * size_m;
  // Vertex i has x = bit0, y = bit1, z = bit2 (0 -> -h, 1 -> +h).
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(),
                            (i & 4) ? h.z() : -h.z());
  }
  const int quads[6][4] = {
      {0, 2, 3, 1},  // -z
      {4, 5, 7, 6},  // +z
      {0, 1, 5, 4},  // -y
      {2, 6, 7, 3},  // +y
      {0, 4, 6, 2},  // -x
      {1, 3, 7, 5},  // +x
  };
  for (const auto& q : quads) {
    m.triangles.emplace_back(q[0], q[1], q[2]);
    m.triangles.emplace_back(q[0], q[2], q[3]);
  }
  return m;
}

double mesh_area(const TriangleMesh& mesh) {
  double area = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<size_t>(t[2])];
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

std::vector<Eigen::Vector3d> sample_surface(const TriangleMesh& mesh, std::size_t n,
                                            std::uint64_t seed,
                                            std::vector<Eigen::Vector3d>* face_normals) {
  std::vector<Eigen::Vector3d> out;
  if (face_normals) face_normals->clear();
  if (n == 0) return out;
  std::vector<double> cum(mesh.triangles.size());
  double total = 0.0;
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    const Eigen::Vector3d& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<size_t>(t[2])];
    total += 0.5 * (b - a).cross(c - a).norm();
    cum[i] = total;
  }
  if (!(total > 0.0)) throw std::invalid_argument("sample_surface: mesh has zero area");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  out.reserve(n);
  if (face_normals) face_normals->reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const double u = uni(rng) * total;
    size_t k = static_cast<size_t>(std::upper_bound(cum.begin(), cum.end(), u) - cum.begin());
    if (k >= cum.size()) k = cum.size() - 1;
    // Skip zero-area triangles that upper_bound cannot land on anyway (cum equal to previous).
    const auto& t = mesh.triangles[k];
    const Eigen::Vector3d& a = mesh.vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices[static_cast<size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices[static_cast<size_t>(t[2])];
    const double s = std::sqrt(uni(rng));
    const double r2 = uni(rng);
    out.push_back((1.0 - s) * a + s * (1.0 - r2) * b + s * r2 * c);
    if (face_normals) {
      const Eigen::Vector3d nrm = (b - a).cross(c - a);
      const double len = nrm.norm();
      face_normals->push_back(len > 0.0 ? Eigen::Vector3d(nrm / len) : Eigen::Vector3d::Zero());
    }
  }
  return out;
}

std::vector<double> distances_to_surface(const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3d>& points) {
  if (points.empty()) return {};
  // The hints pay off beyond a few dozen queries.
  const MeshTree tree(mesh, points.size() >= 64 ? DistanceHints::kSurface : DistanceHints::kNone,
                      "distances_to_surface");
  return tree.distances_m(points);
}

}  // namespace pbnbv
