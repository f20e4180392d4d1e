// The benchmark's report (report.md and PNG plots) and the ablations' (bench.hpp).
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "report/line_chart.hpp"
#include "core/io/json.hpp"
#include "core/scan/scan_settings.hpp"
#include "eval/bench.hpp"
#include "eval/bench_sweep.hpp"
#include "eval/objects.hpp"
#include "core/base/format.hpp"

#include <fmt/format.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {
namespace {

// The authors' release, run closed-loop on this machine kind (2 cores), optimised build, on five
// real meshes of its own, free rig / full sphere, 0.03 m, 800 candidates. Which five is recorded
// nowhere in the project (that run kept only its figures), so no set of ours is the one it was
// measured on: it is never drawn on a plot, nor put in a table row beside planners run on other
// objects; report.md says its figures in a sentence of their own (paper setup only).
constexpr const char* kReleaseNote =
    "For context only: the authors' public release, run closed-loop on a 2-core machine on 5 meshes of its own (which "
    "5 was not recorded, so it is compared with no objects here), reached 31.3, 61.0, 80.2, 95.3 and 98.1 % after "
    "views 1-5 and 99.1 % after view 10, in a median 25.8 s per planning iteration.";

std::string f1(double x) { return std::isfinite(x) ? fixed(x, 1) : "-"; }

std::string ms(double x) { return fixed(x, x < 10 ? 2 : x < 100 ? 1 : 0); }

std::string opt(const std::optional<double>& v, int digits = 2) { return v ? fixed(*v, digits) : "never"; }

std::vector<double> view_numbers(int n, int first = 1) {
  std::vector<double> x;
  for (int i = first; i <= n; ++i) x.push_back(i);
  return x;
}

// A chart of mean coverage against views (0-100 %, a line at 95 %), its series to come.
LineChart coverage_by_view_chart(const std::string& title) {
  LineChart c;
  c.title = title;
  c.x_label = "views";
  c.y_label = "surface covered (%, mean)";
  c.integer_x = true;
  c.y_max = 100;
  c.y_lines = {{95.0, "95 %"}};
  return c;
}

// The command that reproduces the benchmark; `lists`: the values of swept options, as given
// (option without "--" -> "a,b"), instead of the spec's one.
std::string command_of(const BenchSpec& s, const std::map<std::string, std::string>& lists = {}) {
  const auto value = [&](const std::string& option, const std::string& one) {
    const auto it = lists.find(option);
    return it != lists.end() ? it->second : one;
  };
  std::ostringstream os;
  os << "build/bin/pbnbv bench --objects ";
  for (std::size_t i = 0; i < s.objects.size(); ++i) os << (i ? "," : "") << s.objects[i];
  os << " --planners ";
  for (std::size_t i = 0; i < s.planners.size(); ++i) os << (i ? "," : "") << name_of(s.planners[i]);
  os << " --rig " << value("rig", std::string(name_of(s.rig))) << " --area " << name_of(s.area) << " --views " << s.views
     << " --resolution " << value("resolution", fmt::format("{}", s.resolution_m)) << " --candidates " << s.candidates
     << " --tmax " << s.tmax << " --beta " << s.beta;
  if (s.initial_view) os << " --initial-view " << s.initial_view->x() << "," << s.initial_view->y() << "," << s.initial_view->z();
  if (s.first_views != kFirstViews.value || lists.count("first-views")) {
    os << " --first-views " << value("first-views", std::to_string(s.first_views));
  }
  if (s.size_m != kObjectSize.value) os << " --size " << s.size_m;
  if (s.up) os << " --up " << name_of(*s.up);
  if (!s.rig_model.empty() || lists.count("rig-model")) os << " --rig-model " << value("rig-model", s.rig_model);
  if (s.camera != kCamera.value || lists.count("camera")) os << " --camera " << value("camera", std::string(name_of(s.camera)));
  if (s.sim_speed != kSimSpeed.value) os << " --sim-speed " << s.sim_speed;
  if (s.rig_errors != kRigErrors.value || lists.count("rig-errors")) {
    os << " --rig-errors " << value("rig-errors", std::string(name_of(s.rig_errors)));
  }
  if (s.when_done != kWhenDone.value) os << " --when-done " << name_of(s.when_done);
  if (s.motion != kMotion.value) os << " --motion " << name_of(s.motion);
  if (s.map_pose != kMapPose.value) os << " --map-pose " << name_of(s.map_pose);
  if (s.seconds_per_point != kSecondsPerPoint.value) os << " --seconds-per-point " << s.seconds_per_point;
  if (s.stop_rule.window != kStopWindow.value) os << " --stop-window " << s.stop_rule.window;
  if (s.stop_rule.max_new_percent != kStopNewSurface.value) os << " --stop-new-surface " << s.stop_rule.max_new_percent;
  if (s.stop_rule.min_views != kStopMinViews.value) os << " --stop-min-views " << s.stop_rule.min_views;
  if (s.seconds_rule.window != kStopRateViews.value) os << " --stop-rate-views " << s.seconds_rule.window;
  if (s.seconds_rule.min_percent_per_s != kStopGainPerSecond.value) {
    os << " --stop-gain-per-second " << s.seconds_rule.min_percent_per_s;
  }
  if (s.metrics.threshold_m != kMetricThreshold.value) os << " --threshold " << s.metrics.threshold_m;
  if (s.slurm) {
    os << " --slurm";
    if (!s.slurm->partition.empty()) os << " --partition " << s.slurm->partition;
    if (!s.slurm->account.empty()) os << " --account " << s.slurm->account;
    if (!s.slurm->time_limit.empty()) os << " --time-limit " << s.slurm->time_limit;
  } else {
    os << " --jobs " << s.jobs;
  }
  if (!s.netns) os << " --no-netns";
  os << " --out " << s.out.string();
  return os.str();
}

bool paper_setup(const BenchSpec& s) { return s.rig == RigKind::kFree && s.area == CandidateArea::kFullSphere; }


// What a mean is over: the objects, or the runs (objects x first views).
std::string means_over(const BenchSpec& s) { return s.first_views > 1 ? "runs" : "objects"; }

// The views listed in a table: `wanted` within the budget, and the budget's last view.
std::vector<int> listed_views(std::vector<int> wanted, int n) {
  std::vector<int> v;
  for (const int w : wanted) {
    if (w <= n) v.push_back(w);
  }
  if (v.empty() || v.back() < n) v.push_back(n);
  return v;
}

std::string interval_text(const Interval& i, int digits) { return "[" + fixed(i.lo, digits) + ", " + fixed(i.hi, digits) + "]"; }

// A planner's 95 % interval of the mean coverage after `view`, "-" when there is none.
std::string coverage_interval(const PlannerSummary& p, int view) {
  return view <= static_cast<int>(p.coverage_ci95_by_view.size()) ? interval_text(p.coverage_ci95_by_view[view - 1], 1) : "-";
}

// The table in the paper's form for `planners` (the main one and each half's): coverage after
// each view, views to 95 %, planner time, runs; with `intervals`, the 95 % interval after views
// 2, 4, 10 (those within the budget, and the last).
std::string coverage_table(const std::vector<PlannerSummary>& planners, const BenchSpec& s, bool intervals) {
  const int n = s.views;
  const std::vector<int> ci_views = listed_views({2, 4, 10}, n);
  std::ostringstream md;
  md << "| planner |";
  for (int i = 1; i <= n; ++i) md << " " << i << " |";
  md << " views to 95 % | planner time per iteration, median (mean) | " << means_over(s) << " |";
  if (intervals) {
    for (const int v : ci_views) md << " 95 % interval after " << v << " |";
  }
  md << "\n|---|";
  for (int i = 0; i < n + 3 + (intervals ? static_cast<int>(ci_views.size()) : 0); ++i) md << "---|";
  md << "\n";
  for (const auto& p : planners) {
    md << "| " << name_of(p.planner) << " |";
    for (int i = 0; i < n; ++i) md << " " << (i < static_cast<int>(p.coverage_by_view.size()) ? f1(p.coverage_by_view[i]) : "-") << " |";
    md << " " << opt(p.views_to_95) << " (" << p.reached_95 << " of " << p.complete << " reach it) | ";
    if (p.planner == PlannerKind::kRing) md << "- (fixed views) |";
    else md << ms(p.planner_ms_median) << " ms (" << ms(p.planner_ms_mean) << ") |";
    md << " " << p.complete << (p.failed ? " (" + std::to_string(p.failed) + " failed)" : "") << " |";
    if (intervals) {
      for (const int v : ci_views) md << " " << coverage_interval(p, v) << " |";
    }
    md << "\n";
  }
  return md.str();
}

// The 95 % intervals of `planners`' means, one line each: after views 2, 4, 10 and views to 95 %.
std::string interval_lines(const std::vector<PlannerSummary>& planners, int n) {
  std::ostringstream md;
  for (const auto& p : planners) {
    if (p.coverage_ci95_by_view.empty()) continue;
    md << "- " << name_of(p.planner) << " (" << p.objects_complete << (p.objects_complete == 1 ? " object" : " objects") << "):";
    const char* sep = " coverage after view ";
    for (const int v : listed_views({2, 4, 10}, n)) {
      md << sep << v << " " << coverage_interval(p, v);
      sep = ", ";
    }
    md << "; views to 95 % ";
    if (p.views_to_95_ci95) {
      md << interval_text(*p.views_to_95_ci95, 2) << " (over the " << p.objects_reaching_95 << " of " << p.objects_complete
         << " objects with a run reaching 95 %)";
    } else {
      md << "- (no object reaches 95 %)";
    }
    md << "\n";
  }
  return md.str();
}

std::string interval_rule_text(const BenchSpec& s) {
  return "95 % intervals of the mean: percentile bootstrap over the objects (" + std::to_string(kBootstrapResamples) +
         " resamples with replacement, fixed seed), each object's value its mean over its" +
         (s.first_views > 1 ? " " + std::to_string(s.first_views) + " first views" : std::string(" one first view")) +
         "; views to 95 % over the objects with a run reaching 95 % (each its mean over those runs): an object that "
         "never reaches 95 % is left out, as in the mean, and the count says how many remain.";
}

std::string area_text(const BenchSpec& s, const char* hemisphere) {
  return s.area == CandidateArea::kFullSphere ? "full sphere" : hemisphere;
}

// Median over the runs of the planner time at each planning iteration (views 2..n).
std::vector<double> median_time_by_iteration(const PlannerSummary& p, int views) {
  std::vector<double> out;
  for (int k = 0; k + 1 < views; ++k) {
    std::vector<double> t;
    for (const auto& o : p.runs) {
      if (o.complete && k < static_cast<int>(o.planner_ms.size())) t.push_back(o.planner_ms[k]);
    }
    if (t.empty()) {
      out.push_back(NAN);
      continue;
    }
    out.push_back(median_of(std::move(t)));
  }
  return out;
}

// Min and max over the complete runs of the observable coverage after each view.
std::pair<std::vector<double>, std::vector<double>> observable_spread(const PlannerSummary& p, int n) {
  std::vector<double> lo(n, INFINITY), hi(n, -INFINITY);
  bool any = false;
  for (const auto& o : p.runs) {
    if (!o.complete || o.observable_by_view.empty()) continue;
    const std::vector<double> v = pad_views(o.observable_by_view, n);
    for (int i = 0; i < n; ++i) {
      lo[i] = std::min(lo[i], v[i]);
      hi[i] = std::max(hi[i], v[i]);
    }
    any = true;
  }
  if (!any) return {};
  return {lo, hi};
}

void coverage_chart(const BenchResult& r, bool observable, const fs::path& path) {
  const BenchSpec& s = r.spec;
  LineChart c;
  c.title = std::string(observable ? "Observable coverage" : "Coverage") + " after each view - " + std::string(name_of(s.rig)) + " rig, " +
            area_text(s, "hemisphere") + ", " + objects_text(r) + ", band: min-max over " + means_over(s);
  c.x_label = "views";
  c.y_label = observable ? "observable surface covered (%, mean)" : "surface covered (%, mean)";
  c.integer_x = true;
  c.y_max = 100;
  c.y_lines = {{95.0, "95 %"}};
  for (const auto& p : r.planners) {
    const std::vector<double>& y = observable ? p.observable_by_view : p.coverage_by_view;
    if (y.empty()) continue;
    ChartSeries cs{std::string(name_of(p.planner)), view_numbers(static_cast<int>(y.size())), y};
    if (observable) {
      const auto [lo, hi] = observable_spread(p, static_cast<int>(y.size()));
      cs.lo = lo;
      cs.hi = hi;
    } else if (p.coverage_min_by_view.size() == y.size()) {
      cs.lo = p.coverage_min_by_view;
      cs.hi = p.coverage_max_by_view;
    }
    c.series.push_back(cs);
  }
  if (c.series.empty()) return;
  write_line_chart(c, path.string());
}

// Observable coverage against rig time: per planner the mean over its runs at common times
// (coverage_at_rig_times on one grid for every planner, to the longest run's rig time), with the
// runs' min-max as a band; false when no run measured its rig time.
bool rig_time_chart(const BenchResult& r, const fs::path& path) {
  const BenchSpec& s = r.spec;
  double longest = 0;
  for (const auto& p : r.planners) {
    for (const auto& o : p.runs) {
      if (o.complete && o.rig_time && !o.rig_time_by_view.empty() && std::isfinite(o.rig_time_by_view.back())) {
        longest = std::max(longest, o.rig_time_by_view.back());
      }
    }
  }
  const std::vector<double> times = rig_time_grid(longest);
  LineChart c;
  c.title = "Observable coverage against rig time - " + std::string(name_of(s.rig)) + " rig, " + area_text(s, "hemisphere") +
            ", " + objects_text(r) + ", band: min-max over " + means_over(s);
  c.x_label = "rig time (s): motion, settling, capture and the wait for computation";
  c.y_label = "observable surface covered (%, mean)";
  c.y_min = 0;
  c.y_max = 100;
  c.x_min = 0;
  c.x_max = times.back() > 0 ? times.back() : NAN;
  c.y_lines = {{90.0, "90 %"}, {95.0, "95 %"}};
  for (const auto& p : r.planners) {
    const CoverageOverTime cov = coverage_at_rig_times(p.runs, times);
    if (cov.runs == 0) continue;
    ChartSeries cs{std::string(name_of(p.planner)), times, cov.mean};
    cs.markers = false;
    cs.lo = cov.lo;
    cs.hi = cov.hi;
    c.series.push_back(cs);
  }
  if (c.series.empty()) return false;
  write_line_chart(c, path.string());
  return true;
}

// Each planner's gap to the oracle (percentage points) after each view; false when there is none.
bool gap_chart(const BenchResult& r, const fs::path& path) {
  LineChart c;
  c.title = "Gap to the oracle after each view (coverage, mean over " + objects_text(r) + ")";
  c.x_label = "views";
  c.y_label = "oracle - planner (percentage points)";
  c.integer_x = true;
  for (const auto& p : r.planners) {
    if (p.planner == PlannerKind::kOracle || p.gap_to_oracle_by_view.empty()) continue;
    c.series.push_back({std::string(name_of(p.planner)), view_numbers(static_cast<int>(p.gap_to_oracle_by_view.size())),
                        p.gap_to_oracle_by_view});
  }
  if (c.series.empty()) return false;
  write_line_chart(c, path.string());
  return true;
}

void time_chart(const BenchResult& r, const fs::path& path) {
  LineChart c;
  c.title = "Planner time per iteration (median over " + objects_text(r) + ") - map update + view selection";
  c.x_label = "planning for view";
  c.y_label = "ms (log scale)";
  c.integer_x = true;
  c.log_y = true;
  for (const auto& p : r.planners) {
    if (p.planner == PlannerKind::kRing) continue;
    const std::vector<double> t = median_time_by_iteration(p, r.spec.views);
    if (std::none_of(t.begin(), t.end(), [](double x) { return std::isfinite(x) && x > 0; })) continue;
    c.series.push_back({std::string(name_of(p.planner)), view_numbers(r.spec.views, 2), t});
  }
  if (c.series.empty()) return;
  write_line_chart(c, path.string());
}

// The summary of `planner` in r, or nullptr.
const PlannerSummary* find_planner(const BenchResult& r, PlannerKind planner) {
  for (const auto& p : r.planners) {
    if (p.planner == planner) return &p;
  }
  return nullptr;
}

// The title, the command, the setup and the coverage table with its intervals.
void header_section(const BenchResult& r, std::ostream& md) {
  const BenchSpec& s = r.spec;
  const int n = s.views;
  md << "# Benchmark: " << name_of(s.rig) << " rig, " << area_text(s, "hemisphere") << ", "
     << objects_text(r) << ", " << n << " views\n\n";
  md << "```\n" << command_of(s) << "\n```\n\n";
  md << "Candidates " << s.candidates << " on the " << area_text(s, "upper hemisphere")
     << ", voxel map resolution " << s.resolution_m << " m, T_max " << s.tmax << ", beta " << s.beta << ", object size "
     << s.size_m << " m (shortest bounding-box edge). Coverage: " << s.coverage.num_samples
     << " surface samples, a sample is covered by a captured point within " << s.coverage.radius_m * 1000 << " mm. "
     << "Machine: " << r.machine.value("cpu", std::string("?")) << ", " << r.machine.value("cores", 0) << " cores, "
     << r.machine.value("scans_at_once", 1) << " scan(s) at a time, " << r.machine.value("date", std::string("")) << ".\n\n";

  md << "## Coverage after each view (%, mean over " << (s.first_views > 1 ? "runs: objects x first views" : "objects")
     << ")\n\n";
  const std::string table = coverage_table(r.planners, s, false);
  md << table << "\n" << interval_lines(r.planners, n) << "\nMeans over each planner's completed scans";
  if (s.first_views > 1) {
    md << " (each object from " << s.first_views
       << " first views: the scan's default, and " << s.first_views - 1
       << " drawn uniformly on the " << area_text(s, "upper half of the sphere")
       << " at the default's distance, the same for every planner; the ring's views are fixed, so its runs repeat)";
  }
  md << "; coverage.png shows each planner's min-max over " << means_over(s) << " as a band. " << interval_rule_text(s);
  if (paper_setup(s)) md << " " << kReleaseNote;
  md << "\n\n";
}

// The failed scans (left out of every mean) and each planner's time against pbnbv's.
void failed_and_times_section(const BenchResult& r, std::ostream& md) {
  const PlannerSummary* pbnbv = find_planner(r, PlannerKind::kPbnbv);
  bool any_failed = false;
  for (const auto& p : r.planners) {
    for (const auto& o : p.runs) any_failed = any_failed || !o.complete;
  }
  if (any_failed) {
    md << "## Failed scans (left out of every mean)\n\n| run | planner | reason |\n|---|---|---|\n";
    for (const auto& p : r.planners) {
      for (const auto& o : p.runs) {
        if (o.complete) continue;
        std::string reason = o.error.empty() ? "-" : o.error;
        std::replace(reason.begin(), reason.end(), '|', '/');
        std::replace(reason.begin(), reason.end(), '\n', ' ');
        md << "| " << run_folder(o.object, o.first_view) << " | " << name_of(p.planner) << " | " << reason << " |\n";
      }
    }
    md << "\n";
  }
  std::string critical;
  for (const auto& p : r.planners) {
    if (p.planner == PlannerKind::kRing || p.planner_critical_ms_median <= 0) continue;
    critical += std::string(critical.empty() ? "" : "; ") + std::string(name_of(p.planner)) + " " + ms(p.planner_critical_ms_median) +
                " ms (the parts' sum " + ms(p.planner_ms_median) + " ms)";
  }
  if (!critical.empty()) {
    md << "- planner time per iteration as the scan waits for it (map update + the view scorer's time from the "
          "request to its answer; the ellipsoid fit runs beside the reachability check), medians: "
       << critical << "\n";
  }
  const bool ratios = pbnbv && pbnbv->planner_ms_median > 0;
  if (ratios) {
    for (const auto& p : r.planners) {
      if (&p == pbnbv || p.planner == PlannerKind::kRing || p.planner_ms_median <= 0) continue;
      md << "- " << name_of(p.planner) << " / pbnbv planner time, medians: " << f1(p.planner_ms_median / pbnbv->planner_ms_median)
         << "x\n";
    }
  }
  if (ratios || !critical.empty()) md << "\n";
}

// The rig's contacts during the scans' moves (the twin's contact check): none, or per planner
// the events and each move with any.
void rig_contacts_section(const BenchResult& r, std::ostream& md) {
  int64_t events = 0;
  for (const auto& p : r.planners) events += p.rig_contacts;
  if (events == 0) {
    md << "Rig contacts: none (no move of any scan touched anything with the arm or the camera).\n\n";
    return;
  }
  md << "## Rig contacts\n\n" << events << " contact" << (events == 1 ? "" : "s")
     << " of the arm or the camera with the rig or the object during the scans' moves (each stops its move):\n\n"
     << "| planner | contacts | run | moves |\n|---|---|---|---|\n";
  for (const auto& p : r.planners) {
    for (const auto& o : p.runs) {
      if (o.rig_contacts == 0) continue;
      std::string moves;
      for (const std::string& c : o.rig_contact_list) moves += (moves.empty() ? "" : "; ") + c;
      std::replace(moves.begin(), moves.end(), '|', '/');
      md << "| " << name_of(p.planner) << " | " << o.rig_contacts << " | " << run_folder(o.object, o.first_view)
         << " | " << moves << " |\n";
    }
  }
  md << "\n";
}

// Coverage of the surface some reachable candidate can see (runs with an observable mask).
void observable_section(const BenchResult& r, std::ostream& md) {
  const BenchSpec& s = r.spec;
  const int n = s.views;
  md << "## Observable coverage (%, mean): over the surface samples that some reachable candidate view can see\n\n| planner |";
  for (int i = 1; i <= n; ++i) md << " " << i << " |";
  md << "\n|---|";
  for (int i = 0; i < n; ++i) md << "---|";
  md << "\n";
  for (const auto& p : r.planners) {
    if (p.observable_by_view.empty()) continue;
    md << "| " << name_of(p.planner) << " |";
    for (int i = 0; i < n; ++i) md << " " << f1(p.observable_by_view[i]) << " |";
    md << "\n";
  }
  md << "\n";
}

// Rig time per scan and its parts, the time to 90 % and 95 % of the observable surface, and the
// rig time at the end of each view.
void rig_time_section(const BenchResult& r, std::ostream& md) {
  const BenchSpec& s = r.spec;
  const int n = s.views;
  const auto seconds = [](const std::optional<double>& t, int runs, int of) {
    return (t ? fixed(*t, 1) + " s" : std::string("never")) + " (" + std::to_string(runs) + " of " + std::to_string(of) + ")";
  };
  md << "## Rig time (s, mean per scan over the " << means_over(s) << " measured at every view)\n\n"
     << "What the rig spends, as a physical rig would: motion (command to within tolerance) and settling on the rig's "
        "clock; capture (the settled move's answer to the frame's arrival at the camera service) and compute (the rig "
        "standing still after a capture until the next command: cloud, registration, map, plan, inverse kinematics; "
        "after the last view until the scan stops) on the wall clock (docs/scan.md, rig time). Time to 90 % and 95 %: the rig time at "
        "the end of the first view whose observable coverage reaches it, mean over the runs that reach it (how many of "
        "those measured).\n\n"
     << "| planner | runs | rig time per scan | motion | settle | capture | compute | motion share | to 90 % observable | "
        "to 95 % observable |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& p : r.planners) {
    if (p.rig_time_runs == 0) continue;
    const RigTime& t = p.rig_time_mean;
    md << "| " << name_of(p.planner) << " | " << p.rig_time_runs << " | " << fixed(t.total_s(), 1) << " | "
       << fixed(t.motion_s, 1) << " | " << fixed(t.settle_s, 2) << " | " << fixed(t.capture_s, 2) << " | "
       << fixed(t.compute_s, 1) << " | " << fixed(t.total_s() > 0 ? 100.0 * t.motion_s / t.total_s() : 0.0, 0) << " % | "
       << seconds(p.rig_time_to_90, p.rig_time_reaching_90, p.rig_time_runs) << " | "
       << seconds(p.rig_time_to_95, p.rig_time_reaching_95, p.rig_time_runs) << " |\n";
  }
  md << "\nRig time (s) from the start to the end of each view, mean:\n\n| planner |";
  for (int i = 1; i <= n; ++i) md << " " << i << " |";
  md << "\n|---|";
  for (int i = 0; i < n; ++i) md << "---|";
  md << "\n";
  for (const auto& p : r.planners) {
    if (p.rig_time_by_view.empty()) continue;
    md << "| " << name_of(p.planner) << " |";
    for (int i = 0; i < n; ++i) md << " " << f1(p.rig_time_by_view[i]) << " |";
    md << "\n";
  }
  md << "\n![observable coverage against rig time](observable_time.png)\n\nobservable_time.png: at each time, each "
        "run's observable coverage after the last view it had finished by then (0 before its first), mean over the runs "
        "(band: min-max); its .csv holds the curves.\n\n";
}

// Each planner's gap to the oracle after each view.
void gap_section(const BenchResult& r, std::ostream& md) {
  const BenchSpec& s = r.spec;
  const int n = s.views;
  md << "## Gap to the oracle (percentage points of coverage, mean over the " << means_over(s) << " both completed)\n\n"
     << "The oracle chooses, on the same candidates, reachability and exclusions, the view that sees the most true "
        "surface samples no view taken saw (greedy, knowing the mesh): the yardstick, not a planner for an unknown "
        "object.\n\n| planner |";
  for (int i = 1; i <= n; ++i) md << " " << i << " |";
  md << " " << means_over(s) << " |\n|---|";
  for (int i = 0; i < n + 1; ++i) md << "---|";
  md << "\n";
  for (const auto& p : r.planners) {
    if (p.planner == PlannerKind::kOracle || p.gap_to_oracle_by_view.empty()) continue;
    md << "| " << name_of(p.planner) << " |";
    for (int i = 0; i < n; ++i) md << " " << f1(p.gap_to_oracle_by_view[i]) << " |";
    md << " " << p.gap_objects << " |\n";
  }
  md << "\n![gap to the oracle](gap.png)\n\n";
}

// Where the surface stop rule would have stopped each run, and what it would have cost.
void stop_rule_section(const BenchResult& r, std::ostream& md) {
  const BenchSpec& s = r.spec;
  const int n = s.views;
  const SurfaceStopRule& rule = s.stop_rule;
  md << "## Stop rule\n\nThe scans spent the whole budget; the surface rule (`pbnbv scan`'s default) would have stopped "
        "each after the first view at which the last "
     << rule.window << " views each added less than " << fixed(rule.max_new_percent, 2)
     << " % new surface (points farther than 5 mm from the model before them, relative to the model), from view "
     << rule.min_views << " on (`--stop-window " << rule.window << " --stop-new-surface " << fixed(rule.max_new_percent, 2)
     << " --stop-min-views " << rule.min_views << "`). Coverage in %, shortfall in points.\n\n"
     << "| run | planner | stop view | coverage there | coverage after view " << n << " | shortfall |\n|---|---|---|---|---|---|\n";
  for (const auto& p : r.planners) {
    for (const auto& o : p.runs) {
      if (!o.complete || o.coverage_by_view.empty()) continue;
      const int stop = stop_view_or_budget(o, n);
      md << "| " << run_folder(o.object, o.first_view) << " | " << name_of(p.planner) << " | " << (o.stop_view ? std::to_string(stop) : "never (" + std::to_string(n) + ")")
         << " | " << fixed(coverage_at_view(o, stop), 2) << " | " << fixed(coverage_at_view(o, n), 2) << " | "
         << fixed(coverage_at_view(o, n) - coverage_at_view(o, stop), 2) << " |\n";
    }
  }
  md << "\n| planner | runs | stopped before " << n << " | mean stop view | mean views saved | worst shortfall | within 0.5 points |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const auto& p : r.planners) {
    const StopRuleSummary& st = p.stop_rule;
    md << "| " << name_of(p.planner) << " | " << st.objects << " | " << st.stopped << " | " << fixed(st.mean_stop_view, 2) << " | "
       << fixed(st.mean_views_saved_percent, 1) << " % | " << fixed(st.worst_shortfall, 2) << " (" << st.worst_object << ") | "
       << st.within_half_point << " of " << st.objects << " |\n";
  }
  const SecondsStopRule& sr = s.seconds_rule;
  md << "\nThe rule in seconds (`--stop-rule seconds --stop-rate-views " << sr.window << " --stop-gain-per-second "
     << fixed(sr.min_percent_per_s, 3) << "`) would have stopped each after the first view (from view " << sr.min_views
     << " on) at which the last " << sr.window << " views added less than " << fixed(sr.min_percent_per_s, 3)
     << " % of the model per second of their rig time (motion, settle, capture). Rig time saved: to the end of the stop "
        "view against to the end of view "
     << n << ".\n\n"
     << "| planner | runs | stopped before " << n << " | mean stop view | mean shortfall | worst shortfall | within 0.5 points | "
        "rig time saved |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& p : r.planners) {
    const StopRuleSummary& st = p.seconds_rule;
    md << "| " << name_of(p.planner) << " | " << st.objects << " | " << st.stopped << " | " << fixed(st.mean_stop_view, 2) << " | "
       << fixed(st.mean_shortfall, 2) << " | " << fixed(st.worst_shortfall, 2) << " (" << st.worst_object << ") | "
       << st.within_half_point << " of " << st.objects << " | "
       << (st.rig_time_runs > 0 ? fixed(st.mean_rig_time_saved_percent, 1) + " % (" + std::to_string(st.rig_time_runs) + " runs)"
                                : std::string("-"))
       << " |\n";
  }
  md << "\n";
}

// Coverage and views to 95 % per object, and the objects where pbnbv ends below ray casting.
void per_object_section(const BenchResult& r, std::ostream& md) {
  const BenchSpec& s = r.spec;
  const int n = s.views;
  const PlannerSummary* pbnbv = find_planner(r, PlannerKind::kPbnbv);
  const std::vector<int> object_views = listed_views({2, 3, 4, 5, 10}, n);
  md << "## Per object: coverage after views ";
  for (std::size_t i = 0; i < object_views.size(); ++i) md << (i ? ", " : "") << object_views[i];
  md << " (%) and views to 95 %, mean over " << (s.first_views > 1 ? "its first views" : "its one first view")
     << "\n\n| object | planner |";
  for (const int v : object_views) md << " " << v << " |";
  md << " views to 95 % (runs reaching it) |\n|---|---|";
  for (std::size_t i = 0; i <= object_views.size(); ++i) md << "---|";
  md << "\n";
  std::vector<std::string> names;
  for (const auto& p : r.planners) {
    for (const auto& o : p.per_object) {
      if (std::find(names.begin(), names.end(), o.object) == names.end()) names.push_back(o.object);
    }
  }
  auto mean_of = [](const PlannerSummary& p, const std::string& name) -> const ObjectMean* {
    const auto it = std::find_if(p.per_object.begin(), p.per_object.end(), [&](const ObjectMean& m) { return m.object == name; });
    return it == p.per_object.end() ? nullptr : &*it;
  };
  for (const auto& name : names) {
    for (const auto& p : r.planners) {
      const ObjectMean* m = mean_of(p, name);
      if (!m) continue;
      md << "| " << name << " | " << name_of(p.planner) << " |";
      if (m->runs_complete == 0) {
        for (std::size_t i = 0; i < object_views.size(); ++i) md << " failed |";
        md << " - |\n";
        continue;
      }
      for (const int v : object_views) md << " " << f1(m->coverage_by_view[v - 1]) << " |";
      md << " " << opt(m->views_to_95) << " (" << m->runs_reaching_95 << " of " << m->runs_complete << ") |\n";
    }
  }
  md << "\n";
  // Where pbnbv ends more than a point below ray casting.
  const PlannerSummary* raycast = find_planner(r, PlannerKind::kRaycast);
  if (pbnbv && raycast) {
    std::vector<std::string> below;
    for (const auto& name : names) {
      const ObjectMean *a = mean_of(*pbnbv, name), *b = mean_of(*raycast, name);
      if (!a || !b || a->coverage_by_view.empty() || b->coverage_by_view.empty()) continue;
      const double pa = a->coverage_by_view.back(), pb = b->coverage_by_view.back();
      if (pa < pb - 1.0) below.push_back(name + " (" + fixed(pa, 2) + " against " + fixed(pb, 2) + ")");
    }
    md << "Objects where pbnbv ends (after view " << n << ", mean over the first views) more than 1 point below raycast: ";
    if (below.empty()) md << "none.\n\n";
    for (std::size_t i = 0; i < below.size(); ++i) md << below[i] << (i + 1 < below.size() ? ", " : ".\n\n");
  }
}

// The tuning set's tune and confirm halves, each its own table.
void halves_section(const BenchResult& r, std::ostream& md) {
  const BenchSpec& s = r.spec;
  const int n = s.views;
  md << "## Halves of the tuning set\n\nThe 30 objects' names sorted alphabetically: positions 1, 3, 5, ... form the tune "
        "half, positions 2, 4, 6, ... the confirm half. Each half's table is over its objects in this benchmark.\n\n";
  for (const HalfSummary& h : r.halves) {
    md << "### " << name_of(h.half) << " half (" << h.objects.size() << (h.objects.size() == 1 ? " object: " : " objects: ");
    for (std::size_t i = 0; i < h.objects.size(); ++i) md << (i ? ", " : "") << h.objects[i];
    md << ")\n\n" << coverage_table(h.planners, s, true) << "\n" << interval_lines(h.planners, n) << "\n";
  }
}

}  // namespace

void write_report(const BenchResult& r) {
  const BenchSpec& s = r.spec;
  bool any_observable = false, any_gap = false, any_rig_time = false;
  for (const auto& p : r.planners) {
    any_observable = any_observable || !p.observable_by_view.empty();
    any_rig_time = any_rig_time || p.rig_time_runs > 0;
    any_gap = any_gap || (p.planner != PlannerKind::kOracle && !p.gap_to_oracle_by_view.empty());
  }
  std::ostringstream md;
  header_section(r, md);
  failed_and_times_section(r, md);
  rig_contacts_section(r, md);
  md << surface_metrics_markdown(r.planners, s.metrics);
  if (any_observable) observable_section(r, md);
  if (any_rig_time) rig_time_section(r, md);
  if (any_gap) gap_section(r, md);
  stop_rule_section(r, md);
  per_object_section(r, md);
  if (!r.halves.empty()) halves_section(r, md);
  md << "\n![coverage](coverage.png)\n\n![time](time.png)\n";
  if (any_observable) md << "\n![observable coverage](observable.png)\n";
  md << "\nsummary.json holds every figure; each scan's outputs are in <planner>/<object>/"
     << (s.first_views > 1 ? " (first view 1) and <planner>/<object>-fv<k>/ (first view k)" : "") << ".\n";
  write_text_atomic(md.str(), (s.out / "report.md").string());

  coverage_chart(r, false, s.out / "coverage.png");
  if (any_observable) coverage_chart(r, true, s.out / "observable.png");
  if (any_rig_time) rig_time_chart(r, s.out / "observable_time.png");
  time_chart(r, s.out / "time.png");
  if (any_gap) gap_chart(r, s.out / "gap.png");
}

std::optional<double> time_ratio_raycast_to_pbnbv(const BenchResult& r) {
  const auto find = [&](PlannerKind k) -> const PlannerSummary* {
    for (const auto& p : r.planners)
      if (p.planner == k && p.complete > 0) return &p;
    return nullptr;
  };
  const PlannerSummary* pb = find(PlannerKind::kPbnbv);
  const PlannerSummary* rc = find(PlannerKind::kRaycast);
  if (!pb || !rc || !(pb->planner_ms_median > 0)) return std::nullopt;
  return rc->planner_ms_median / pb->planner_ms_median;
}

void write_ablation(const std::string& param, const std::vector<std::pair<std::string, BenchResult>>& runs,
                    const fs::path& out) {
  fs::create_directories(out);
  json j = {{"parameter", param}, {"values", json::array()}, {"time_ratios", json::array()}};
  bool several = false;
  for (const auto& run : runs) several = several || run.second.planners.size() > 1;
  LineChart c = coverage_by_view_chart("Ablation: " + param +
                                       (several ? " (mean coverage over objects)" : " (PB-NBV, mean coverage over objects)"));
  std::ostringstream md;
  md << "# Ablation: " << param << "\n\n";
  int n = 0;
  for (const auto& [value, r] : runs) n = std::max(n, r.spec.views);
  md << "| " << param << " |";
  for (int i = 1; i <= n; ++i) md << " " << i << " |";
  md << " views to 95 % | planner time, median (mean) |\n|---|";
  for (int i = 0; i < n + 2; ++i) md << "---|";
  md << "\n";
  // Planner time per iteration against the value, one curve per planner, when every value is a
  // number (tmax, beta, resolution).
  LineChart t;
  t.title = "Planner time per iteration (median over objects and iterations) against " + param;
  t.x_label = param;
  t.y_label = "ms (log scale)";
  t.log_y = true;
  std::map<PlannerKind, ChartSeries> time_series;
  bool numeric = true;
  for (const auto& [value, r] : runs) {
    double x = 0;
    std::istringstream in(value);
    const bool is_number = static_cast<bool>(in >> x) && in.peek() == std::char_traits<char>::eof();
    numeric = numeric && is_number;
    for (const auto& p : r.planners) {
      const std::string planner(name_of(p.planner));
      const std::string label = param + " " + value + (r.planners.size() > 1 ? " " + planner : "");
      j["values"].push_back({{"value", value}, {"planner", planner}, {"coverage_by_view", p.coverage_by_view},
                             {"views_to_95", p.views_to_95 ? json(*p.views_to_95) : json(nullptr)},
                             {"planner_ms_median", p.planner_ms_median}, {"planner_ms_mean", p.planner_ms_mean},
                             {"objects_complete", p.complete}, {"folder", r.spec.out.filename().string()}});
      md << "| " << label << " |";
      for (int i = 0; i < n; ++i) md << " " << (i < static_cast<int>(p.coverage_by_view.size()) ? f1(p.coverage_by_view[i]) : "-") << " |";
      md << " " << opt(p.views_to_95) << " | " << ms(p.planner_ms_median) << " ms (" << ms(p.planner_ms_mean) << ") |\n";
      if (!p.coverage_by_view.empty()) c.series.push_back({label, view_numbers(static_cast<int>(p.coverage_by_view.size())), p.coverage_by_view});
      if (is_number && p.complete > 0 && p.planner_ms_median > 0 && p.planner != PlannerKind::kRing) {
        ChartSeries& s = time_series[p.planner];
        s.label = planner;
        s.x.push_back(x);
        s.y.push_back(p.planner_ms_median);
      }
    }
  }
  bool any_ratio = false;
  for (const auto& run : runs) any_ratio = any_ratio || time_ratio_raycast_to_pbnbv(run.second).has_value();
  if (any_ratio) {
    md << "\nPlanner time per iteration, median over every iteration of every object, and the ratio (same run):\n\n"
       << "| " << param << " | pbnbv | raycast | raycast / pbnbv |\n|---|---|---|---|\n";
    for (const auto& [value, r] : runs) {
      const std::optional<double> ratio = time_ratio_raycast_to_pbnbv(r);
      double pb = NAN, rc = NAN;
      for (const auto& p : r.planners) {
        if (p.planner == PlannerKind::kPbnbv) pb = p.planner_ms_median;
        if (p.planner == PlannerKind::kRaycast) rc = p.planner_ms_median;
      }
      md << "| " << value << " | " << (std::isfinite(pb) ? ms(pb) + " ms" : "-") << " | "
         << (std::isfinite(rc) ? ms(rc) + " ms" : "-") << " | " << (ratio ? fixed(*ratio, 1) + "x" : "-") << " |\n";
      j["time_ratios"].push_back({{"value", value}, {"raycast_to_pbnbv", ratio ? json(*ratio) : json(nullptr)}});
    }
  }
  for (auto& [planner, s] : time_series) t.series.push_back(s);
  const bool time_plot = numeric && !t.series.empty();
  if (!runs.empty()) md << "\nEach value's benchmark (report.md, summary.json, scans) is in its folder; the command:\n\n```\n"
                        << command_of(runs.front().second.spec) << "\n```\n(with the value changed).\n";
  md << "\n![ablation](ablation.png)\n";
  if (time_plot) md << "\n![planner time](ablation_time.png)\n";
  write_json_atomic(j, (out / "ablation.json").string());
  write_text_atomic(md.str(), (out / "ablation.md").string());
  if (!c.series.empty()) write_line_chart(c, (out / "ablation.png").string());
  if (time_plot) write_line_chart(t, (out / "ablation_time.png").string());
}

void write_sweep(const Sweep& sweep, const std::vector<BenchResult>& results) {
  if (results.size() != sweep.benches.size() || sweep.values.size() != sweep.benches.size()) {
    throw std::invalid_argument("write_sweep: one result and one set of values per combination are needed");
  }
  fs::create_directories(sweep.out);
  std::string swept;
  for (const std::string& p : sweep.parameters) swept += (swept.empty() ? "" : " x ") + p;
  json j = {{"parameters", sweep.parameters}, {"benches", json::array()}};
  LineChart c = coverage_by_view_chart("Sweep: " + swept + " (mean coverage)");
  std::ostringstream md;
  md << "# Sweep: " << swept << "\n\n"
     << results.size() << " benchmarks, one per combination, each in its folder (summary.json, report.md, the scans). "
     << "Coverage: mean over each planner's complete runs after the last view, with its 95 % interval (bootstrap over the "
     << "objects); rig time: mean per scan over the runs measured at every view, and to 95 % of the observable surface "
     << "over the runs that reach it.\n\n|";
  for (const std::string& p : sweep.parameters) md << " " << p << " |";
  md << " planner | runs | coverage after the last view (%) | views to 95 % | planner time, median | rig time (s) | to 95 % (s) | rig contacts |\n|";
  for (std::size_t i = 0; i < sweep.parameters.size() + 8; ++i) md << "---|";
  md << "\n";
  for (std::size_t b = 0; b < results.size(); ++b) {
    const BenchResult& r = results[b];
    const int n = r.spec.views;
    json values = json::object();
    for (std::size_t k = 0; k < sweep.parameters.size(); ++k) values[sweep.parameters[k]] = sweep.values[b][k];
    json bj = {{"label", sweep.benches[b].first}, {"folder", r.spec.out.filename().string()}, {"values", values},
               {"planners", json::object()}};
    for (const PlannerSummary& p : r.planners) {
      const std::string planner(name_of(p.planner));
      const double last = p.coverage_by_view.empty() ? NAN : p.coverage_by_view.back();
      const bool timed = p.rig_time_runs > 0;
      bj["planners"][planner] = {
          {"runs_complete", p.complete},
          {"runs_failed", p.failed},
          {"coverage_by_view", p.coverage_by_view},
          {"coverage_ci95_last", p.coverage_ci95_by_view.empty() ? json(nullptr) : json{p.coverage_ci95_by_view.back().lo, p.coverage_ci95_by_view.back().hi}},
          {"views_to_95", p.views_to_95 ? json(*p.views_to_95) : json(nullptr)},
          {"planner_ms_median", p.planner_ms_median},
          {"rig_time_s", timed ? json(p.rig_time_mean.total_s()) : json(nullptr)},
          {"rig_time_s_to_95", p.rig_time_to_95 ? json(*p.rig_time_to_95) : json(nullptr)},
          {"rig_contacts", p.rig_contacts}};
      md << "|";
      for (const std::string& v : sweep.values[b]) md << " " << v << " |";
      md << " " << planner << " | " << p.complete << (p.failed ? " (" + std::to_string(p.failed) + " failed)" : "") << " | "
         << f1(last) << " " << coverage_interval(p, n) << " | " << opt(p.views_to_95) << " | "
         << (p.planner == PlannerKind::kRing ? std::string("-") : ms(p.planner_ms_median) + " ms") << " | "
         << (timed ? f1(p.rig_time_mean.total_s()) : std::string("-")) << " | "
         << (p.rig_time_to_95 ? f1(*p.rig_time_to_95) : std::string("-")) << " | " << p.rig_contacts << " |\n";
      if (!p.coverage_by_view.empty()) {
        ChartSeries line;
        line.label = sweep.benches[b].first + (r.planners.size() > 1 ? " " + planner : "");
        line.x = view_numbers(static_cast<int>(p.coverage_by_view.size()));
        line.y = p.coverage_by_view;
        c.series.push_back(std::move(line));
      }
    }
    j["benches"].push_back(bj);
  }
  if (!results.empty()) {
    BenchSpec first = results.front().spec;
    first.out = sweep.out;
    md << "\nThe command:\n\n```\n" << command_of(first, sweep.lists) << "\n```\n";
  }
  md << "\n![sweep](sweep.png)\n";
  write_json_atomic(j, (sweep.out / "sweep.json").string());
  write_text_atomic(md.str(), (sweep.out / "sweep.md").string());
  if (!c.series.empty()) write_line_chart(c, (sweep.out / "sweep.png").string());
}

}  // namespace pbnbv::eval
