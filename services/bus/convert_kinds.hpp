#pragma once
// The planner and the ranking as the contract carries them: int8 constants of plan_request_t and
// view_plan_t, each checked on receipt (a value outside the constants is named with its field).
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/planning/kinds.hpp"
#include "core/geometry/rig_kind.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/view_plan_t.hpp"

namespace pbnbv::bus {

namespace kinds_internal {

inline constexpr std::pair<PlannerKind, int8_t> kPlanners[] = {
    {PlannerKind::kPbnbv, plan_request_t::kPlannerPbnbv},     {PlannerKind::kPbnbvPaper, plan_request_t::kPlannerPbnbvPaper},
    {PlannerKind::kRaycast, plan_request_t::kPlannerRaycast}, {PlannerKind::kRandom, plan_request_t::kPlannerRandom},
    {PlannerKind::kOracle, plan_request_t::kPlannerOracle}};
inline constexpr std::pair<Ranking, int8_t> kRankings[] = {
    {Ranking::kF, view_plan_t::kRankingF},
    {Ranking::kUnobservedVoxels, view_plan_t::kRankingUnobservedVoxels},
    {Ranking::kTrueSamples, view_plan_t::kRankingTrueSamples},
    {Ranking::kRandom, view_plan_t::kRankingRandom},
    {Ranking::kGapAngle, view_plan_t::kRankingGapAngle},
    {Ranking::kCombined, view_plan_t::kRankingCombined}};

// `value` of field `field` as its kind; throws naming the field and the constants' range.
template <class Kind, std::size_t N>
Kind from_constant(const std::pair<Kind, int8_t> (&table)[N], int8_t value, const std::string& field) {
  for (const auto& [kind, constant] : table) {
    if (constant == value) return kind;
  }
  throw std::invalid_argument(field + " = " + std::to_string(value) + " is not one of its constants (0.." +
                              std::to_string(N - 1) + ")");
}

}  // namespace kinds_internal

// The planner's constant; the ring has none (it sends no PLAN_REQUEST): std::logic_error.
inline int8_t planner_to_msg(PlannerKind k) {
  for (const auto& [kind, constant] : kinds_internal::kPlanners) {
    if (kind == k) return constant;
  }
  throw std::logic_error(std::string("planner '") + std::string(name_of(k)) + "' plans no view: it has no PLAN_REQUEST constant");
}

// The planner of a received constant; `field` names it in the error ("PLAN_REQUEST planner").
inline PlannerKind planner_from_msg(int8_t value, const std::string& field) {
  return kinds_internal::from_constant(kinds_internal::kPlanners, value, field);
}

inline int8_t ranking_to_msg(Ranking r) {
  for (const auto& [kind, constant] : kinds_internal::kRankings) {
    if (kind == r) return constant;
  }
  throw std::logic_error("a ranking without a VIEW_PLAN constant");
}

inline Ranking ranking_from_msg(int8_t value, const std::string& field) {
  return kinds_internal::from_constant(kinds_internal::kRankings, value, field);
}

static_assert(static_cast<int>(TurntableChoice::kPreferred) == plan_request_t::kPreferredAzimuth &&
              static_cast<int>(TurntableChoice::kLeastTurn) == plan_request_t::kLeastTurn &&
              static_cast<int>(TurntableChoice::kLeastTurnOnGrid) == plan_request_t::kLeastTurnOnGrid &&
              move_request_t::kPreferredAzimuth == plan_request_t::kPreferredAzimuth &&
              move_request_t::kLeastTurn == plan_request_t::kLeastTurn &&
              static_cast<int>(TurntableChoice::kQuickest) == plan_request_t::kQuickest &&
              move_request_t::kLeastTurnOnGrid == plan_request_t::kLeastTurnOnGrid &&
              move_request_t::kQuickest == plan_request_t::kQuickest);

// A turntable_choice field (MOVE_REQUEST's, PLAN_REQUEST's): one of its constants, else throws naming `what`.
inline TurntableChoice turntable_choice_from_msg(int8_t v, const std::string& what) {
  if (v != plan_request_t::kPreferredAzimuth && v != plan_request_t::kLeastTurn && v != plan_request_t::kLeastTurnOnGrid &&
      v != plan_request_t::kQuickest) {
    throw std::invalid_argument(what + " = " + std::to_string(v) +
                                " is not one of its constants (0 preferred azimuth, 1 least turn, 2 least turn on the grid, "
                                "3 quickest move)");
  }
  return static_cast<TurntableChoice>(v);
}

}  // namespace pbnbv::bus
