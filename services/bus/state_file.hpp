#pragma once
// What a service keeps in the scan's folder so that, killed and restarted, it continues where it
// was: an LCM message (its last answer) written atomically, and read back with its scan checked.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "bus/message_guard.hpp"
#include "core/io/json.hpp"

namespace pbnbv::bus {

// Writes `msg` LCM-encoded to `path` (temporary file + rename: a reader never sees half of it).
template <class T>
void save_message(const T& msg, const std::string& path) {
  std::string bytes(static_cast<std::size_t>(msg.getEncodedSize()), '\0');
  if (msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) {
    throw std::runtime_error("cannot encode " + std::string(T::getTypeName()) + " for " + path);
  }
  write_text_atomic(bytes, path);
}

// The message saved at `path`, or none when there is no such file; throws naming the file when it
// does not decode as T.
template <class T>
std::optional<T> load_message(const std::string& path) {
  if (!std::filesystem::exists(path)) return std::nullopt;
  const std::string bytes = read_text(path);
  T msg;
  std::string why;
  if (!decode_checked(path, bytes.data(), static_cast<int64_t>(bytes.size()), &msg, &why)) {
    throw std::invalid_argument(path + " does not hold a " + std::string(T::getTypeName()) + " (" + why + ")");
  }
  return msg;
}

}  // namespace pbnbv::bus
