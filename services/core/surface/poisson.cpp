// Poisson reconstruction (PCL) of the frames' points with normals turned to their camera, and
// the method switch.
#include <pcl/point_types.h>
#include <pcl/surface/poisson.h>

#include <stdexcept>

#include "core/perception/neighbours.hpp"
#include "core/surface/surface.hpp"

namespace pbnbv {

TriangleMesh poisson_surface(const std::vector<SurfaceFrame>& frames, const SurfaceSettings& s, SurfaceStats* stats) {
  s.validate();
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  for (const auto& f : frames) {
    if (f.points.empty()) continue;
    const SurfaceNormals normals = estimate_normals(f.points, s.normal_neighbours);
    const Eigen::Vector3f eye = f.object_T_camera.translation().cast<float>();
    for (std::size_t i = 0; i < f.points.size(); ++i) {
      if (!normals.valid[i] || !f.points[i].allFinite()) continue;
      Eigen::Vector3f n = normals.normals[i];
      if ((eye - f.points[i]).dot(n) < 0) n = -n;
      pcl::PointNormal p;
      p.getVector3fMap() = f.points[i];
      p.getNormalVector3fMap() = n;
      cloud->push_back(p);
    }
  }
  if (cloud->empty()) throw std::invalid_argument("Poisson reconstruction: the frames hold no points with a normal");
  pcl::Poisson<pcl::PointNormal> poisson;
  poisson.setDepth(s.poisson_depth);
  poisson.setInputCloud(cloud);
  pcl::PointCloud<pcl::PointNormal> out;
  std::vector<pcl::Vertices> polygons;
  poisson.reconstruct(out, polygons);
  TriangleMesh mesh;
  mesh.vertices.reserve(out.size());
  for (const auto& p : out) mesh.vertices.push_back(p.getVector3fMap().cast<double>());
  for (const auto& poly : polygons) {
    for (std::size_t k = 1; k + 1 < poly.vertices.size(); ++k) {
      mesh.triangles.emplace_back(int(poly.vertices[0]), int(poly.vertices[k]), int(poly.vertices[k + 1]));
    }
  }
  if (stats) {
    stats->frames = frames.size();
    stats->points = cloud->size();
  }
  return mesh;
}

TriangleMesh build_surface(const std::vector<SurfaceFrame>& frames, const SurfaceSettings& s, SurfaceStats* stats) {
  return s.method == MeshMethod::kPoisson ? poisson_surface(frames, s, stats) : fuse_tsdf(frames, s, stats);
}

}  // namespace pbnbv
