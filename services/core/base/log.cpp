#include "core/base/log.hpp"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>

namespace pbnbv {
namespace {
std::string g_name = "pbnbv";
std::mutex g_mutex;

void emit(const char* level, const std::string& message) {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const int ms = static_cast<int>(
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000);
  std::tm tm{};
  localtime_r(&t, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%H:%M:%S", &tm);
  std::lock_guard<std::mutex> lock(g_mutex);
  std::fprintf(stderr, "%s.%03d [%s] %s%s\n", stamp, ms, g_name.c_str(), level, message.c_str());
  std::fflush(stderr);
}
}  // namespace

void set_log_name(const std::string& program) { g_name = program; }
void log_info(const std::string& message) { emit("", message); }
void log_warn(const std::string& message) { emit("warning: ", message); }
void log_error(const std::string& message) { emit("error: ", message); }

}  // namespace pbnbv

namespace pbnbv {

bool LogLimiter::allow(const std::string& kind, double now_s) {
  auto it = kinds_.find(kind);
  if (it == kinds_.end() || (now_s - it->second.window_start_s >= window_s_ && it->second.suppressed == 0)) {
    kinds_[kind] = Kind{now_s, 0};
    return true;
  }
  ++it->second.suppressed;
  return false;
}

std::map<std::string, long> LogLimiter::take_due(double now_s) {
  std::map<std::string, long> due;
  for (auto& [kind, k] : kinds_) {
    if (k.suppressed > 0 && now_s - k.window_start_s >= window_s_) {
      due[kind] = k.suppressed;
      k = Kind{now_s, 0};
    }
  }
  return due;
}

long LogLimiter::suppressed() const {
  long n = 0;
  for (const auto& [kind, k] : kinds_) n += k.suppressed;
  return n;
}

}  // namespace pbnbv
