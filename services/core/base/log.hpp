#pragma once
// One logger: timestamped lines on stderr, prefixed with the program's name.
#include <map>
#include <string>

namespace pbnbv {

void set_log_name(const std::string& program);
void log_info(const std::string& message);
void log_warn(const std::string& message);
void log_error(const std::string& message);

// Keeps a flood of like lines (a malformed message on every packet, another scan's traffic)
// from drowning the log: the first line of each kind is printed, the next ones within
// `window_s` are only counted, and the count is printed once the window is over:
//   "57 more messages rejected on CLOUD (...)".
// Plain and clock-injected (now_s: seconds on any monotonic clock), so it is tested without
// waiting.
class LogLimiter {
 public:
  explicit LogLimiter(double window_s = 10.0) : window_s_(window_s) {}

  // Whether a line of `kind` may be printed now; when not, it is counted.
  bool allow(const std::string& kind, double now_s);
  // The kinds whose window is over and that had lines counted, with their counts (the caller
  // prints one line each); each of them starts a new window.
  std::map<std::string, long> take_due(double now_s);
  // Lines counted and not yet reported, over all kinds.
  long suppressed() const;
  double window_s() const { return window_s_; }

 private:
  struct Kind {
    double window_start_s = 0;
    long suppressed = 0;
  };
  double window_s_;
  std::map<std::string, Kind> kinds_;
};

}  // namespace pbnbv
