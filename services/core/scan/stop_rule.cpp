#include "core/scan/stop_rule.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/base/format.hpp"

namespace pbnbv {

nlohmann::json to_json(const NewSurface& n) {
  return {{"percent_of_model", n.percent_of_model()}, {"percent_of_frame", n.percent_of_frame()},
          {"new_points", n.new_points}, {"frame_points", n.frame_points}, {"model_points", n.model_points},
          {"radius_m", n.radius_m}};
}

namespace {

void check(const SurfaceStopRule& r) {
  kStopWindow.checked(r.window);
  kStopNewSurface.checked(r.max_new_percent);
  kStopMinViews.checked(r.min_views);
}

void check(const SecondsStopRule& r) {
  kStopRateViews.checked(r.window);
  kStopGainPerSecond.checked(r.min_percent_per_s);
  kStopMinViews.checked(r.min_views);
}

// The first prefix (views 1..n, n = 1..size) on which `stop` stops; none if none does.
template <class Figure, class Rule, class Stop>
std::optional<SurfaceStopDecision> first_stop(const std::vector<Figure>& figures, const Rule& rule, Stop stop) {
  check(rule);
  for (std::size_t n = 1; n <= figures.size(); ++n) {
    if (auto d = stop(std::vector<Figure>(figures.begin(), figures.begin() + n), rule)) return d;
  }
  return std::nullopt;
}

}  // namespace

std::optional<SurfaceStopDecision> surface_stop(const std::vector<double>& figures, const SurfaceStopRule& rule) {
  check(rule);
  const int views = static_cast<int>(figures.size());
  if (views < rule.min_views) return std::nullopt;
  std::vector<int> window;  // the last rule.window views with a figure, newest first
  for (int i = views - 1; i >= 0 && static_cast<int>(window.size()) < rule.window; --i) {
    if (std::isfinite(figures[i])) window.push_back(i);
  }
  if (static_cast<int>(window.size()) < rule.window) return std::nullopt;
  for (const int i : window) {
    if (figures[i] >= rule.max_new_percent) return std::nullopt;
  }
  SurfaceStopDecision d;
  d.after_views = views;
  std::string values;
  for (auto i = window.rbegin(); i != window.rend(); ++i) {
    d.last_percent.push_back(figures[*i]);
    values += (values.empty() ? "" : ", ") + fixed(figures[*i], 2);
  }
  const std::string which = rule.window == 1 ? "view " + std::to_string(window.front() + 1)
                                             : "views " + std::to_string(window.back() + 1) + "-" + std::to_string(window.front() + 1);
  d.reason = which + (rule.window == 1 ? " added" : " each added") + " less than " + fixed(rule.max_new_percent, 2) +
             " % new surface (" + values + " % of the model)";
  return d;
}

std::optional<SurfaceStopDecision> first_surface_stop(const std::vector<double>& figures, const SurfaceStopRule& rule) {
  return first_stop(figures, rule, surface_stop);
}

std::optional<SurfaceStopDecision> seconds_stop(const std::vector<ViewGain>& views, const SecondsStopRule& rule) {
  check(rule);
  const int n = static_cast<int>(views.size());
  if (n < rule.min_views || n < rule.window) return std::nullopt;
  double gain = 0, seconds = 0;
  SurfaceStopDecision d;
  d.after_views = n;
  for (int i = n - rule.window; i < n; ++i) {
    if (!std::isfinite(views[i].rig_s) || views[i].rig_s < 0) return std::nullopt;  // not known: no judgement
    const double added = std::isfinite(views[i].new_percent) ? views[i].new_percent : 0.0;
    gain += added;
    seconds += views[i].rig_s;
    d.last_percent.push_back(added);
  }
  if (!(seconds > 0)) return std::nullopt;
  const double rate = gain / seconds;
  if (rate >= rule.min_percent_per_s) return std::nullopt;
  const std::string which =
      rule.window == 1 ? "view " + std::to_string(n) : "views " + std::to_string(n - rule.window + 1) + "-" + std::to_string(n);
  d.reason = which + " added " + fixed(gain, 2) + " % new surface in " + fixed(seconds, 1) + " s of rig time (" +
             fixed(rate, 3) + " %/s, under " + fixed(rule.min_percent_per_s, 3) + " %/s)";
  return d;
}

std::optional<SurfaceStopDecision> first_seconds_stop(const std::vector<ViewGain>& views, const SecondsStopRule& rule) {
  return first_stop(views, rule, seconds_stop);
}

std::vector<double> new_percents(const std::vector<ViewGain>& views) {
  std::vector<double> out;
  out.reserve(views.size());
  for (const ViewGain& g : views) out.push_back(g.new_percent);
  return out;
}

nlohmann::json to_json(const SecondsStopRule& r) {
  return {{"window", r.window}, {"min_percent_per_s", r.min_percent_per_s}, {"min_views", r.min_views}};
}

nlohmann::json to_json(const SurfaceStopRule& r) {
  return {{"window", r.window}, {"max_new_percent", r.max_new_percent}, {"min_views", r.min_views}};
}

}  // namespace pbnbv
