#include "eval/bench_progress.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ostream>

namespace pbnbv::eval {

std::optional<double> scan_time_left_s(int k, int n, double elapsed_s) {
  if (k < 1 || n < k || !(elapsed_s >= 0)) return std::nullopt;
  return elapsed_s / (k - 0.5) * (n - k + 0.5);
}

std::string duration_text(double s) {
  const long t = std::lround(std::max(0.0, s));
  if (t < 3600) return fmt::format("{}:{:02d}", t / 60, t % 60);
  return fmt::format("{} h {:02d} min", t / 3600, (t % 3600) / 60);
}

std::string scan_progress_line(const std::string& name, int k, int n, double elapsed_s) {
  std::string line = name + ": ";
  line += k >= 1 ? fmt::format("view {}/{}, ", k, n) : "starting, ";
  line += duration_text(elapsed_s) + " elapsed";
  if (const auto left = scan_time_left_s(k, n, elapsed_s)) line += ", about " + duration_text(*left) + " left";
  return line;
}

LiveLines::~LiveLines() {
  if (live_) erase();
}

void LiveLines::erase() {
  if (shown_.empty()) return;
  for (size_t i = 0; i < shown_.size(); ++i) os_ << "\x1b[1A\x1b[2K";
  os_ << '\r';
  shown_.clear();
}

void LiveLines::event(const std::string& line) {
  if (!live_) {
    os_ << line << std::endl;
    return;
  }
  const std::vector<std::string> block = shown_;
  erase();
  os_ << line << '\n';
  update(block);
}

void LiveLines::update(const std::vector<std::string>& lines) {
  if (!live_ || lines == shown_) return;
  erase();
  for (const auto& l : lines) os_ << l << '\n';
  os_ << std::flush;
  shown_ = lines;
}

}  // namespace pbnbv::eval
