#pragma once
// pbnbv-study's planners and its per-state analysis (planner research only; planner_study_main.cpp).
#include <limits>
#include <string>
#include <vector>

#include "core/geometry/mesh.hpp"
#include "core/geometry/visibility.hpp"
#include "core/mapping/voxel_map.hpp"
#include "core/planning/planner.hpp"

namespace pbnbv::study {

// The true object, for the oracle and the analysis.
struct Truth {
  const TriangleMesh* mesh = nullptr;
  const SurfaceSamples* samples = nullptr;
};

// What a scan carries from one plan to the next, as the scan sequencer does.
struct State {
  std::vector<Pose> views_done;
  double first_quality = std::numeric_limits<double>::quiet_NaN();
};

struct Choice {
  bool ok = false;
  Pose view = Pose::Identity();
  std::string why;
};

// One plan as the view scorer makes it on the free rig, full sphere (pbnbv, pbnbv-paper, raycast,
// oracle), from the map and the state; updates state.first_quality.
Choice plan(const std::string& planner, const VoxelMap& map, State& state, const CameraIntrinsics& camera,
            const DepthRange& range, const Truth& truth);

// Every candidate's figures in this state, as one JSON object: which are scored, the oracle's gain
// (true surface samples newly seen), ray casting's gain, F, the gap to the views taken (deg), the
// combined ranking's ray term, and pbnbv's combined score (shortlisted candidates only).
std::string analyse_state(const VoxelMap& map, const State& state, const CameraIntrinsics& camera,
                          const DepthRange& range, const Truth& truth);

}  // namespace pbnbv::study
