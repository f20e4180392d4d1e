// A child run to its end with a deadline: its exit code, the folder it runs in, and a kill at the
// deadline.
#include "process/processes.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "file_test_util.hpp"

using namespace pbnbv;

namespace {

using ProcessRun = pbnbv::testing::TempDirTest;

TEST_F(ProcessRun, ReturnsTheExitCodeAndRunsInItsFolder) {
  process::Child c;
  c.name = "sh";
  c.argv = {"sh", "-c", "pwd > where.txt; exit 3"};
  c.cwd = dir_.string();
  EXPECT_EQ(process::run(c, 10.0), 3);
  EXPECT_FALSE(c.running);
  std::ifstream in(dir_ / "where.txt");
  std::string where;
  std::getline(in, where);
  EXPECT_EQ(std::filesystem::canonical(where), std::filesystem::canonical(dir_));
}

TEST_F(ProcessRun, IsKilledAtItsDeadline) {
  process::Child c;
  c.name = "sleep";
  c.argv = {"sleep", "30"};
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(process::run(c, 0.2), 128 + 9);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(took, 5.0) << "killed at 0.2 s, not after the sleep's 30 s";
}

TEST_F(ProcessRun, AProgramThatIsNotThereExits127NamingIt) {
  process::Child c;
  c.name = "none";
  c.argv = {"pbnbv-no-such-program"};
  c.log_path = (dir_ / "log.txt").string();
  EXPECT_EQ(process::run(c, 10.0), 127);
  EXPECT_NE(process::tail_lines(c.log_path, 1).find("cannot run pbnbv-no-such-program"), std::string::npos);
}

}  // namespace
