#pragma once
// The check every received or logged message passes before a generated decoder sees it.
// lcm-gen's decoders size their vectors and strings from the counts inside the message before
// anything has checked them: a 100-byte packet claiming a 2 GB depth image makes every subscriber
// allocate 2 GB. check_message walks the encoding with the contract's schema (message_schema.hpp)
// without allocating from it: the type hash, the message's size against its type's limit, every
// string length and array count against the bytes that remain and against the contract's limits.
// It also finds the scan id, so a message of another scan is dropped without being decoded.
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>

#include "core/geometry/camera_options.hpp"

namespace pbnbv::bus {

// The largest depth image the contract allows, pixels (core/geometry/camera_options.hpp):
// CameraIntrinsics::validate holds every camera to it; here it bounds a DEPTH_FRAME's image, a
// cloud's points and the bytes of both.
inline constexpr int64_t kMaxFramePixels = kMaxImagePixels;

// How large a message of each type may be. The defaults follow the contract; a process that knows
// its camera may lower max_frame_pixels.
struct DecodeLimits {
  int64_t max_frame_pixels = kMaxFramePixels;

  // The most bytes a message of `type_name` may take on the wire.
  int64_t max_message_bytes(std::string_view type_name) const;
  // The most elements member `field` of struct `type_name` may hold (-1: no limit but the
  // bytes that remain).
  int64_t max_elements(std::string_view type_name, std::string_view field) const;
};

struct MessageCheck {
  bool ok = false;
  std::string reason;      // when not ok: what is wrong, naming the type, field and numbers
  bool has_scope = false;  // the type has the scope field asked for
  std::string_view scope;  // that string's bytes, inside the checked buffer
};

// Checks that `size` bytes at `data` are a well-formed `type_name` whose 8-byte hash is
// `expected_hash` (T::getHash()), that lcm-gen's decoder can read without allocating beyond the
// message's own size and the limits. `scope_field` names a top-level string member to return
// ("scan_id"; "" for none). Never throws for any bytes; allocates only for the reason.
MessageCheck check_message(const void* data, int64_t size, std::string_view type_name, int64_t expected_hash,
                           std::string_view scope_field = "", const DecodeLimits& limits = DecodeLimits{});

// check_message, then T's decoder when the check passes: true with *msg filled, or false with
// `*why` saying what was wrong ("DEPTH_FRAME: depth_frame_t.depth claims 2147483647 bytes, 84
// remain"; `what` names the channel or the file). Never throws.
template <class T>
bool decode_checked(const std::string& what, const void* data, int64_t size, T* msg, std::string* why = nullptr,
                    const DecodeLimits& limits = DecodeLimits{}) {
  const MessageCheck c = check_message(data, size, T::getTypeName(), T::getHash(), "", limits);
  if (!c.ok) {
    if (why) *why = what + ": " + c.reason;
    return false;
  }
  try {
    if (msg->decode(data, 0, static_cast<int>(size)) >= 0) return true;
  } catch (const std::exception& e) {
    if (why) *why = what + ": " + T::getTypeName() + " does not decode (" + e.what() + ")";
    return false;
  }
  if (why) *why = what + ": " + T::getTypeName() + " does not decode";
  return false;
}

}  // namespace pbnbv::bus
