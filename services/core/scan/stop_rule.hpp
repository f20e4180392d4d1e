#pragma once
// When a scan is done without knowing the object: the rule that stops the scan when the last few
// views each added less than a threshold of new surface (surface_stop; the figure per view,
// NewSurface, is the registration service's: core/perception/new_surface.hpp). Plain data and functions, no bus: the
// coordinator applies the rule after each view, the benchmark computes from a fixed-budget scan's
// recorded figures where the rule would have stopped it.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/point_cloud.hpp"
#include "core/perception/new_surface.hpp"
#include "core/scan/scan_options.hpp"

namespace pbnbv {

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

nlohmann::json to_json(const SurfaceStopRule& r);

}  // namespace pbnbv
