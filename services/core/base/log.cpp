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
