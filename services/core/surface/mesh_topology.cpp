#include "core/surface/mesh_topology.hpp"
#include "core/base/version.hpp"
#include "core/base/atomic_file.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

namespace pbnbv {

namespace {
std::uint64_t edge_key(int a, int b) { return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b); }
}  // namespace

namespace {

// Each undirected edge: how many triangles use it, and the direction of its last use.
std::unordered_map<std::uint64_t, std::pair<int, bool>> edge_uses(const TriangleMesh& mesh) {
  std::unordered_map<std::uint64_t, std::pair<int, bool>> uses;  // (min, max) -> (count, min -> max)
  uses.reserve(mesh.triangles.size() * 2);
  for (const auto& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int u = tri[k], w = tri[(k + 1) % 3];
      auto& e = uses[edge_key(std::min(u, w), std::max(u, w))];
      ++e.first;
      e.second = u < w;
    }
  }
  return uses;
}

// The boundary loops as vertex chains, each vertex followed by the next along its triangle's
// direction (the last joins the first).
std::vector<std::vector<int>> loops_of(const std::unordered_map<std::uint64_t, std::pair<int, bool>>& uses) {
  std::unordered_multimap<int, int> next;
  std::map<std::pair<int, int>, bool> used;
  for (const auto& [key, e] : uses) {
    if (e.first != 1) continue;
    const int lo = int(key >> 32), hi = int(key & 0xffffffffu);
    const int from = e.second ? lo : hi, to = e.second ? hi : lo;
    next.emplace(from, to);
    used[{from, to}] = false;
  }
  std::vector<std::vector<int>> loops;
  for (auto& [edge, done] : used) {
    if (done) continue;
    std::vector<int> loop;
    std::pair<int, int> cur = edge;
    while (true) {
      used[cur] = true;
      loop.push_back(cur.first);
      bool moved = false;
      const auto range = next.equal_range(cur.second);
      for (auto it = range.first; it != range.second; ++it) {
        if (!used[{it->first, it->second}]) {
          cur = {it->first, it->second};
          moved = true;
          break;
        }
      }
      if (!moved) break;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

double loop_length(const TriangleMesh& mesh, const std::vector<int>& loop) {
  double l = 0;
  for (std::size_t i = 0; i < loop.size(); ++i) l += (mesh.vertices[loop[(i + 1) % loop.size()]] - mesh.vertices[loop[i]]).norm();
  return l;
}

}  // namespace

MeshTopology mesh_topology(const TriangleMesh& mesh) {
  MeshTopology t;
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3d &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    t.area_m2 += 0.5 * (b - a).cross(c - a).norm();
    t.volume_m3 += a.dot(b.cross(c)) / 6.0;
  }
  const auto uses = edge_uses(mesh);
  t.edges = uses.size();
  for (const auto& [key, e] : uses) {
    if (e.first >= 3) ++t.non_manifold_edges;
    if (e.first != 1) continue;
    ++t.boundary_edges;
    t.boundary_length_m += (mesh.vertices[int(key >> 32)] - mesh.vertices[int(key & 0xffffffffu)]).norm();
  }
  t.boundary_loops = loops_of(uses).size();
  t.watertight = !mesh.triangles.empty() && t.boundary_edges == 0 && t.non_manifold_edges == 0;
  return t;
}

std::size_t fill_small_holes(TriangleMesh& mesh, double max_boundary_m) {
  std::size_t filled = 0;
  for (const auto& loop : loops_of(edge_uses(mesh))) {
    if (loop.size() < 3 || loop_length(mesh, loop) > max_boundary_m) continue;
    // A fan from the loop's centroid, each triangle running its boundary edge the other way.
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : loop) c += mesh.vertices[v];
    const int ci = int(mesh.vertices.size());
    mesh.vertices.push_back(c / double(loop.size()));
    for (std::size_t i = 0; i < loop.size(); ++i) mesh.triangles.emplace_back(loop[(i + 1) % loop.size()], loop[i], ci);
    ++filled;
  }
  return filled;
}

std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> n(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3d &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    const Eigen::Vector3d f = (b - a).cross(c - a);  // length = twice the area
    for (int k = 0; k < 3; ++k) n[tri[k]] += f;
  }
  for (auto& x : n) {
    const double l = x.norm();
    x = l > 0 ? Eigen::Vector3d(x / l) : Eigen::Vector3d::Zero();
  }
  return n;
}

std::size_t remove_small_components(TriangleMesh& mesh, std::size_t min_triangles) {
  // Union-find over vertices joined by triangles.
  std::vector<int> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& tri : mesh.triangles) {
    parent[find(tri[1])] = find(tri[0]);
    parent[find(tri[2])] = find(tri[0]);
  }
  std::vector<std::size_t> count(mesh.vertices.size(), 0);
  for (const auto& tri : mesh.triangles) ++count[find(tri[0])];
  TriangleMesh kept;
  std::vector<int> new_index(mesh.vertices.size(), -1);
  for (const auto& tri : mesh.triangles) {
    if (count[find(tri[0])] < min_triangles) continue;
    Eigen::Vector3i t;
    for (int k = 0; k < 3; ++k) {
      int& ni = new_index[tri[k]];
      if (ni < 0) {
        ni = int(kept.vertices.size());
        kept.vertices.push_back(mesh.vertices[tri[k]]);
      }
      t[k] = ni;
    }
    kept.triangles.push_back(t);
  }
  const std::size_t removed = mesh.triangles.size() - kept.triangles.size();
  mesh = std::move(kept);
  return removed;
}

void write_mesh_ply(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& normals, const std::string& path,
                    const std::vector<Rgb>& colours) {
  if (normals.size() != mesh.vertices.size()) {
    throw std::invalid_argument(path + ": " + std::to_string(normals.size()) + " normals for " +
                                std::to_string(mesh.vertices.size()) + " vertices");
  }
  if (!colours.empty() && colours.size() != mesh.vertices.size()) {
    throw std::invalid_argument(path + ": " + std::to_string(colours.size()) + " colours for " +
                                std::to_string(mesh.vertices.size()) + " vertices");
  }
  std::ostringstream out;
  {
    out << "ply\nformat binary_little_endian 1.0\ncomment written by pbnbv " << pbnbv_version() << "\n"
        << "comment units metres, object frame (scan.json); triangles counter-clockwise seen from outside\n"
        << "element vertex " << mesh.vertices.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n"
        << "property float nx\nproperty float ny\nproperty float nz\n"
        << (colours.empty() ? "" : "property uchar red\nproperty uchar green\nproperty uchar blue\n")
        << "element face " << mesh.triangles.size() << "\n"
        << "property list uchar int vertex_indices\nend_header\n";
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const float f[6] = {float(mesh.vertices[i].x()), float(mesh.vertices[i].y()), float(mesh.vertices[i].z()),
                          float(normals[i].x()),       float(normals[i].y()),       float(normals[i].z())};
      out.write(reinterpret_cast<const char*>(f), sizeof f);
      if (!colours.empty()) out.write(reinterpret_cast<const char*>(colours[i].data()), 3);
    }
    for (const auto& tri : mesh.triangles) {
      const unsigned char n = 3;
      const std::int32_t idx[3] = {tri[0], tri[1], tri[2]};
      out.write(reinterpret_cast<const char*>(&n), 1);
      out.write(reinterpret_cast<const char*>(idx), sizeof idx);
    }
  }
  write_file_atomic(path, out.str());
}

}  // namespace pbnbv
