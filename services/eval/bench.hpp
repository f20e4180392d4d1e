#pragma once
// The benchmark: every planner on every object in the twin (each scan a full `pbnbv scan`, in
// its own private network namespace so that scans can run side by side), evaluated against the
// ground truth as the paper does, summarised (summary.json), reported (report.md + PNG plots),
// and resumable (a rerun skips the scans already complete in the output folder). The ablations
// run the benchmark once per value of one PB-NBV parameter.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/geometry/mesh.hpp"
#include "core/mapping/map_options.hpp"
#include "core/planning/kinds.hpp"
#include "core/planning/planning_options.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/scan_options.hpp"
#include "core/scan/stop_rule.hpp"
#include "core/metrics/surface_metrics.hpp"
#include "eval/coverage.hpp"

namespace pbnbv::eval {

// The benchmark's own defaults (the scan's other settings keep theirs): the paper's comparison
// setup (a free camera, candidates on the full sphere), the whole view budget spent as in the
// paper's evaluation, every planner but the ring, one scan at a time.
inline constexpr ChoiceSetting<RigKind> kBenchRig = kRig.with_default(RigKind::kFree);
inline constexpr ChoiceSetting<CandidateArea> kBenchArea = kArea.with_default(CandidateArea::kFullSphere);
inline constexpr std::array<PlannerKind, 4> kBenchPlanners{PlannerKind::kPbnbv, PlannerKind::kPbnbvPaper,
                                                            PlannerKind::kRaycast, PlannerKind::kRandom};
inline constexpr Setting<int> kJobs{"jobs", 1, 1, 64, "", "scans at once, each in its own network namespace"};

struct BenchSpec {
  std::vector<std::string> objects;  // names (default set, built-ins) or mesh paths
  std::vector<PlannerKind> planners = std::vector<PlannerKind>(kBenchPlanners.begin(), kBenchPlanners.end());
  RigKind rig = kBenchRig.value;
  CandidateArea area = kBenchArea.value;
  int views = kViews.value;
  double resolution_m = kMapResolution.value;
  int candidates = kCandidates.value;
  int tmax = kTMax.value;
  int beta = kSectors.value;
  std::optional<Eigen::Vector3d> initial_view;  // none: the scan's default first view
  double size_m = kObjectSize.value;
  std::optional<UpAxis> up;                     // none: each object's natural up axis
  int64_t seed = kPlannerSeed.value;            // the random planner's seed
  WhenDone when_done = kWhenDone.value;
  // The scans spend the whole budget (stop rule off); the summary says where this rule would
  // have stopped each from its recorded per-view figures (it may change in a folder's reruns).
  SurfaceStopRule stop_rule;
  int jobs = kJobs.value;            // scans run at once (each in its own network namespace)
  bool netns = true;                 // false: every scan on the current LCM bus, one at a time
  std::filesystem::path out;
  CoverageParams coverage;
  MetricParams metrics;  // the surface metrics' threshold and sample density

  // Throws std::invalid_argument naming the option that is out of range (the ranges of the
  // table of scan options; the candidates must not be fewer than the parallels they lie on).
  void validate() const;
};

nlohmann::json to_json(const BenchSpec& s);

// One scan's evaluation as the summary keeps it.
struct ObjectRun {
  std::string object;
  PlannerKind planner = PlannerKind::kPbnbv;
  bool complete = false;                  // the scan finished (state "done") and was evaluated
  std::string error;                      // why not (scan_failure_reason)
  std::vector<double> coverage_by_view;   // views 1..N; after an early stop the last figure holds
  std::vector<double> observable_by_view; // the same over the observable samples
  std::vector<double> planner_ms;         // per planning iteration
  std::optional<int> views_to_95;         // first view with coverage >= 95 %
  int views_done = 0;
  std::string stop_reason;
  double wall_s = 0;                      // the scan's wall time (as recorded when it ran)
  // The surface stop rule on the scan's recorded figures (scan.json's new_surface per view).
  std::vector<double> new_surface_by_view;  // percent of the model, NaN for a view not merged
  std::optional<int> stop_view;             // the view after which the rule would stop (none: never)
  std::string stop_rule_reason;
  // After the last view, against the true mesh (evaluate_scan): the cloud's and mesh.ply's.
  std::optional<SurfaceMetrics> cloud_metrics, mesh_metrics;
};

// A planner's surface metrics after the last view, mean over the complete objects that have them.
struct MeanSurfaceMetrics {
  int objects = 0;
  double accuracy_mean_mm = 0, accuracy_median_mm = 0, accuracy_rmse_mm = 0, accuracy_p95_mm = 0;
  double completeness_mean_mm = 0;
  double precision = 0, recall = 0, f_score = 0;
};
// The mean of `metrics` over the runs where `which` has a value (objects = 0: none has).
MeanSurfaceMetrics mean_surface_metrics(const std::vector<ObjectRun>& runs,
                                        std::optional<SurfaceMetrics> ObjectRun::*which);

// Where the stop rule would have stopped a planner's scans: per complete object the stop view
// (the budget when it never stops), the coverage there and at the budget.
struct StopRuleSummary {
  int objects = 0;                    // complete objects
  int stopped = 0;                    // of them, stopped before the budget
  double mean_stop_view = 0;          // mean over the objects of the stop view (budget if never)
  double mean_views_saved_percent = 0;  // 100 * (budget - stop view) / budget, mean
  double worst_shortfall = 0;         // largest coverage at the budget minus at the stop view, points
  std::string worst_object;
  int within_half_point = 0;          // objects whose shortfall is at most 0.5 points
};
// The stop view of a run (its budget `views` when the rule never stops it), its coverage there and the shortfall.
int stop_view_or_budget(const ObjectRun& r, int views);
double coverage_at_view(const ObjectRun& r, int view);
StopRuleSummary summarise_stop_rule(const std::vector<ObjectRun>& runs, int views);

struct PlannerSummary {
  PlannerKind planner = PlannerKind::kPbnbv;
  std::vector<double> coverage_by_view;    // mean over the complete objects
  std::vector<double> coverage_min_by_view, coverage_max_by_view;  // spread over the complete objects
  std::vector<double> observable_by_view;  // mean over the complete objects
  double planner_ms_median = 0, planner_ms_mean = 0;  // over every iteration of every object
  std::optional<double> views_to_95;       // mean over the objects that reach 95 %
  std::optional<int> views_to_95_of_mean;  // first view at which the mean coverage reaches 95 %
  int reached_95 = 0, complete = 0, failed = 0;
  std::vector<ObjectRun> objects;
  // Percentage points of coverage the oracle has above this planner after views 1..N, mean over
  // the objects complete for both (gap_objects of them); empty when the oracle was not run.
  std::vector<double> gap_to_oracle_by_view;
  int gap_objects = 0;
  StopRuleSummary stop_rule;
  MeanSurfaceMetrics cloud_metrics, mesh_metrics;  // after the last view
};

// Why a scan in `dir` did not complete, for the report: scan.json's state and message ("scan
// failed after 3 of 10 views: ..."), else the last line of its log, else that neither exists;
// each with the log's path.
std::string scan_failure_reason(const std::filesystem::path& dir, const std::filesystem::path& log);

// Pure helpers (tested): the first view (1-based) whose coverage reaches `percent`; a curve
// padded to n views with its last value; the summary of a planner's runs.
std::optional<int> views_to_reach(const std::vector<double>& coverage_by_view, double percent);
std::vector<double> pad_views(std::vector<double> v, int n);
PlannerSummary summarise(PlannerKind planner, const std::vector<ObjectRun>& runs, int views);
// Fills every planner's gap_to_oracle_by_view (the oracle's own: zeros) when `planners` holds
// the oracle; otherwise leaves them empty.
void add_gaps_to_oracle(std::vector<PlannerSummary>& planners, int views);

struct BenchResult {
  BenchSpec spec;
  std::vector<PlannerSummary> planners;
  nlohmann::json machine;
};

nlohmann::json to_json(const BenchResult& r);

// report.md's section of surface metrics after the last view: one row per planner and model
// (cloud, mesh) with objects evaluated, mean accuracy (mean, median, RMSE, p95, mm), mean
// completeness (mm) and precision / recall / F-score at the threshold; "" when no planner has any.
std::string surface_metrics_markdown(const std::vector<PlannerSummary>& planners, const MetricParams& params);

// The objects a result's means are over, for titles: "12 objects, 1 of 13 failed" (every
// planner the same), "11-12 objects (failed: pbnbv 1, random 2 of 13)", "13 objects".
std::string objects_text(const BenchResult& r);

// Runs the scans that are not complete in spec.out, evaluates every scan, writes
// spec.out/summary.json, report.md, coverage.png, time.png (and observable.png on the arm rig,
// gap.png when the oracle ran).
// `self` is the pbnbv executable that runs each scan. Progress goes to `log`: with `terminal`,
// one line per running scan redrawn in place with an estimate of the time left (bench_progress.hpp),
// else plain lines.
BenchResult run_bench(const BenchSpec& spec, const std::filesystem::path& self, std::ostream& log,
                      bool terminal = false);

// An ablation: one benchmark per value of `param` (runs: the value as text, its benchmark), in
// the order given, then write_ablation into `out`. Progress goes to `log`.
std::vector<std::pair<std::string, BenchResult>> run_ablation(const std::string& param,
                                                              const std::vector<std::pair<std::string, BenchSpec>>& runs,
                                                              const std::filesystem::path& out,
                                                              const std::filesystem::path& self, std::ostream& log,
                                                              bool terminal = false);

// Writes report.md and the plots for a finished benchmark (report.cpp).
void write_report(const BenchResult& r);
// Writes out/ablation.json, ablation.md, ablation.png (coverage per view, one curve per value and
// planner) for an ablation's benchmarks (value, result), in the order run; when every value is a
// number also ablation_time.png (planner time per iteration, median, against the value, log
// scale, one curve per planner); when pbnbv and raycast both ran, a table of their times and
// time_ratio_raycast_to_pbnbv per value (ablation.md, and "time_ratios" in ablation.json).
// Ray casting's planner time median over PB-NBV's in one benchmark; none unless both completed
// at least one scan with a positive PB-NBV time.
std::optional<double> time_ratio_raycast_to_pbnbv(const BenchResult& r);
void write_ablation(const std::string& param, const std::vector<std::pair<std::string, BenchResult>>& runs,
                    const std::filesystem::path& out);

}  // namespace pbnbv::eval
