#pragma once
// The benchmark: every planner on every object in the twin (each scan a full `pbnbv scan`, in
// its own private network namespace so that scans can run side by side), evaluated against the
// ground truth as the paper does, summarised (summary.json), reported (report.md + PNG plots),
// and resumable (a rerun skips the scans already complete in the output folder). The ablations
// run the benchmark once per value of one PB-NBV parameter.
#include <Eigen/Core>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "eval/coverage.hpp"

namespace pbnbv::eval {

struct BenchSpec {
  std::vector<std::string> objects;  // names (default set, built-ins) or mesh paths
  std::vector<std::string> planners = {"pbnbv", "raycast", "random"};
  std::string rig = "free";          // free | arm
  std::string area = "full";         // full | hemi
  int views = 10;
  double resolution_m = 0.03;
  int candidates = 800;
  int tmax = 10;
  int beta = 4;
  std::optional<Eigen::Vector3d> initial_view;  // none: the scan's default first view
  double size_m = 0.3;
  std::string up;                    // "" : each object's natural up axis
  int64_t seed = 1;                  // the random planner's seed
  std::string when_done = "spread";  // the paper's evaluation spends the whole view budget
  int jobs = 1;                      // scans run at once (each in its own network namespace)
  bool netns = true;                 // false: every scan on the current LCM bus, one at a time
  std::filesystem::path out;
  CoverageParams coverage;

  // Throws std::invalid_argument naming the option that is out of range.
  void validate() const;
};

nlohmann::json to_json(const BenchSpec& s);

// One scan's evaluation as the summary keeps it.
struct ObjectRun {
  std::string object;
  std::string planner;
  bool complete = false;                  // the scan finished (state "done") and was evaluated
  std::string error;                      // why not
  std::vector<double> coverage_by_view;   // views 1..N; after an early stop the last figure holds
  std::vector<double> observable_by_view; // the same over the observable samples
  std::vector<double> planner_ms;         // per planning iteration
  std::optional<int> views_to_95;         // first view with coverage >= 95 %
  int views_done = 0;
  std::string stop_reason;
  double wall_s = 0;                      // the scan's wall time (as recorded when it ran)
};

struct PlannerSummary {
  std::string planner;
  std::vector<double> coverage_by_view;    // mean over the complete objects
  std::vector<double> observable_by_view;  // mean over the complete objects
  double planner_ms_median = 0, planner_ms_mean = 0;  // over every iteration of every object
  std::optional<double> views_to_95;       // mean over the objects that reach 95 %
  std::optional<int> views_to_95_of_mean;  // first view at which the mean coverage reaches 95 %
  int reached_95 = 0, complete = 0, failed = 0;
  std::vector<ObjectRun> objects;
};

// Pure helpers (tested): the first view (1-based) whose coverage reaches `percent`; a curve
// padded to n views with its last value; the summary of a planner's runs.
std::optional<int> views_to_reach(const std::vector<double>& coverage_by_view, double percent);
std::vector<double> pad_views(std::vector<double> v, int n);
PlannerSummary summarise(const std::string& planner, const std::vector<ObjectRun>& runs, int views);

struct BenchResult {
  BenchSpec spec;
  std::vector<PlannerSummary> planners;
  nlohmann::json machine;
};

nlohmann::json to_json(const BenchResult& r);

// Runs the scans that are not complete in spec.out, evaluates every scan, writes
// spec.out/summary.json, report.md, coverage.png, time.png (and observable.png on the arm rig).
// `self` is the pbnbv executable that runs each scan. Progress goes to `log`.
BenchResult run_bench(const BenchSpec& spec, const std::filesystem::path& self, std::ostream& log);

// The command lines: `pbnbv bench ...` and `pbnbv ablate ...` (argv as main's).
int bench_command(int argc, char** argv, const std::filesystem::path& self);
int ablate_command(int argc, char** argv, const std::filesystem::path& self);

// Writes report.md and the plots for a finished benchmark (report.cpp).
void write_report(const BenchResult& r);
// Writes out/ablation.json, ablation.md, ablation.png (coverage per view, one curve per value)
// and ablation_time.png for an ablation's benchmarks (value, result), in the order run.
void write_ablation(const std::string& param, const std::vector<std::pair<std::string, BenchResult>>& runs,
                    const std::filesystem::path& out);

}  // namespace pbnbv::eval
