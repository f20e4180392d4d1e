#pragma once
// The planning settings, each defined once (core/base/setting.hpp): default, allowed range,
// unit and meaning. CandidateSpec and PlanInput take their defaults from here; so do the scan
// settings, the benchmark, the ellipsoid fitter's and the launcher's options and their help.
#include <cstdint>

#include "core/base/setting.hpp"
#include "core/planning/kinds.hpp"

namespace pbnbv {

inline constexpr ChoiceSetting<PlannerKind> kPlanner{
    "planner", PlannerKind::kPbnbv,
    "pbnbv: next-best-view planning (PB-NBV with our departures, docs/method.md); pbnbv-paper: PB-NBV as the "
    "paper has it; ring: a fixed turntable ring; the benchmark's "
    "baselines on PB-NBV's candidates: raycast (ray-casting information gain), random (a random candidate), "
    "oracle (the most true surface not yet seen: the yardstick, twin scans only)"};
inline constexpr ChoiceSetting<CandidateArea> kArea{
    "area", CandidateArea::kHemisphere,
    "candidate views on the hemisphere above the object, or on the full sphere (the paper's comparison: "
    "--rig free --area full)"};
inline constexpr ChoiceSetting<WhenDone> kWhenDone{
    "when-done", WhenDone::kSpread,
    "when the map has nothing left to aim at (no frontier ellipsoid; raycast: no unobserved voxel in view): "
    "stop, or spend the remaining views filling the largest gaps between the views taken"};
inline constexpr ChoiceSetting<Motion> kMotion{
    "motion", Motion::kAuto,
    "arm rig: aware (each view is reached by the quickest clear move, the turntable turning only as far as the arm "
    "cannot reach round the object or further where that is quicker, and pbnbv charges each candidate its rig time), plain (every view turned to the arm, the paper's rig), or auto (aware for every "
    "planner but pbnbv-paper)"};

// pbnbv's combined ranking (docs/method.md "Beyond the paper", departure 4; chosen on the tune half of
// the tuning set, planner.hpp CombinedRanking): the shortlist's size per term, the ray term's
// saturation length and the coarsest cell it casts through.
inline constexpr int kShortlistPerTerm = 40;
inline constexpr double kRaySaturationM = 0.24;
inline constexpr double kRayCellM = 0.03;
// Motion-aware: the rig time that one point of the combined ranking (of 3) is worth, s.
inline constexpr double kMotionSecondsPerPoint = 4.0;
inline constexpr Setting<double> kSecondsPerPoint{
    "seconds-per-point", kMotionSecondsPerPoint, 0.0, 1000.0, "s",
    "motion-aware ranking (pbnbv, --motion aware): the rig time one point of the combined score (of 3) is worth; 0: "
    "time does not enter the ranking"};

inline constexpr Setting<int> kCandidates{"candidates", 800, 1, 100000, "", "candidate views per plan (N)"};
inline constexpr Setting<int> kParallels{"parallels", 24, 1, 1000, "",
                                         "parallels the candidates lie on (alpha); at most --candidates"};
inline constexpr Setting<int> kSectors{"beta", 4, 1, 360, "", "global partitioning sectors (beta; 1: off)"};
inline constexpr Setting<int> kTMax{"tmax", 10, 1, 200, "", "most Gaussian components per ellipsoid class (T_max)"};
inline constexpr Setting<double> kWorkingDistance{"working-distance", 0.6, 0.15, 3.0, "m",
                                                  "camera to the object's bounding sphere (d_c)"};
inline constexpr Setting<double> kStopFraction{
    "stop-fraction", 0.0, 0.0, 1.0, "",
    "stop when the best view quality F falls below this times the first planned view's F (0: never; docs/scan.md says why)"};
inline constexpr Setting<int> kAlternatives{"alternatives", 5, 0, 100, "",
                                            "next-best views tried when the rig cannot reach the best"};
inline constexpr Setting<int64_t> kMixtureSeed{"seed", 1, 0, int64_t{1} << 30, "",
                                              "the Gaussian mixture's seed (k-means++ starts)"};
// The oracle's true surface samples: as many, and drawn as, the benchmark's coverage samples
// (eval/coverage.hpp CoverageParams: 10,000, seed 1).
inline constexpr Setting<int> kOracleSamples{"truth-samples", 10000, 100, 1000000, "",
                                             "surface samples on the true mesh the oracle counts (--truth-mesh)"};
inline constexpr uint64_t kOracleSeed = 1;
inline constexpr Setting<int64_t> kPlannerSeed{"seed", 1, 0, int64_t{1} << 62, "", "the random planner's seed"};

}  // namespace pbnbv
