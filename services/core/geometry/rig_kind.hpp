#pragma once
// Which kind of rig a scan runs on, and the rig option of every program that works with a rig.
// Here, below the rig's model and kinematics (core/rig/rig.hpp), so that what only names a rig
// kind (the scan's settings, the coordinator) does not depend on them.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/base/setting.hpp"

namespace pbnbv {

enum class RigKind {
  kArm,   // 6-axis arm + turntable; object on the turntable
  kFree,  // no arm: a 6-DOF virtual gantry puts the camera anywhere; object floats at origin
};
template <>
struct EnumNames<RigKind> {
  static constexpr std::string_view what = "rig kind";
  static constexpr std::array<NamedValue<RigKind>, 2> names{{{RigKind::kArm, "arm"}, {RigKind::kFree, "free"}}};
};
// "arm" | "free"; parse_rig_kind throws naming the value and the choices.
inline std::string to_string(RigKind kind) { return std::string(name_of(kind)); }
inline RigKind parse_rig_kind(const std::string& s) { return parse_name<RigKind>(s); }
// How the reachability check chooses a view's turntable angle (arm rig).
//  kPreferred: the angle bringing the view to the arm's preferred azimuth, or when that fails the
//    nearest of azimuth offsets +-15 ... +-90 deg (the paper's rig: the turntable turns every view
//    to the arm).
//  kLeastTurn: the same angles and, when the view lies within +-90 deg of the preferred azimuth as
//    the turntable stands, the current angle, tried in order of how far the turntable turns: the
//    arm reaches round the object as far as it can before the turntable turns (the turntable,
//    60 deg/s against the arm's 180-360 deg/s, is the slow part of a move). A single view's solve
//    (the motion executor's) then bisects the 15 deg step nearer to where the turntable stands
//    three times: the turn stops within 1.9 deg of the least clear one (a batch, the view scorer's
//    ranking, keeps the grid's angle).
//  kLeastTurnOnGrid: kLeastTurn without the bisection, a single view's solve too: the executor's
//    rule before the least turn was narrowed, kept so that a scan recorded then replays as it was moved
//    (ScanSettings::least_turn, settings.json planning.least_turn).
//  kQuickest: kLeastTurn's angles in the same order, but the clear solution whose move takes the
//    rig least time (core/rig move_s: the arm and the turntable at once, the slower decides) wins,
//    not the first. The least turn is best when the turntable is the slower part; when the arm is
//    (a long swing of its base round the object), turning the turntable further shortens the
//    arm's part. The search stops at the first angle whose turn alone takes longer than the best
//    move found, and a solution that cannot beat it is not checked for collisions. A single view's
//    solve narrows the least clear turn as kLeastTurn does, and keeps the narrowed one when it is
//    no slower.
enum class TurntableChoice : uint8_t { kPreferred, kLeastTurn, kLeastTurnOnGrid, kQuickest };

// The motion executor's rule for a view's turntable angle, as a scan's settings record it: the
// quickest move (kQuickest, the default), the least turn narrowed (kLeastTurn: scans recorded
// before the quickest move), or on the grid alone (kLeastTurnOnGrid: scans recorded before the
// least turn was narrowed).
enum class LeastTurn : uint8_t { kNarrowed, kGrid, kQuickest };
template <>
struct EnumNames<LeastTurn> {
  static constexpr std::string_view what = "least turn";
  static constexpr std::array<NamedValue<LeastTurn>, 3> names{
      {{LeastTurn::kNarrowed, "narrowed"}, {LeastTurn::kGrid, "grid"}, {LeastTurn::kQuickest, "quickest"}}};
};

// The rig option of every program that works with a rig (pbnbv scan, motion, camera, scorer, twin).
inline constexpr ChoiceSetting<RigKind> kRig{"rig", RigKind::kArm,
                                             "arm + turntable, or a free-flying camera (the paper's setup)"};

}  // namespace pbnbv
