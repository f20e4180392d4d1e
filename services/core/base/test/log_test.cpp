// The log limiter: the first line of a kind is printed, a flood within the window is counted and
// reported once, a quiet kind prints again.
#include "core/base/log.hpp"

#include <gtest/gtest.h>

using namespace pbnbv;

TEST(LogLimiter, AFloodIsOneLineAndOneCount) {
  LogLimiter limit(10.0);
  EXPECT_TRUE(limit.allow("CLOUD rejected", 0.0));
  for (int i = 1; i <= 57; ++i) EXPECT_FALSE(limit.allow("CLOUD rejected", 0.1 * i));  // 0.1 .. 5.7 s
  EXPECT_TRUE(limit.allow("VOXEL_MAP rejected", 1.0));  // another kind has its own window
  EXPECT_EQ(limit.suppressed(), 57);
  EXPECT_TRUE(limit.take_due(9.9).empty());  // the window is not over
  const auto due = limit.take_due(10.0);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due.at("CLOUD rejected"), 57);
  EXPECT_EQ(limit.suppressed(), 0);
  // Reported at 10 s, a new window began there: a line at 15 s is counted, one at 20.5 s after
  // its report prints.
  EXPECT_FALSE(limit.allow("CLOUD rejected", 15.0));
  EXPECT_EQ(limit.take_due(20.0).at("CLOUD rejected"), 1);
  EXPECT_TRUE(limit.allow("CLOUD rejected", 30.5));
}

TEST(LogLimiter, AQuietKindPrintsEveryLine) {
  LogLimiter limit(10.0);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(limit.allow("rare", 10.0 * i));
  EXPECT_EQ(limit.suppressed(), 0);
}
