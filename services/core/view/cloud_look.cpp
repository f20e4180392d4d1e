// How pbnbv view's page shades the drawn cloud. See cloud_look.hpp.
#include "core/view/cloud_look.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>


namespace pbnbv {

std::vector<Eigen::Vector3f> fitted_normals(const PointCloud& points) {
  if (points.size() < 3) return std::vector<Eigen::Vector3f>(points.size(), Eigen::Vector3f::Zero());
  SurfaceNormals s = estimate_normals(points, 12);
  for (std::size_t i = 0; i < points.size(); ++i) s.normals[i] = s.valid[i] ? Eigen::Vector3f(-s.normals[i]) : Eigen::Vector3f::Zero();
  return s.normals;
}

CloudLook look_from(const PointCloud& drawn, const PointCloud& from, const NeighbourIndex& index,
                    const std::vector<Eigen::Vector3f>& normals, const std::vector<Rgb>& colours, float max_m) {
  CloudLook look;
  const bool with_normals = !normals.empty() && normals.size() == from.size();
  const bool with_colours = !colours.empty() && colours.size() == from.size();
  if (with_normals) look.normals.assign(drawn.size(), Eigen::Vector3f::Zero());
  if (with_colours) look.colours.assign(drawn.size(), Rgb{128, 128, 128});
  if (!with_normals && !with_colours) return look;
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    float d2 = 0;
    const int k = index.nearest(drawn[i], max_m * max_m, d2);
    if (k < 0) continue;
    if (with_normals) look.normals[i] = normals[static_cast<std::size_t>(k)];
    if (with_colours) look.colours[i] = colours[static_cast<std::size_t>(k)];
  }
  return look;
}

}  // namespace pbnbv
