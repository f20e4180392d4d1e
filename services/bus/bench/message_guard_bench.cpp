// What the message guard adds to receiving a message: check_message on a full 1280 x 720 raw
// depth frame (1.8 MB), a heartbeat and an arm status, beside lcm-gen's decode of the same frame.
#include <benchmark/benchmark.h>

#include <vector>

#include "bus/message_guard.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/heartbeat_t.hpp"

using namespace pbnbv;

namespace {

template <class T>
std::vector<uint8_t> encoded(const T& m) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::vector<uint8_t> full_frame() {
  depth_frame_t f{};
  f.camera_id = "pbnbv-twin";
  f.scan_id = "bunny-0123456789abcdef";
  f.width = 1280;
  f.height = 720;
  f.fx = f.fy = 696;
  f.cx = 640;
  f.cy = 360;
  f.depth_min_m = 0.1;
  f.depth_max_m = 3;
  f.depth_unit_m = 1e-4;
  f.encoding = depth_frame_t::kEncodingRaw;
  f.depth.assign(1280 * 720 * 2, 7);
  f.num_bytes = static_cast<int32_t>(f.depth.size());
  return encoded(f);
}

template <class T>
void check(benchmark::State& state, const std::vector<uint8_t>& bytes) {
  for (auto _ : state) {
    const bus::MessageCheck c =
        bus::check_message(bytes.data(), static_cast<int64_t>(bytes.size()), T::getTypeName(), T::getHash(), "scan_id");
    benchmark::DoNotOptimize(c.ok);
  }
}

void BM_CheckFullDepthFrame(benchmark::State& state) { check<depth_frame_t>(state, full_frame()); }
BENCHMARK(BM_CheckFullDepthFrame);

void BM_DecodeFullDepthFrame(benchmark::State& state) {
  const std::vector<uint8_t> bytes = full_frame();
  for (auto _ : state) {
    depth_frame_t f{};
    benchmark::DoNotOptimize(f.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
  }
}
BENCHMARK(BM_DecodeFullDepthFrame);

void BM_CheckArmStatus(benchmark::State& state) {
  arm_status_t s{};
  s.scan_id = "bunny-0123456789abcdef";
  s.num_joints = 6;
  s.joint_names = {"a1", "a2", "a3", "a4", "a5", "a6"};
  s.joint_position_rad.assign(6, 0.1);
  s.joint_velocity_rad_s.assign(6, 0.0);
  s.joint_position_commanded_rad.assign(6, 0.1);
  check<arm_status_t>(state, encoded(s));
}
BENCHMARK(BM_CheckArmStatus);

void BM_CheckHeartbeat(benchmark::State& state) {
  heartbeat_t h{};
  h.service = "camera";
  h.scan_id = "bunny-0123456789abcdef";
  h.state = "idle";
  check<heartbeat_t>(state, encoded(h));
}
BENCHMARK(BM_CheckHeartbeat);

}  // namespace
