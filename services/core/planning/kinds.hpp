#pragma once
// The planning-level kinds, named once (core/base/enum_names.hpp): which planner chooses the
// views, where the candidate views lie, and what a planner does when nothing is left to aim at.
// Text only at the edges (options, settings.json / summary.json, PLAN_REQUEST's planner string).
#include <array>
#include <cstdint>

#include "core/base/enum_names.hpp"
#include "core/mapping/map_options.hpp"

namespace pbnbv {

enum class PlannerKind : uint8_t {
  kPbnbv,    // next-best-view planning: PB-NBV with our departures (docs/method.md "Beyond the
             // paper"): F, the gap to the views taken and rays through the map rank a shortlist,
             // the partition applies only to registered views, the face-neighbour frontier
  kRaycast,  // baseline: the candidate whose rays reveal the most unobserved voxels
  kRandom,   // baseline: a uniformly random candidate
  kRing,     // fixed views on a turntable ring (no planning step)
  kOracle,   // the benchmark's yardstick: the candidate that sees the most true surface not yet
             // seen (needs the object's true mesh: twin scans only)
  kPbnbvPaper,  // PB-NBV exactly as the paper describes it (its table and ablations)
};

// Candidate views on the whole sphere around B, or on the hemisphere above its centre.
enum class CandidateArea : uint8_t { kHemisphere, kFullSphere };

// Nothing left to aim at (PB-NBV: no frontier ellipsoid; raycast: no unobserved voxel in view):
// stop, or spend the remaining views on the candidates farthest from every view taken.
enum class WhenDone : uint8_t { kStop, kSpread };

// How the arm rig's moves are chosen for what they cost (`--motion`): kAware, each view's
// turntable angle and arm configuration are the quickest clear move's (core/rig
// TurntableChoice::kQuickest: the turntable turns only as far as the arm cannot reach round the
// object, or further when that shortens the arm's part); kPlain, the view is turned to the arm's preferred azimuth every time (the paper's rig); kAuto,
// aware for every planner but pbnbv-paper (kept as the paper has it).
enum class Motion : uint8_t { kAuto, kAware, kPlain };

// What a plan ranks its candidates by, i.e. what the quality of its chosen view and alternatives
// means: PB-NBV's F in pixels, ray casting's unobserved voxels, the oracle's unseen true surface
// samples, nothing (random), or - for a view that fills the largest gap once nothing is left to
// aim at (WhenDone::kSpread) - the angle in degrees to the nearest view taken. VIEW_PLAN's
// `ranking` and scan.json carry it, so a reader need not tell a gap-filling plan by its reason.
// kCombined: pbnbv's combined ranking (planner.hpp CombinedRanking), the sum of three terms each
// scaled to [0, 1] over the shortlist (0 to 3).
enum class Ranking : uint8_t { kF, kUnobservedVoxels, kTrueSamples, kRandom, kGapAngle, kCombined };

template <>
struct EnumNames<PlannerKind> {
  static constexpr std::string_view what = "planner";
  static constexpr std::array<NamedValue<PlannerKind>, 6> names{{{PlannerKind::kPbnbv, "pbnbv"},
                                                                 {PlannerKind::kPbnbvPaper, "pbnbv-paper"},
                                                                 {PlannerKind::kRaycast, "raycast"},
                                                                 {PlannerKind::kRandom, "random"},
                                                                 {PlannerKind::kRing, "ring"},
                                                                 {PlannerKind::kOracle, "oracle"}}};
};

template <>
struct EnumNames<CandidateArea> {
  static constexpr std::string_view what = "candidate area";
  static constexpr std::array<NamedValue<CandidateArea>, 2> names{
      {{CandidateArea::kHemisphere, "hemi"}, {CandidateArea::kFullSphere, "full"}}};
};

template <>
struct EnumNames<Ranking> {
  static constexpr std::string_view what = "plan ranking";
  static constexpr std::array<NamedValue<Ranking>, 6> names{{{Ranking::kF, "f_px"},
                                                             {Ranking::kUnobservedVoxels, "unobserved_voxels"},
                                                             {Ranking::kTrueSamples, "true_samples"},
                                                             {Ranking::kRandom, "random"},
                                                             {Ranking::kGapAngle, "gap_deg"},
                                                             {Ranking::kCombined, "combined"}}};
};

template <>
struct EnumNames<Motion> {
  static constexpr std::string_view what = "motion";
  static constexpr std::array<NamedValue<Motion>, 3> names{
      {{Motion::kAuto, "auto"}, {Motion::kAware, "aware"}, {Motion::kPlain, "plain"}}};
};

template <>
struct EnumNames<WhenDone> {
  static constexpr std::string_view what = "when-done rule";
  static constexpr std::array<NamedValue<WhenDone>, 2> names{{{WhenDone::kStop, "stop"}, {WhenDone::kSpread, "spread"}}};
};

// The planners that ask the view scorer for each view (all but the ring).
constexpr bool uses_view_scorer(PlannerKind k) { return k != PlannerKind::kRing; }
// The PB-NBV planners (ours and the paper's): ellipsoids, view quality F, partitions.
constexpr bool is_pbnbv(PlannerKind k) { return k == PlannerKind::kPbnbv || k == PlannerKind::kPbnbvPaper; }
// The planners that need the ellipsoid fitter (PB-NBV only).
constexpr bool uses_ellipsoids(PlannerKind k) { return is_pbnbv(k); }
// The planners that need the object's true mesh (the oracle: a twin scan only).
constexpr bool uses_truth(PlannerKind k) { return k == PlannerKind::kOracle; }

// What a planner's plans rank by, unless it fills a gap (Ranking::kGapAngle); the ring plans
// nothing and counts as random.
constexpr Ranking ranking_of(PlannerKind k) {
  return k == PlannerKind::kPbnbv ? Ranking::kCombined
         : is_pbnbv(k)             ? Ranking::kF
         : k == PlannerKind::kRaycast ? Ranking::kUnobservedVoxels
         : k == PlannerKind::kOracle  ? Ranking::kTrueSamples
                                      : Ranking::kRandom;
}

// Our departures from the paper (planner pbnbv; docs/method.md "Beyond the paper"), decided here
// and nowhere else; pbnbv-paper keeps the paper's rule in each.
// 4. The combined ranking (planner.hpp CombinedRanking): F, the gap to the views taken and the rays
//    through the map rank a shortlist (the view scorer's PlanInput::grid). It replaced departure 1
//    (a weak best F counted as nothing left to aim at), which it makes unnecessary.
constexpr bool combined_ranking(PlannerKind k) { return k == PlannerKind::kPbnbv; }
// 2. The partition keeps each view next to one already taken, which the arm's registration and
//    travel need; the free rig (exact poses, no registration, no travel) does without it.
constexpr int partition_sectors(PlannerKind k, bool free_rig, int beta) {
  return k == PlannerKind::kPbnbv && free_rig ? 1 : beta;
}
// 3. Frontier: an Unknown voxel next to an Occupied one counts when an Empty voxel is among its 6
//    face neighbours (ours) or among all 26 (the paper's "spatial neighbourhood" as we read it):
//    the mapping service's --frontier-empty. Only the PB-NBV planners read the frontier, so every
//    other planner keeps pbnbv's map: a scan's map is then the same whichever of them plans it
//    (pbnbv replay --planner random).
constexpr FrontierEmpty frontier_empty(PlannerKind k) {
  return k == PlannerKind::kPbnbvPaper ? FrontierEmpty::kAllNeighbours : FrontierEmpty::kFaceNeighbours;
}

}  // namespace pbnbv
