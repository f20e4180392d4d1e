#include "bus/depth_codec.hpp"

#include <zlib.h>

#include <stdexcept>

namespace pbnbv::bus {

std::vector<uint8_t> deflate_bytes(const std::vector<uint8_t>& raw, int level) {
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<uint8_t> out(size);
  if (compress2(out.data(), &size, raw.data(), static_cast<uLong>(raw.size()), level) != Z_OK) {
    throw std::runtime_error("zlib could not compress " + std::to_string(raw.size()) + " bytes");
  }
  out.resize(size);
  return out;
}

std::vector<uint8_t> inflate_bytes(const std::vector<uint8_t>& compressed, std::size_t expected_size,
                                   std::size_t max_size, const std::string& what) {
  if (expected_size > max_size) {
    throw std::invalid_argument(what + " declares " + std::to_string(expected_size) + " bytes, more than the " +
                                std::to_string(max_size) + " allowed");
  }
  // No compressed byte inflates to more than kMaxInflateRatio bytes (the header and checksum to none).
  if (expected_size > compressed.size() * kMaxInflateRatio) {
    throw std::invalid_argument(what + " declares " + std::to_string(expected_size) + " bytes, which " +
                                std::to_string(compressed.size()) + " compressed bytes cannot inflate to");
  }
  std::vector<uint8_t> out(expected_size + 1);  // one spare byte: a longer image is an error too
  uLongf size = static_cast<uLongf>(out.size());
  const int rc = uncompress(out.data(), &size, compressed.data(), static_cast<uLong>(compressed.size()));
  if (rc != Z_OK && rc != Z_BUF_ERROR) {
    throw std::invalid_argument(what + " is not valid zlib data (" + std::to_string(compressed.size()) + " bytes: " +
                                (rc == Z_DATA_ERROR ? "corrupt" : "truncated") + ")");
  }
  if (rc == Z_BUF_ERROR || size != expected_size) {
    throw std::invalid_argument(what + " inflates to " + (rc == Z_BUF_ERROR ? "more than " + std::to_string(expected_size)
                                                                           : std::to_string(size)) +
                                " bytes, the image needs " + std::to_string(expected_size));
  }
  out.resize(size);
  return out;
}

}  // namespace pbnbv::bus
