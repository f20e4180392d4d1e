#pragma once
// What a finished twin scan achieved, measured against the ground truth the twin rendered
// (object.stl in the output folder, the normalised mesh): coverage after every view, as the
// paper measures it, and the planner time per iteration. Reads only the output folder.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "eval/coverage.hpp"

namespace pbnbv::eval {

struct ScanEvaluation {
  std::vector<double> coverage_by_view;  // percent after views 1..n (a view that added nothing
                                         // to the model repeats the previous figure)
  std::vector<double> observable_by_view;  // the same over the observable samples (when a mask
                                           // is given; empty otherwise)
  std::vector<double> planner_ms;        // per planning iteration: map update + ellipsoid fit +
                                         // view selection (views 2..n; empty for a ring scan)
  std::vector<int> points_by_view;       // points in the model after each view
  std::vector<double> new_surface_by_view;  // what each view added, % of the model before it
                                            // (the stop rule's figure; NaN: not merged or not recorded)
  std::string state;                     // scan.json status.state
  std::string stop_reason;               // why the scan stopped
  int views_done = 0;
};

// Evaluates the scan in `out` (scan.json, frames/, object.stl). `observable` (optional): one
// flag per coverage sample (CoverageEvaluator(object.stl, params).samples()), 1 = some reachable
// candidate view can see it. Throws std::runtime_error naming the file that is missing or
// malformed, std::invalid_argument when the mask's size is not the number of samples.
ScanEvaluation evaluate_scan(const std::filesystem::path& out, const CoverageParams& params = {},
                             const std::vector<uint8_t>* observable = nullptr);

nlohmann::json to_json(const ScanEvaluation& e, const CoverageParams& params);

}  // namespace pbnbv::eval
