#pragma once
// When a scan is done without knowing the object: what each view added to the surface seen so
// far (new_surface: the share of the view's points farther than the coverage scale, 5 mm, from
// every point of the model before it), and the rule that stops the scan when the last few views
// each added less than a threshold (surface_stop). Plain data and functions, no bus: the
// coordinator applies the rule after each view, the benchmark computes from a fixed-budget scan's
// recorded figures where the rule would have stopped it.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/point_cloud.hpp"
#include "core/scan/scan_options.hpp"

namespace pbnbv {

// What one view's cloud added to the model (the accumulated cloud of the views before it).
struct NewSurface {
  int frame_points = 0;  // the view's points (finite)
  int new_points = 0;    // of them, farther than radius_m from every model point
  int model_points = 0;  // the model before the view
  double radius_m = 0;

  // new_points as a percent of the model before the view (100 for the first view): roughly the
  // surface the view added relative to the surface seen so far, the figure the rule reads.
  double percent_of_model() const;
  // new_points as a percent of the view's own points (0 for an empty view).
  double percent_of_frame() const;
};

// Counts the points of `frame` farther than radius_m from every point of `model` (a k-d tree
// over the model). Throws std::invalid_argument when radius_m is not positive.
NewSurface new_surface(const PointCloud& frame, const PointCloud& model, double radius_m = kStopRadius.value);

nlohmann::json to_json(const NewSurface& n);

// The surface rule's parameters (the scan settings stop-window, stop-new-surface, stop-min-views).
struct SurfaceStopRule {
  int window = kStopWindow.value;                     // k: this many views in a row ...
  double max_new_percent = kStopNewSurface.value;     // x: ... each added less than this (% of the model)
  int min_views = kStopMinViews.value;                // m: never before this many views
};

// Why the rule stops, with the figures it used.
struct SurfaceStopDecision {
  int after_views = 0;               // views counted (entries of the curve) when it stops
  std::vector<double> last_percent;  // the window's figures, oldest first
  std::string reason;                // "views 4-5 each added less than 0.5 % new surface (0.31, 0.12 %)"
};

// Applies the rule to a scan's per-view figures so far (percent_of_model per view that produced
// a cloud, in order; NaN for a view that was not merged into the model: it neither counts towards
// the window nor breaks it). Stops when at least rule.min_views views were taken and the last
// rule.window figures are each below rule.max_new_percent. Throws std::invalid_argument naming
// the parameter that is outside its range.
std::optional<SurfaceStopDecision> surface_stop(const std::vector<double>& new_percent_by_view, const SurfaceStopRule& rule);

// The first view after which the rule stops a scan whose figures are `new_percent_by_view`
// (views 1..n): surface_stop on the figures of views 1..i for i = 1..n; none if it never stops.
std::optional<SurfaceStopDecision> first_surface_stop(const std::vector<double>& new_percent_by_view,
                                                      const SurfaceStopRule& rule);

// The rule's figures from scan.json's "views": one per view with a frame (captured and mapped),
// new_surface.percent_of_model, NaN when the view was not merged or has no figure.
std::vector<double> new_surface_figures(const nlohmann::json& views);

nlohmann::json to_json(const SurfaceStopRule& r);

}  // namespace pbnbv
