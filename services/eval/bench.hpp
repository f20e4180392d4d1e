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

#include "core/geometry/depth_sensor.hpp"
#include "core/geometry/mesh.hpp"
#include "core/mapping/map_options.hpp"
#include "core/planning/kinds.hpp"
#include "core/planning/planning_options.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/rig_time.hpp"
#include "core/scan/scan_options.hpp"
#include "core/scan/stop_rule.hpp"
#include "core/metrics/surface_metrics.hpp"
#include "eval/bench_slurm.hpp"
#include "eval/coverage.hpp"
#include "eval/objects.hpp"

namespace pbnbv::eval {

// The benchmark's own defaults (the scan's other settings keep theirs): the paper's comparison
// setup (a free camera, candidates on the full sphere), the whole view budget spent as in the
// paper's evaluation, every planner but the ring, one scan at a time.
inline constexpr ChoiceSetting<RigKind> kBenchRig = kRig.with_default(RigKind::kFree);
inline constexpr ChoiceSetting<CandidateArea> kBenchArea = kArea.with_default(CandidateArea::kFullSphere);
inline constexpr std::array<PlannerKind, 4> kBenchPlanners{PlannerKind::kPbnbv, PlannerKind::kPbnbvPaper,
                                                            PlannerKind::kRaycast, PlannerKind::kRandom};
inline constexpr Setting<int> kJobs{"jobs", 1, 1, 64, "", "scans at once, each in its own network namespace"};
// Each object is scanned from N first views: the scan's default one, and N-1 drawn uniformly on
// the candidate area (the sphere, or its half above the object centre for --area hemi) with a
// fixed seed, at the default first view's distance from the object centre.
inline constexpr Setting<int> kFirstViews{"first-views", 1, 1, 10, "",
                                          "first views per object: the scan's default and N-1 drawn uniformly on the "
                                          "candidate area (fixed seed) at its distance"};
inline constexpr std::uint64_t kFirstViewSeed = 1;  // the draws of the first views 2..N
// The 95 % intervals of the means: a percentile bootstrap over the objects.
inline constexpr int kBootstrapResamples = 2000;
inline constexpr std::uint64_t kBootstrapSeed = 1;

struct BenchSpec {
  std::vector<std::string> objects;  // names (default set, built-ins) or mesh paths
  std::vector<PlannerKind> planners = std::vector<PlannerKind>(kBenchPlanners.begin(), kBenchPlanners.end());
  RigKind rig = kBenchRig.value;
  std::string rig_model;  // the rig's MJCF file ("": models/rig_<rig>.xml), e.g. models/rig_ur5e.xml
  CandidateArea area = kBenchArea.value;
  int views = kViews.value;
  double resolution_m = kMapResolution.value;
  int candidates = kCandidates.value;
  int tmax = kTMax.value;
  int beta = kSectors.value;
  std::optional<Eigen::Vector3d> initial_view;  // none: the scan's default first view
  int first_views = kFirstViews.value;          // first views per object (1: the default one only)
  double size_m = kObjectSize.value;
  double working_distance_m = kWorkingDistance.value;  // d_c: suit it to the camera's range (d405: 0.25 m)
  std::optional<UpAxis> up;                     // none: each object's natural up axis
  int64_t seed = kPlannerSeed.value;            // the random planner's seed
  WhenDone when_done = kWhenDone.value;
  Motion motion = kMotion.value;
  MapPose map_pose = kMapPose.value;  // the pose each view enters the planner's map at
  double seconds_per_point = kSecondsPerPoint.value;
  CameraKind camera = kCamera.value;        // the twin's camera (depth_sensor.hpp)
  RigErrors rig_errors = kRigErrors.value;  // the twin's rig errors by name
  double sim_speed = kSimSpeed.value;       // the twin's rig time per wall time
  // The scans spend the whole budget (stop rule off); the summary says where this rule would
  // have stopped each from its recorded per-view figures (it may change in a folder's reruns).
  SurfaceStopRule stop_rule;
  SecondsStopRule seconds_rule;  // the rule in seconds, evaluated the same way
  int jobs = kJobs.value;            // scans run at once (each in its own network namespace)
  bool netns = true;                 // false: every scan on the current LCM bus, one at a time
  // Each scan a task of a Slurm job array (bench_slurm.hpp) instead of a process here; `jobs`
  // does not apply (Slurm decides how many run at once).
  std::optional<SlurmSpec> slurm;
  std::filesystem::path out;
  CoverageParams coverage;
  MetricParams metrics;  // the surface metrics' threshold and sample density

  // Throws std::invalid_argument naming the option that is out of range (the ranges of the
  // table of scan options; the candidates must not be fewer than the parallels they lie on;
  // --first-views above 1 with --initial-view).
  void validate() const;
};

nlohmann::json to_json(const BenchSpec& s);

// The directions (unit vectors) of the first views 2..s.first_views, view k at index k - 2:
// drawn uniformly (uniform_sphere_points, seed kFirstViewSeed) on the sphere, or on its upper
// half for --area hemi; the same for every object and planner, so runs compare across planners.
std::vector<Eigen::Vector3d> first_view_directions(const BenchSpec& s);
// The distance from the object centre of the scan's default first view of `object` (loaded and
// normalised as its scans are: --size, --up or its own up axis; --working-distance):
// views_known_at_start's.
double default_first_view_distance(const std::string& object, double size_m, double working_distance_m,
                                   std::optional<UpAxis> up);
// A run's folder below DIR/<planner>/ (and its name in summary.json and the report): the
// object's name for the default first view, <name>-fv<k> for the first view k >= 2.
std::string run_folder(const std::string& name, int first_view);

// One scan's evaluation as the summary keeps it: a run, one object from one first view.
struct ObjectRun {
  std::string object;
  int first_view = 1;                           // 1: the scan's default first view; 2..N: drawn
  std::optional<Eigen::Vector3d> initial_view;  // the first camera position (object frame), as the scan recorded it
  PlannerKind planner = PlannerKind::kPbnbv;
  bool complete = false;                  // the scan finished (state "done") and was evaluated
  std::string error;                      // why not (scan_failure_reason)
  std::vector<double> coverage_by_view;   // views 1..N; after an early stop the last figure holds
  std::vector<double> observable_by_view; // the same over the observable samples
  std::vector<double> planner_ms;         // per planning iteration
  std::vector<double> planner_critical_ms;  // the same as the scan waited for them (those recorded)
  std::optional<int> views_to_95;         // first view with coverage >= 95 %
  int views_done = 0;
  std::string stop_reason;
  double wall_s = 0;                      // the scan's wall time (as recorded when it ran)
  // Rig time (core/scan/rig_time.hpp): from the start to the end of each view of coverage_by_view,
  // s (padded as it; NaN from a view not measured in full; empty: the scan recorded none), and
  // the scan's sums per part (none unless every view's is known).
  std::vector<double> rig_time_by_view;
  std::optional<RigTime> rig_time;
  // The surface stop rule on the scan's recorded figures (scan.json's new_surface per view).
  std::vector<double> new_surface_by_view;  // percent of the model, NaN for a view not merged
  std::optional<int> stop_view;             // the view after which the rule would stop (none: never)
  std::string stop_rule_reason;
  // The rule in seconds on the recorded figures (new surface and rig time before computation).
  std::optional<int> seconds_stop_view;
  std::string seconds_stop_reason;
  // After the last view, against the true mesh (evaluate_scan): the cloud's and mesh.ply's.
  std::optional<SurfaceMetrics> cloud_metrics, mesh_metrics;
  // Contacts of the rig during the scan's moves (scan.json's rig_contacts; complete or not): the
  // events, and per move with any "view 3 (request 17): <the last contact>".
  int64_t rig_contacts = 0;
  std::vector<std::string> rig_contact_list;
};

// A planner's surface metrics after the last view, mean over the complete runs that have them.
struct MeanSurfaceMetrics {
  int objects = 0;  // runs (objects x first views) with the metrics
  double accuracy_mean_mm = 0, accuracy_median_mm = 0, accuracy_rmse_mm = 0, accuracy_p95_mm = 0;
  double completeness_mean_mm = 0;
  double precision = 0, recall = 0, f_score = 0;
};
// The mean of `metrics` over the runs where `which` has a value (objects = 0: none has).
MeanSurfaceMetrics mean_surface_metrics(const std::vector<ObjectRun>& runs,
                                        std::optional<SurfaceMetrics> ObjectRun::*which);

// Where the stop rule would have stopped a planner's scans: per complete run the stop view
// (the budget when it never stops), the coverage there and at the budget.
struct StopRuleSummary {
  int objects = 0;                    // complete runs (objects x first views)
  int stopped = 0;                    // of them, stopped before the budget
  double mean_stop_view = 0;          // mean over the runs of the stop view (budget if never)
  double mean_views_saved_percent = 0;  // 100 * (budget - stop view) / budget, mean
  double worst_shortfall = 0;         // largest coverage at the budget minus at the stop view, points
  std::string worst_object;           // that run's run_folder name
  int within_half_point = 0;          // runs whose shortfall is at most 0.5 points
  double mean_shortfall = 0;          // coverage at the budget minus at the stop view, mean, points
  // Rig time to the end of the stop view against to the end of the budget's last view, over the
  // runs with both known: 100 * (1 - stop / budget), mean, and the runs.
  double mean_rig_time_saved_percent = 0;
  int rig_time_runs = 0;
};
// The stop view of a run (its budget `views` when the rule never stops it), its coverage there and the shortfall.
// `stop`: which rule's stop view (the surface rule's, or seconds_stop_view).
using StopViewOf = std::optional<int> ObjectRun::*;
int stop_view_or_budget(const ObjectRun& r, int views, StopViewOf stop = &ObjectRun::stop_view);
double coverage_at_view(const ObjectRun& r, int view);
StopRuleSummary summarise_stop_rule(const std::vector<ObjectRun>& runs, int views, StopViewOf stop = &ObjectRun::stop_view);

// The middle value of `v` (the mean of the two middle ones for an even count); `v` not empty.
double median_of(std::vector<double> v);

// A 95 % interval [lo, hi].
struct Interval {
  double lo = 0, hi = 0;
};

// The percentile bootstrap of a mean: `rows` (one per object, every row as long as the first)
// resampled with replacement `resamples` times (mt19937_64(seed), the same resamples for every
// column), and per column the 2.5th and 97.5th percentiles (linear between order statistics) of
// the resampled rows' means. No rows: empty. Throws std::invalid_argument for rows of unequal
// length or resamples < 1.
std::vector<Interval> bootstrap_mean_ci95(const std::vector<std::vector<double>>& rows,
                                          int resamples = kBootstrapResamples, std::uint64_t seed = kBootstrapSeed);

// One object's figures, mean over its complete runs (its first views).
struct ObjectMean {
  std::string object;
  int runs_complete = 0, runs_failed = 0;
  std::vector<double> coverage_by_view;  // mean over the complete runs (padded to the budget); empty if none
  std::optional<double> views_to_95;     // mean over the complete runs that reach 95 %; none if none does
  int runs_reaching_95 = 0;
};
// Per object, in the order the runs first name them.
std::vector<ObjectMean> object_means(const std::vector<ObjectRun>& runs, int views);

struct PlannerSummary {
  PlannerKind planner = PlannerKind::kPbnbv;
  // Means and spread over the complete runs (objects x first views).
  std::vector<double> coverage_by_view;    // mean over the complete runs
  std::vector<double> coverage_min_by_view, coverage_max_by_view;  // spread over the complete runs
  std::vector<double> observable_by_view;  // mean over the complete runs
  double planner_ms_median = 0, planner_ms_mean = 0;  // over every iteration of every run
  double planner_critical_ms_median = 0;              // the same iterations as the scan waited
                                                      // for them (0: none recorded)
  std::optional<double> views_to_95;       // mean over the runs that reach 95 %
  std::optional<int> views_to_95_of_mean;  // first view at which the mean coverage reaches 95 %
  int reached_95 = 0, complete = 0, failed = 0;  // runs
  std::vector<ObjectRun> runs;
  // Per object (mean over its first views), and the 95 % intervals by bootstrap over the objects
  // (each object's value its mean over its complete first views): of the mean coverage after
  // each view (over the objects_complete objects with a complete run), and of views to 95 %
  // (over the objects_reaching_95 objects with a run reaching 95 %, each its mean over those
  // runs; an object that never reaches 95 % is left out, as in views_to_95).
  std::vector<ObjectMean> per_object;
  int objects_complete = 0, objects_reaching_95 = 0;
  std::vector<Interval> coverage_ci95_by_view;
  std::optional<Interval> views_to_95_ci95;
  // Percentage points of coverage the oracle has above this planner after views 1..N, mean over
  // the runs (object and first view) complete for both (gap_objects of them); empty when the
  // oracle was not run.
  std::vector<double> gap_to_oracle_by_view;
  int gap_objects = 0;
  StopRuleSummary stop_rule, seconds_rule;
  MeanSurfaceMetrics cloud_metrics, mesh_metrics;  // after the last view
  // Contact events of the rig over every run (complete or not), and the runs with any (run_folder).
  int64_t rig_contacts = 0;
  std::vector<std::string> runs_with_rig_contacts;
  // Rig time over the complete runs with a rig time measured in full (rig_time_runs of them): the
  // mean per scan of each part, the mean rig time from the start to the end of each view, and
  // the mean time to 90 % and 95 % of the observable surface over the runs that reach it
  // (rig_time_to_reach; none when no run does).
  int rig_time_runs = 0;
  RigTime rig_time_mean{0, 0, 0, 0};
  std::vector<double> rig_time_by_view;
  std::optional<double> rig_time_to_90, rig_time_to_95;
  int rig_time_reaching_90 = 0, rig_time_reaching_95 = 0;
};

// Why a scan in `dir` did not complete, for the report: scan.json's state and message ("scan
// failed after 3 of 10 views: ..."), else the last line of its log, else that neither exists;
// each with the log's path.
std::string scan_failure_reason(const std::filesystem::path& dir, const std::filesystem::path& log);

// Pure helpers (tested): the first view (1-based) whose coverage reaches `percent`; a curve
// padded to n views with its last value; the summary of a planner's runs (every object from
// every first view).
std::optional<int> views_to_reach(const std::vector<double>& coverage_by_view, double percent);
std::vector<double> pad_views(std::vector<double> v, int n);
// The rig time (s, from the start) at the end of the first view whose coverage reaches `percent`
// (coverage and rig time per view, in step); none when no view reaches it, or that view's rig
// time is not known (NaN, or the rig time has fewer views).
std::optional<double> rig_time_to_reach(const std::vector<double>& coverage_by_view,
                                        const std::vector<double>& rig_time_by_view, double percent);
// The times at which coverage_at_rig_times is drawn: 0, step, 2 step, ... up to the first at or
// past max_s, the step the smallest of 1, 2, 5 x 10^k (k whole) that needs at most `points`
// steps (max_s <= 0: just 0).
std::vector<double> rig_time_grid(double max_s, int points = 200);
// Observable coverage against rig time, over a planner's complete runs with observable coverage
// and a rig time known at every view: each run's coverage at time t is its figure after the last
// view that ended at or before t (0 before its first view; its last figure after its last view);
// at each of `times`, the mean over those runs (`runs`), and their min and max.
struct CoverageOverTime {
  int runs = 0;
  std::vector<double> mean, lo, hi;  // per time
};
CoverageOverTime coverage_at_rig_times(const std::vector<ObjectRun>& runs, const std::vector<double>& times);
PlannerSummary summarise(PlannerKind planner, const std::vector<ObjectRun>& runs, int views);
// Fills every planner's gap_to_oracle_by_view (the oracle's own: zeros) when `planners` holds
// the oracle; otherwise leaves them empty. Runs pair by object and first view.
void add_gaps_to_oracle(std::vector<PlannerSummary>& planners, int views);

// One half of the tuning set (tuning_half): each planner summarised over the runs of the
// benchmark's objects in that half.
struct HalfSummary {
  ObjectSet half = ObjectSet::kTune;
  std::vector<std::string> objects;  // the benchmark's objects in this half, in its order
  std::vector<PlannerSummary> planners;
};
// Both halves when `spec.objects` names members of both (a member given by its name; a path is
// no member), else none.
std::vector<HalfSummary> summarise_halves(const BenchSpec& spec, const std::vector<PlannerSummary>& planners);

struct BenchResult {
  BenchSpec spec;
  std::vector<PlannerSummary> planners;
  std::vector<HalfSummary> halves;  // summarise_halves
  nlohmann::json machine;
};

nlohmann::json to_json(const BenchResult& r);

// report.md's section of surface metrics after the last view: one row per planner and model
// (cloud, mesh) with objects evaluated, mean accuracy (mean, median, RMSE, p95, mm), mean
// completeness (mm) and precision / recall / F-score at the threshold; "" when no planner has any.
std::string surface_metrics_markdown(const std::vector<PlannerSummary>& planners, const MetricParams& params);

// The objects a result's means are over, for titles: "12 objects, 1 of 13 failed" (every
// planner the same), "11-12 objects (failed: pbnbv 1, random 2 of 13)", "13 objects"; with
// several first views the runs: "12 objects x 3 first views (36 runs)", "35 of 36 runs (12
// objects x 3 first views), 1 failed", "34-35 of 36 runs (12 objects x 3 first views; failed:
// pbnbv 1, random 2)".
std::string objects_text(const BenchResult& r);

// Runs the scans that are not complete in spec.out (every object from every first view, in
// DIR/<planner>/<run_folder>), evaluates every scan, writes
// spec.out/summary.json, report.md, coverage.png, time.png (and observable.png on the arm rig,
// gap.png when the oracle ran).
// `self` is the pbnbv executable that runs each scan. Progress goes to `log`: with `terminal`,
// one line per running scan redrawn in place with an estimate of the time left (bench_progress.hpp),
// else plain lines.
BenchResult run_bench(const BenchSpec& spec, const std::filesystem::path& self, std::ostream& log,
                      bool terminal = false);
// Several benchmarks at once (a sweep's or an ablation's: each with its label, e.g.
// "resolution=0.01"): every scan of every one in one run (spec.jobs at a time, or on Slurm, as
// the first bench's spec says: the options of how to run are the same for all), then each
// bench's evaluation and summary as run_bench writes them. The scans' evaluation runs as tasks
// like the scans, one per object of each bench (bench_evaluation.hpp): here spec.jobs at a time,
// or as Slurm tasks. `root`: the run's folder (Slurm's scripts and output go to root/slurm).
std::vector<BenchResult> run_benches(const std::vector<std::pair<std::string, BenchSpec>>& benches,
                                     const std::filesystem::path& root, const std::filesystem::path& self,
                                     std::ostream& log, bool terminal = false);

// An ablation: one benchmark per value of `param` (runs: the value as text, its benchmark), run
// together (run_benches), then write_ablation into `out`. Progress goes to `log`.
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
