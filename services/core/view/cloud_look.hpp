#pragma once
// How pbnbv view's page shades a scan's drawn cloud: a normal per drawn point (the cloud's own, or
// fitted) and its colour when the cloud has colours. Plain functions, no bus, no server.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/geometry/colour_image.hpp"
#include "core/geometry/point_cloud.hpp"
#include "core/perception/neighbours.hpp"

namespace pbnbv {

// How the page shades the drawn cloud (Scene::cloud): a unit normal per drawn point (zero: none
// found) and, when the cloud has colours, a colour per drawn point; either may be empty (none).
struct CloudLook {
  std::vector<Eigen::Vector3f> normals;
  std::vector<Rgb> colours;
};

// Normals fitted to each point's 12 nearest drawn points, facing away from the object frame's
// origin (the object's centre): where no better normals are at hand. Zero where none was fitted.
std::vector<Eigen::Vector3f> fitted_normals(const PointCloud& points);

// The normals and colours of `drawn` taken from a cloud that carries them (`from`, with `normals`
// and `colours` each one per point of `from` or empty): each drawn point gets those of the point of
// `from` nearest to it within max_m (none: a zero normal and mid grey).
CloudLook look_from(const PointCloud& drawn, const PointCloud& from, const NeighbourIndex& index,
                    const std::vector<Eigen::Vector3f>& normals, const std::vector<Rgb>& colours, float max_m);

}  // namespace pbnbv
