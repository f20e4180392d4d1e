#pragma once
// When a scan is done without knowing the object: the rule that stops the scan when the last few
// views each added less than a threshold of new surface (surface_stop; the figure per view,
// NewSurface, is the registration service's: core/perception/new_surface.hpp). Plain data and functions, no bus: the
// coordinator applies the rule after each view, the benchmark computes from a fixed-budget scan's
// recorded figures where the rule would have stopped it.
#include <limits>
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

// The rule in seconds (the scan settings stop-rate-views, stop-gain-per-second, stop-min-views).
// On a rig a view costs the rig's time, and what the next view will add is best judged by what
// the last ones added: the scan stops when the last `window` views added, together, less than
// min_percent_per_s percent of the model per second of the rig time they took (their motion,
// settling and capture: what a view costs the rig before its computation, known once its cloud
// is in).
struct SecondsStopRule {
  int window = kStopRateViews.value;
  double min_percent_per_s = kStopGainPerSecond.value;
  int min_views = kStopMinViews.value;
};

// One view's figures for the rule: the new surface it added (% of the model; NaN: not merged into
// it, counted as adding nothing) and the rig seconds it took (NaN: not known).
struct ViewGain {
  double new_percent = std::numeric_limits<double>::quiet_NaN();
  double rig_s = std::numeric_limits<double>::quiet_NaN();
};

// Applies the rule to the figures of a scan's views so far (one per view that produced a cloud, in
// order). Stops when at least rule.min_views views were taken, the last rule.window ones have a
// rig time, and their new surface per second of it is under rule.min_percent_per_s. Throws
// std::invalid_argument naming the parameter outside its range.
std::optional<SurfaceStopDecision> seconds_stop(const std::vector<ViewGain>& views, const SecondsStopRule& rule);

// The first view after which the rule stops a scan whose figures are `views` (seconds_stop on
// views 1..i for i = 1..n); none if it never stops.
std::optional<SurfaceStopDecision> first_seconds_stop(const std::vector<ViewGain>& views, const SecondsStopRule& rule);

// The views' new surface alone (the surface rule's figures).
std::vector<double> new_percents(const std::vector<ViewGain>& views);

nlohmann::json to_json(const SecondsStopRule& r);

}  // namespace pbnbv
