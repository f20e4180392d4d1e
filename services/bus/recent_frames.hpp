#pragma once
// The last depth frames a service has heard on DEPTH_FRAME and DEPTH_FRAME_RESENT (the camera
// service sends a frame again with a repeated answer, for a subscriber that lost it), found by the
// camera's frame number: the mapping service integrates a view's frame, the registration service
// writes it to DIR/depth/. A frame sent again is kept once.
#include <cstddef>
#include <cstdint>
#include <deque>

#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "pbnbv/depth_frame_t.hpp"

namespace pbnbv::bus {

class RecentFrames {
 public:
  // Subscribes `bus` to both channels; keeps the `kept` frames heard last.
  RecentFrames(Bus& bus, std::size_t kept) : kept_(kept) {
    for (const char* channel : {channels::kDepthFrame, channels::kDepthFrameResent}) {
      bus.subscribe<depth_frame_t>(channel, [this](const depth_frame_t& f) { keep(f); });
    }
  }
  RecentFrames(const RecentFrames&) = delete;  // the subscriptions hold `this`
  RecentFrames& operator=(const RecentFrames&) = delete;

  // The frame numbered `seq`, or null when it has not come (or was pushed out).
  const depth_frame_t* find(int64_t seq) const {
    for (const auto& f : frames_) {
      if (f.seq == seq) return &f;
    }
    return nullptr;
  }

 private:
  void keep(const depth_frame_t& f) {
    if (find(f.seq)) return;  // sent again: kept already
    frames_.push_back(f);
    if (frames_.size() > kept_) frames_.pop_front();
  }

  std::size_t kept_;
  std::deque<depth_frame_t> frames_;
};

}  // namespace pbnbv::bus
