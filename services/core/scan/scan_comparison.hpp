#pragma once
// A replayed scan against its recording (`pbnbv replay`): per view, the decisions the pipeline
// made in each (registration accepted, the correction it applied, the voxel map's counts per
// state, the view the planner chose), read from the two scan.json records, plus the poses a
// replay must move to (the recording's).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/base/pose.hpp"

namespace pbnbv {

// Two planned views are the same view within these.
inline constexpr double kSameViewPositionM = 1e-6;
inline constexpr double kSameViewAngleRad = 1e-6;

// The poses each recorded view moved to, in order: its failed moves, then the one it reached.
// `scan`: a scan.json; `file` names it in errors. Throws std::invalid_argument naming the file
// and the view when a pose is malformed.
std::vector<std::vector<Pose>> recorded_attempts(const nlohmann::json& scan, const std::string& file);

// replay.json: {"views": [per view: "view" (0-based), "accepted", "merged", "correction",
// "registered_pose", "voxels", "plan"; each with the original's and the replay's value and
// whether they agree], "same_decisions", "differences": [what differs, one line each]}.
nlohmann::json compare_scans(const nlohmann::json& original, const nlohmann::json& replay);

// The comparison as a table for people, one line per view, then the verdict.
std::string comparison_table(const nlohmann::json& comparison);

}  // namespace pbnbv
