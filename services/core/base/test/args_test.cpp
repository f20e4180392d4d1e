#include "core/base/args.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

using namespace pbnbv;

TEST(Args, ParsesValuesAndNamesBadOnes) {
  const char* argv[] = {"prog", "--views", "5", "--size=0.25", "--up", "y", "--offset", "-0.5", "--no-log"};
  Args a(9, const_cast<char**>(argv));
  EXPECT_EQ(a.integer("views", 8, 1, 100), 5);
  EXPECT_DOUBLE_EQ(a.num("size", 0.3, 0.01, 1), 0.25);
  EXPECT_EQ(a.str("up", "z"), "y");
  EXPECT_DOUBLE_EQ(a.num("offset", 0, -1, 1), -0.5);
  EXPECT_TRUE(a.flag("no-log"));
  EXPECT_NO_THROW(a.reject_unknown());
  const char* bad[] = {"prog", "--views", "five", "--veiws", "3"};
  Args b(5, const_cast<char**>(bad));
  try {
    b.integer("views", 8, 1, 100);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--views"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("five"), std::string::npos);
  }
  try {
    b.reject_unknown();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--veiws"), std::string::npos);
  }
  const char* range[] = {"prog", "--size", "7"};
  Args c(3, const_cast<char**>(range));
  EXPECT_THROW(c.num("size", 0.3, 0.01, 2.0), std::invalid_argument);
}
