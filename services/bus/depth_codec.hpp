#pragma once
// The depth image's bytes on DEPTH_FRAME, raw or zlib-compressed (depth_frame_t::encoding).
// Compression is what lets a frame survive a lossy bus: a 1280x720 frame of the twin is 1.8 MB
// raw (28 UDP fragments: at 1 % packet loss a quarter of the frames are lost) and about 85 kB
// compressed at level 1 in about 6 ms (2 fragments).
#include <cstdint>
#include <string>
#include <vector>

namespace pbnbv::bus {

// zlib (RFC 1950) at `level` (1 fastest .. 9 smallest).
std::vector<uint8_t> deflate_bytes(const std::vector<uint8_t>& raw, int level = 1);

// zlib inflates at most 1032 bytes from one compressed byte (258-byte matches in 2 bits).
inline constexpr std::size_t kMaxInflateRatio = 1032;

// The raw bytes back; throws std::invalid_argument naming `what` when the data is not zlib or
// does not inflate to exactly `expected_size` bytes. Nothing is allocated for a declared size over
// `max_size` (the contract's largest image) or more than the compressed bytes could ever inflate
// to: a bomb, or a small frame claiming a large image, is refused before any allocation.
std::vector<uint8_t> inflate_bytes(const std::vector<uint8_t>& compressed, std::size_t expected_size,
                                   std::size_t max_size, const std::string& what);

}  // namespace pbnbv::bus
