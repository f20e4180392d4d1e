// The one number formatter: exact text reads back as the same double; fixed decimals round.
#include "core/base/format.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

using namespace pbnbv;

TEST(Format, ExactIsTheShortestTextThatReadsBack) {
  EXPECT_EQ(exact(0.1), "0.1");
  EXPECT_EQ(exact(0.03), "0.03");
  EXPECT_EQ(exact(-2.0), "-2");
  EXPECT_EQ(exact(1.0 / 3.0), "0.3333333333333333");
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  for (int i = 0; i < 1000; ++i) {
    const double x = u(rng);
    EXPECT_EQ(std::strtod(exact(x).c_str(), nullptr), x) << exact(x);
  }
}

TEST(Format, FixedAndViewFiles) {
  EXPECT_EQ(fixed(1.0 / 3.0, 3), "0.333");
  EXPECT_EQ(fixed(99.96, 1), "100.0");
  EXPECT_EQ(fixed(2.5, 0), "2");  // the binary value is exact: round half to even
  EXPECT_EQ(view_file(0, "ply"), "view_001.ply");  // files count views from 1
  EXPECT_EQ(view_file(3, "ply"), "view_004.ply");
  EXPECT_EQ(view_file(12, "png"), "view_013.png");
}
