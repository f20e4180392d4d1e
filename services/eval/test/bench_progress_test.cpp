// The benchmark's progress lines: the time-left estimate, durations, and the live block redrawn
// in place on a terminal (ANSI cursor-up and erase-line) or plain lines off one.
#include "eval/bench_progress.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace pbnbv::eval {
namespace {

TEST(BenchProgress, TimeLeftFromTheTimePerView) {
  // View 3 of 10 after 50 s: 50 / 2.5 = 20 s per view, 7.5 views to go: 150 s.
  EXPECT_DOUBLE_EQ(*scan_time_left_s(3, 10, 50.0), 150.0);
  // View 1 of 1 after 10 s: 20 s per view, half a view to go.
  EXPECT_DOUBLE_EQ(*scan_time_left_s(1, 1, 10.0), 10.0);
  EXPECT_FALSE(scan_time_left_s(0, 10, 5.0).has_value());   // no view yet
  EXPECT_FALSE(scan_time_left_s(11, 10, 5.0).has_value());  // beyond the budget
}

TEST(BenchProgress, Durations) {
  EXPECT_EQ(duration_text(0), "0:00");
  EXPECT_EQ(duration_text(65.4), "1:05");
  EXPECT_EQ(duration_text(3599), "59:59");
  EXPECT_EQ(duration_text(3600 + 5 * 60 + 10), "1 h 05 min");
  EXPECT_EQ(scan_progress_line("bunny - pbnbv", 3, 10, 50), "bunny - pbnbv: view 3/10, 0:50 elapsed, about 2:30 left");
  EXPECT_EQ(scan_progress_line("bunny - pbnbv", 0, 10, 4), "bunny - pbnbv: starting, 0:04 elapsed");
}

TEST(BenchProgress, LiveBlockIsRedrawnInPlaceOnATerminal) {
  std::ostringstream os;
  {
    LiveLines live(os, true);
    live.update({"a: view 1/10", "bench: 0 of 2"});
    live.event("b started");  // erases the two lines, prints the event, redraws them
    live.update({"a: view 2/10", "bench: 0 of 2"});
  }  // the block is erased at the end
  const std::string up = "\x1b[1A\x1b[2K";
  const std::string want = "a: view 1/10\nbench: 0 of 2\n" + up + up + "\rb started\na: view 1/10\nbench: 0 of 2\n" + up +
                           up + "\ra: view 2/10\nbench: 0 of 2\n" + up + up + "\r";
  EXPECT_EQ(os.str(), want);
  // Off a terminal: events only, as plain lines.
  std::ostringstream plain;
  {
    LiveLines live(plain, false);
    live.update({"a: view 1/10"});
    live.event("b started");
  }
  EXPECT_EQ(plain.str(), "b started\n");
}

}  // namespace
}  // namespace pbnbv::eval
