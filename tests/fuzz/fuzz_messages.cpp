// libFuzzer target: every message type as a subscriber receives it. The input's first byte picks
// the type (kTypes' order), the rest is the message. The message guard (check_message) runs
// first, as in the bus; when it passes, lcm-gen's decoder must decode the bytes (the guard's
// promise: a message it passes decodes without allocating beyond its own size and the
// contract's limits), then the conversions a service applies to the type (from_msg, the depth
// frame's inflation), which may refuse it with std::exception as the bus does.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "bus/bus.hpp"
#include "bus/convert.hpp"
#include "bus/convert_planning.hpp"
#include "bus/convert_rig.hpp"
#include "bus/convert_scan.hpp"
#include "bus/message_guard.hpp"
#include "fuzz_types.hpp"

namespace {

using namespace pbnbv;

// The conversion a service applies after decoding; none for the types used as they come.
template <class T>
void convert(const T&) {}
void convert(const depth_frame_t& m) { bus::from_msg(m); }
void convert(const arm_status_t& m) { bus::from_msg(m); }
void convert(const turntable_status_t& m) { bus::from_msg(m); }
void convert(const move_request_t& m) { bus::from_msg(m); }
void convert(const move_result_t& m) { bus::from_msg(m); }
void convert(const capture_request_t& m) { bus::from_msg(m); }
void convert(const point_cloud_t& m) { bus::from_msg(m); }
void convert(const registered_cloud_t& m) { bus::from_msg(m); }
void convert(const voxel_set_t& m) {
  bus::from_msg(m);
  bus::grid_from_msg(m);
}
void convert(const ellipsoid_set_t& m) { bus::from_msg(m); }
void convert(const ellipsoid_t& m) { bus::from_msg(m, "fuzz"); }
void convert(const pose_t& m) { bus::from_msg(m, "fuzz"); }
void convert(const view_plan_t& m) { bus::from_msg(m); }
void convert(const plan_request_t& m) { bus::plan_input_from_msg(m); }
void convert(const mesh_request_t& m) { bus::from_msg(m, 1000); }
void convert(const mesh_result_t& m) { bus::from_msg(m); }

template <class T>
void receive(const uint8_t* data, size_t size) {
  const bus::MessageCheck check = bus::check_message(data, static_cast<int64_t>(size), T::getTypeName(), T::getHash(),
                                                     bus::HasScanId<T>::value ? bus::scope_field<T>() : "");
  if (!check.ok) return;
  T msg;
  bool decoded = false;
  try {
    decoded = msg.decode(data, 0, static_cast<int>(size)) >= 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "the guard passed a %s that throws in the decoder: %s\n", T::getTypeName(), e.what());
    std::abort();
  }
  if (!decoded) {
    std::fprintf(stderr, "the guard passed a %s (%zu bytes) that does not decode\n", T::getTypeName(), size);
    std::abort();
  }
  if constexpr (bus::HasScanId<T>::value) {
    if (!check.has_scope || check.scope != bus::scan_of(msg)) {
      std::fprintf(stderr, "the guard read another scan id than the decoder in a %s\n", T::getTypeName());
      std::abort();
    }
  }
  try {
    convert(msg);
  } catch (const std::exception&) {  // refused, naming the field: what the bus counts as rejected
  }
}

template <class... T>
void dispatch(pbnbv::fuzz::Types<T...>, size_t which, const uint8_t* data, size_t size) {
  size_t k = 0;
  ((k++ == which ? receive<T>(data, size) : void()), ...);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  dispatch(pbnbv::fuzz::kTypes, data[0] % pbnbv::fuzz::kNumTypes, data + 1, size - 1);
  return 0;
}
