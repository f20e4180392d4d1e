#pragma once
// A replayed scan against its recording (`pbnbv replay`): per view, the decisions the pipeline
// made in each (registration accepted, the correction it applied, the voxel map's counts per
// state, the view the planner chose), read from the two scan.json records. (The poses a replay
// moves to are the record's: recorded_attempts, scan_record.hpp.)
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/base/pose.hpp"
#include "core/scan/scan_record.hpp"

namespace pbnbv {

// Two planned views are the same view within these.
inline constexpr double kSameViewPositionM = 1e-6;
inline constexpr double kSameViewAngleRad = 1e-6;

// replay.json: {"views": [per view: "view" (from 1, as scan.json's), "accepted", "merged", "correction",
// "registered_pose", "voxels", "plan"; each with the original's and the replay's value and
// whether they agree], "same_decisions", "differences": [what differs, one line each]}.
nlohmann::json compare_scans(const RecordedScan& original, const RecordedScan& replay);

// The comparison as a table for people, one line per view, then the verdict.
std::string comparison_table(const nlohmann::json& comparison);

}  // namespace pbnbv
