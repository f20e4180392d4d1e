#pragma once
// What a view's cloud added to the model (the accumulated cloud of the views before it): the
// share of the view's points farther than a radius (the coverage scale, 5 mm) from every model
// point. The registration service computes it as it merges a view; the surface stop rule
// (core/scan/stop_rule.hpp) reads the figure.
#include "core/geometry/point_cloud.hpp"

namespace pbnbv {

struct NewSurface {
  int frame_points = 0;  // the view's points (finite)
  int new_points = 0;    // of them, farther than radius_m from every model point
  int model_points = 0;  // the model before the view
  double radius_m = 0;

  // new_points as a percent of the model before the view (100 for the first view): roughly the
  // surface the view added relative to the surface seen so far, the figure the rule reads.
  double percent_of_model() const {
    if (model_points == 0) return new_points > 0 ? 100.0 : 0.0;
    return 100.0 * new_points / model_points;
  }
  // new_points as a percent of the view's own points (0 for an empty view).
  double percent_of_frame() const { return frame_points == 0 ? 0.0 : 100.0 * new_points / frame_points; }
};

// Counts the points of `frame` farther than radius_m from every point of `model` (a k-d tree
// over the model). Throws std::invalid_argument when radius_m is not positive.
NewSurface new_surface(const PointCloud& frame, const PointCloud& model, double radius_m);

class NeighbourIndex;
// The same against a k-d tree over the model built beforehand (core/perception/neighbours.hpp),
// as the registration service builds it while the rig moves.
NewSurface new_surface(const PointCloud& frame, const NeighbourIndex& model, double radius_m);

}  // namespace pbnbv
