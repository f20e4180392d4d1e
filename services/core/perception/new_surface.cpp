#include "core/perception/new_surface.hpp"

#include <stdexcept>
#include <string>

#include "core/perception/neighbours.hpp"

namespace pbnbv {

namespace {

void check_radius(double radius_m) {
  if (!(radius_m > 0)) throw std::invalid_argument("new surface: the radius must be positive, not " + std::to_string(radius_m));
}

// `index`: over the model (none: an empty model).
NewSurface count_new(const PointCloud& frame, const NeighbourIndex* index, double radius_m) {
  NewSurface n;
  n.radius_m = radius_m;
  n.model_points = index ? static_cast<int>(index->size()) : 0;
  const float r2 = static_cast<float>(radius_m * radius_m);
  for (const Eigen::Vector3f& p : frame) {
    if (!p.allFinite()) continue;
    ++n.frame_points;
    float d2 = 0;
    if (n.model_points == 0 || index->nearest(p, r2, d2) < 0) ++n.new_points;
  }
  return n;
}

}  // namespace

NewSurface new_surface(const PointCloud& frame, const NeighbourIndex& model, double radius_m) {
  check_radius(radius_m);
  return count_new(frame, &model, radius_m);
}

NewSurface new_surface(const PointCloud& frame, const PointCloud& model, double radius_m) {
  check_radius(radius_m);
  if (model.empty()) return count_new(frame, nullptr, radius_m);
  const NeighbourIndex index(model);
  return count_new(frame, &index, radius_m);
}

}  // namespace pbnbv
