#pragma once
// The benchmark's progress on a terminal: one line per running scan (object, planner, view k/N,
// elapsed, an estimate of the time left), redrawn in place under the plain event lines (started,
// done, failed); off a terminal, plain lines only.
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace pbnbv::eval {

// Seconds left for a scan on view k of n (k in progress, 1-based) after elapsed_s: the time per
// view so far, elapsed / (k - 0.5), times the n - k + 0.5 views to go. None before view 1.
std::optional<double> scan_time_left_s(int k, int n, double elapsed_s);

// "1:05" (minutes:seconds) below an hour, "1 h 05 min" above.
std::string duration_text(double s);

// "bunny - pbnbv: view 3/10, 0:50 elapsed, about 2:30 left".
std::string scan_progress_line(const std::string& name, int k, int n, double elapsed_s);

// A block of lines kept at the bottom of a terminal: event lines go above it, update() redraws
// it in place (ANSI: cursor up, erase line). With live false, event lines only and update() does
// nothing.
class LiveLines {
 public:
  LiveLines(std::ostream& os, bool live) : os_(os), live_(live) {}
  ~LiveLines();
  void event(const std::string& line);
  void update(const std::vector<std::string>& lines);
  bool live() const { return live_; }

 private:
  void erase();
  std::ostream& os_;
  bool live_;
  std::vector<std::string> shown_;
};

}  // namespace pbnbv::eval
