#include "core/scan/replay_rig.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pbnbv {

namespace {

constexpr int64_t kNoOrder = std::numeric_limits<int64_t>::max();

// The last status logged before `order` (0 when none is).
std::size_t last_before(const std::vector<RecordedStatus>& s, int64_t order) {
  std::size_t at = 0;
  for (std::size_t i = 0; i < s.size() && s[i].order < order; ++i) at = i;
  return at;
}

// The statuses played for a frame exposed at `utime` and logged at `order`, commanded at
// `command_order`, before the command logged at `next_order`: the still ones from the rig's
// settling (at most kReplayBeforeFrameUs before the exposure) to kReplayAfterFrameUs after it.
StatusSpan span_of(const std::vector<RecordedStatus>& s, int64_t utime, int64_t order, int64_t command_order,
                   int64_t next_order) {
  StatusSpan span;
  span.at_frame = span.begin = last_before(s, order);
  while (span.begin > 0 && s[span.at_frame].still && s[span.begin - 1].still && s[span.begin - 1].order > command_order &&
         s[span.begin - 1].utime >= utime - kReplayBeforeFrameUs) {
    --span.begin;
  }
  std::size_t end = span.at_frame + 1;
  while (end < s.size() && s[end].order < next_order && s[end].utime <= utime + kReplayAfterFrameUs) ++end;
  span.end = end;
  return span;
}

// The statuses before the first command: the rig as the scan found it.
StatusSpan initial_span(const std::vector<RecordedStatus>& s, int64_t first_command_order) {
  StatusSpan span;
  span.at_frame = span.begin = last_before(s, first_command_order);
  while (span.begin > 0 && s[span.begin - 1].utime >= s[span.at_frame].utime - kReplayBeforeFrameUs) --span.begin;
  span.end = span.at_frame + 1;
  return span;
}

// The last command logged before `order` (nullptr when none).
const RecordedCommand* command_before(const std::vector<RecordedCommand>& c, int64_t order) {
  const RecordedCommand* last = nullptr;
  for (const RecordedCommand& x : c) {
    if (x.order < order) last = &x;
  }
  return last;
}

}  // namespace

std::vector<RecordedView> recorded_views(const RigTimeline& t) {
  if (t.arm.empty()) throw std::invalid_argument("the recording holds no ARM_STATUS");
  if (t.frames.empty()) throw std::invalid_argument("the recording holds no DEPTH_FRAME of the scan");
  std::vector<RecordedView> views;
  for (std::size_t f = 0; f < t.frames.size(); ++f) {
    const RecordedFrame& frame = t.frames[f];
    const RecordedCommand* arm = command_before(t.arm_commands, frame.order);
    if (!arm) {
      throw std::invalid_argument(fmt::format("the recording's DEPTH_FRAME at rig time {} us has no ARM_COMMAND before it",
                                              frame.utime));
    }
    // A later frame after the same command (the camera triggered again) replaces the earlier one.
    if (!views.empty() && views.back().arm_command_seq == arm->seq) views.pop_back();
    RecordedView v;
    v.frame = f;
    v.arm_command_seq = arm->seq;
    v.arm_target_rad = arm->target_rad;
    if (const RecordedCommand* tt = command_before(t.turntable_commands, frame.order)) v.turntable_target_rad = tt->target_rad[0];
    int64_t next = kNoOrder;
    for (const RecordedCommand& c : t.arm_commands) {
      if (c.order > frame.order && c.seq != arm->seq) {
        next = c.order;
        break;
      }
    }
    v.arm = span_of(t.arm, frame.utime, frame.order, arm->order, next);
    if (t.has_turntable()) v.turntable = span_of(t.turntable, frame.utime, frame.order, arm->order, next);
    views.push_back(v);
  }
  return views;
}

ReplayRig::ReplayRig(const RigTimeline& timeline) : views_(recorded_views(timeline)), has_turntable_(timeline.has_turntable()) {
  const int64_t first = timeline.arm_commands.empty() ? kNoOrder : timeline.arm_commands.front().order;
  arm_span_ = initial_span(timeline.arm, first);
  arm_at_ = arm_span_.begin;
  if (has_turntable_) {
    turntable_span_ = initial_span(timeline.turntable, first);
    turntable_at_ = turntable_span_.begin;
  }
}

ReplayRig::Statuses ReplayRig::tick() {
  Statuses s;
  s.arm = arm_at_;
  if (has_turntable_) s.turntable = turntable_at_;
  // Up to the frame until the trigger, then on to the span's end; the last one is held.
  const auto advance = [&](const StatusSpan& span, std::size_t& at) {
    const std::size_t limit = triggered_ ? span.end - 1 : span.at_frame;
    if (at < limit) ++at;
  };
  advance(arm_span_, arm_at_);
  if (has_turntable_) advance(turntable_span_, turntable_at_);
  return s;
}

void ReplayRig::enter(int view) {
  view_ = view;
  triggered_ = false;
  arm_span_ = views_[view].arm;
  arm_at_ = arm_span_.begin;
  if (has_turntable_) {
    turntable_span_ = views_[view].turntable;
    turntable_at_ = turntable_span_.begin;
  }
}

void ReplayRig::on_arm_command(int64_t seq, const Vector6d& target_rad) {
  if (seq == arm_seq_) return;  // a repeat of the command being played
  int nearest = -1;
  double nearest_rad = std::numeric_limits<double>::infinity();
  // The next recorded view first (the scan's order), then any other.
  for (std::size_t n = 0; n < views_.size(); ++n) {
    const int k = static_cast<int>((view_ + 1 + n) % views_.size());
    const double d = (views_[k].arm_target_rad - target_rad).cwiseAbs().maxCoeff();
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
  arm_fault_.clear();
  arm_fault_seq_ = -1;
  arm_seq_ = seq;
  enter(nearest);
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
  if (!has_turntable_ || view_ < 0 || turntable_seq_ != arm_seq_ || !turntable_target_) return;
  const std::optional<double>& recorded = views_[view_].turntable_target_rad;
  if (recorded && std::abs(*recorded - *turntable_target_) > kReplayTargetToleranceRad) {
    turntable_fault_ = fmt::format("TURNTABLE_COMMAND seq {}: recorded view {} was commanded to {:.6f} rad, not {:.6f}",
                                   turntable_seq_, view_ + 1, *recorded, *turntable_target_);
    turntable_fault_seq_ = turntable_seq_;
  }
}

std::optional<std::size_t> ReplayRig::on_trigger() {
  if (view_ < 0) return std::nullopt;
  triggered_ = true;
  return views_[view_].frame;
}

}  // namespace pbnbv
