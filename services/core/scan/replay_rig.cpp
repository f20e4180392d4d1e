#include "core/scan/replay_rig.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>

namespace pbnbv {

namespace {

// The last status logged before `order` (0 when none is).
std::size_t last_before(const std::vector<RecordedStatus>& s, int64_t order) {
  std::size_t at = 0;
  for (std::size_t i = 0; i < s.size() && s[i].order < order; ++i) at = i;
  return at;
}

// The recording's status period: the median interval between consecutive readings (rig time).
int64_t status_period_us(const std::vector<RecordedStatus>& s) {
  std::vector<int64_t> d;
  for (std::size_t i = 1; i < s.size(); ++i) {
    if (s[i].utime > s[i - 1].utime) d.push_back(s[i].utime - s[i - 1].utime);
  }
  if (d.empty()) return std::numeric_limits<int64_t>::max();
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

// The statuses played for a frame exposed at `utime` and logged at `order`, the rig following
// command `seq`: the still ones from the rig's settling (at most kReplayBeforeFrameUs before the
// exposure) to kReplayAfterFrameUs after it, while the rig followed that command.
StatusSpan span_of(const std::vector<RecordedStatus>& s, int64_t utime, int64_t order, int64_t seq) {
  StatusSpan span;
  span.at_frame = span.begin = last_before(s, order);
  while (span.begin > 0 && s[span.at_frame].still && s[span.begin - 1].still && s[span.begin - 1].command_seq == seq &&
         s[span.begin - 1].utime >= utime - kReplayBeforeFrameUs) {
    --span.begin;
  }
  if (!s[span.at_frame].still || s[span.at_frame].command_seq != seq) {
    // The still readings before the exposure were lost: the first still one after it stands for them.
    for (std::size_t j = span.at_frame + 1; j < s.size() && s[j].utime <= utime + kReplayAfterFrameUs; ++j) {
      if (s[j].still && s[j].command_seq == seq && s[j].order > order) {
        span.begin = span.at_frame = j;
        span.restamp_utime = utime;
        break;
      }
    }
  }
  std::size_t end = span.at_frame + 1;
  while (end < s.size() && s[end].command_seq == seq && s[end].utime <= utime + kReplayAfterFrameUs) ++end;
  span.end = end;
  int64_t nearest_us = std::numeric_limits<int64_t>::max();
  for (std::size_t i = span.begin; i < span.end; ++i) nearest_us = std::min<int64_t>(nearest_us, std::llabs(s[i].utime - utime));
  span.nearest_reading_lost = 2 * nearest_us > status_period_us(s);
  return span;
}

// The statuses before the first command: the rig as the scan found it.
StatusSpan initial_span(const std::vector<RecordedStatus>& s) {
  StatusSpan span;
  while (span.at_frame + 1 < s.size() && s[span.at_frame + 1].command_seq == s[0].command_seq) ++span.at_frame;
  span.begin = span.at_frame;
  while (span.begin > 0 && s[span.begin - 1].utime >= s[span.at_frame].utime - kReplayBeforeFrameUs) --span.begin;
  span.end = span.at_frame + 1;
  return span;
}

// The command `seq` of a list (nullptr when the log lost it).
const RecordedCommand* command_of(const std::vector<RecordedCommand>& c, int64_t seq) {
  for (const RecordedCommand& x : c) {
    if (x.seq == seq) return &x;
  }
  return nullptr;
}

// The statuses played at a detour's stop (command `seq`): from the first still one following it to
// the last one following it, held there. Empty (nullopt) when the log holds none.
std::optional<StatusSpan> stop_span(const std::vector<RecordedStatus>& s, int64_t seq) {
  std::optional<std::size_t> first, first_still, last;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i].command_seq != seq) continue;
    if (!first) first = i;
    if (!first_still && s[i].still) first_still = i;
    last = i;
  }
  if (!last) return std::nullopt;
  StatusSpan span;
  span.begin = first_still.value_or(*first);
  span.at_frame = *last;
  span.end = *last + 1;
  return span;
}

// The detour's stops commanded after log position `after` and before `before`, other than `view_seq`.
std::vector<RecordedStop> stops_between(const RigTimeline& t, int64_t after, int64_t before, int64_t view_seq) {
  std::vector<RecordedStop> stops;
  for (const RecordedCommand& c : t.arm_commands) {
    if (c.order <= after || c.order >= before || c.seq == view_seq) continue;
    if (!stops.empty() && stops.back().arm_command_seq == c.seq) continue;  // re-sent
    const std::optional<StatusSpan> arm = stop_span(t.arm, c.seq);
    if (!arm) continue;  // the log lost what the rig did: a replayed command there is refused
    RecordedStop stop;
    stop.arm_command_seq = c.seq;
    stop.arm_target_rad = c.target_rad;
    stop.arm = *arm;
    if (t.has_turntable()) {
      if (const RecordedCommand* tc = command_of(t.turntable_commands, c.seq)) stop.turntable_target_rad = tc->target_rad[0];
      if (const std::optional<StatusSpan> tt = stop_span(t.turntable, c.seq)) stop.turntable = *tt;
    }
    stops.push_back(stop);
  }
  return stops;
}

// Where in the log the arm was first commanded to `seq` (its command, or the first status
// acknowledging it when the log lost the command).
int64_t commanded_at(const RigTimeline& t, int64_t seq) {
  int64_t order = std::numeric_limits<int64_t>::max();
  for (const RecordedCommand& c : t.arm_commands) {
    if (c.seq == seq) order = std::min(order, c.order);
  }
  for (const RecordedStatus& s : t.arm) {
    if (s.command_seq == seq) {
      order = std::min(order, s.order);
      break;
    }
  }
  return order;
}

}  // namespace

std::vector<RecordedView> recorded_views(const RigTimeline& t) {
  if (t.arm.empty()) throw std::invalid_argument("the recording holds no ARM_STATUS");
  if (t.frames.empty()) throw std::invalid_argument("the recording holds no DEPTH_FRAME of the scan");
  std::vector<RecordedView> views;
  for (std::size_t f = 0; f < t.frames.size(); ++f) {
    const RecordedFrame& frame = t.frames[f];
    const RecordedStatus& arm = t.arm[last_before(t.arm, frame.order)];
    if (arm.command_seq < 0) {
      throw std::invalid_argument(fmt::format(
          "the recording's DEPTH_FRAME at rig time {} us was taken before the arm acknowledged any command", frame.utime));
    }
    // A later frame while the rig followed the same command (the camera triggered again) replaces
    // the earlier one.
    if (!views.empty() && views.back().arm_command_seq == arm.command_seq) views.pop_back();
    RecordedView v;
    v.frame = f;
    v.arm_command_seq = arm.command_seq;
    const RecordedCommand* a = command_of(t.arm_commands, arm.command_seq);
    v.arm_target_rad = a ? a->target_rad : arm.commanded_rad;
    v.arm = span_of(t.arm, frame.utime, frame.order, arm.command_seq);
    if (t.has_turntable()) {
      const RecordedStatus& tt = t.turntable[last_before(t.turntable, frame.order)];
      if (const RecordedCommand* c = command_of(t.turntable_commands, tt.command_seq)) v.turntable_target_rad = c->target_rad[0];
      v.turntable = span_of(t.turntable, frame.utime, frame.order, tt.command_seq);
    }
    const int64_t previous_frame = views.empty() ? -1 : t.frames[views.back().frame].order;
    v.stops = stops_between(t, previous_frame, commanded_at(t, v.arm_command_seq), v.arm_command_seq);
    views.push_back(v);
  }
  return views;
}

ReplayRig::ReplayRig(const RigTimeline& timeline) : views_(recorded_views(timeline)), has_turntable_(timeline.has_turntable()) {
  arm_span_ = initial_span(timeline.arm);
  arm_at_ = arm_span_.begin;
  if (has_turntable_) {
    turntable_span_ = initial_span(timeline.turntable);
    turntable_at_ = turntable_span_.begin;
  }
}

ReplayRig::Statuses ReplayRig::tick() {
  Statuses s;
  s.arm = arm_at_;
  if (has_turntable_) s.turntable = turntable_at_;
  const auto restamped = [&](const StatusSpan& span, std::size_t at) {
    return !triggered_ && at == span.at_frame ? span.restamp_utime : std::nullopt;
  };
  s.arm_utime = restamped(arm_span_, arm_at_);
  if (has_turntable_) s.turntable_utime = restamped(turntable_span_, turntable_at_);
  // Up to the frame until the trigger, then on to the span's end; the last one is held.
  const auto advance = [&](const StatusSpan& span, std::size_t& at) {
    const std::size_t limit = triggered_ ? span.end - 1 : span.at_frame;
    if (at < limit) ++at;
  };
  advance(arm_span_, arm_at_);
  if (has_turntable_) advance(turntable_span_, turntable_at_);
  return s;
}

void ReplayRig::play(const StatusSpan& arm, const StatusSpan& turntable, std::optional<double> turntable_target) {
  triggered_ = false;
  arm_span_ = arm;
  arm_at_ = arm_span_.begin;
  if (has_turntable_) {
    turntable_span_ = turntable;
    turntable_at_ = turntable_span_.begin;
  }
  expected_turntable_rad_ = turntable_target;
}

void ReplayRig::enter(int view) {
  view_ = view;
  stop_ = -1;
  play(views_[view].arm, views_[view].turntable, views_[view].turntable_target_rad);
}

void ReplayRig::on_arm_command(int64_t seq, const Vector6d& target_rad) {
  if (seq == arm_seq_) return;  // a repeat of the command being played
  const auto away = [&](const Vector6d& recorded) { return (recorded - target_rad).cwiseAbs().maxCoeff(); };
  // A stop of the next view's detour, after the one being played.
  int stop = -1;
  if (view_ + 1 < static_cast<int>(views_.size())) {
    const std::vector<RecordedStop>& stops = views_[view_ + 1].stops;
    for (int k = stop_ + 1; k < static_cast<int>(stops.size()) && stop < 0; ++k) {
      if (away(stops[k].arm_target_rad) <= kReplayTargetToleranceRad) stop = k;
    }
  }
  if (stop >= 0) {
    const RecordedStop& s = views_[view_ + 1].stops[stop];
    stop_ = stop;
    play(s.arm, s.turntable, s.turntable_target_rad);
  } else {
    int nearest = -1;
    double nearest_rad = std::numeric_limits<double>::infinity();
    // The next recorded view first (the scan's order), then any other.
    for (std::size_t n = 0; n < views_.size(); ++n) {
      const int k = static_cast<int>((view_ + 1 + n) % views_.size());
      const double d = away(views_[k].arm_target_rad);
      if (d < nearest_rad) {
        nearest_rad = d;
        nearest = k;
      }
      if (d <= kReplayTargetToleranceRad) {
        nearest = k;
        break;
      }
    }
    if (nearest_rad > kReplayTargetToleranceRad) {
      arm_fault_ = fmt::format("ARM_COMMAND seq {}: no recorded view was commanded to these joints (the nearest, "
                               "recorded view {}, is {:.4g} rad away)",
                               seq, nearest + 1, nearest_rad);
      arm_fault_seq_ = seq;
      return;
    }
    enter(nearest);
  }
  arm_fault_.clear();
  arm_fault_seq_ = -1;
  arm_seq_ = seq;
  check_turntable();
}

void ReplayRig::on_arm_hold(int64_t seq) {
  arm_seq_ = seq;
  arm_fault_.clear();
  arm_fault_seq_ = -1;
}

void ReplayRig::on_turntable_command(int64_t seq, double angle_rad) {
  if (seq == turntable_seq_ && turntable_target_ && *turntable_target_ == angle_rad) return;
  turntable_seq_ = seq;
  turntable_target_ = angle_rad;
  turntable_fault_.clear();
  turntable_fault_seq_ = -1;
  check_turntable();
}

void ReplayRig::check_turntable() {
  // Before the first command nothing is expected (expected_turntable_rad_ is empty).
  if (!has_turntable_ || turntable_seq_ != arm_seq_ || !turntable_target_) return;
  const std::optional<double>& recorded = expected_turntable_rad_;
  if (recorded && std::abs(*recorded - *turntable_target_) > kReplayTargetToleranceRad) {
    const std::string what = stop_ < 0 ? fmt::format("recorded view {}", view_ + 1)
                                       : fmt::format("stop {} of recorded view {}'s detour", stop_ + 1, view_ + 2);
    turntable_fault_ = fmt::format("TURNTABLE_COMMAND seq {}: {} was commanded to {:.6f} rad, not {:.6f}",
                                   turntable_seq_, what, *recorded, *turntable_target_);
    turntable_fault_seq_ = turntable_seq_;
  }
}

std::optional<std::size_t> ReplayRig::on_trigger() {
  if (view_ < 0 || stop_ >= 0) return std::nullopt;
  triggered_ = true;
  return views_[view_].frame;
}

}  // namespace pbnbv
