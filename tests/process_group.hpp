#pragma once
// The programs an integration test starts, each logging to DIR/NAME.log: started one by one,
// stopped together when the test ends (SIGTERM, SIGKILL after the grace), each expected to have
// exited cleanly (the log's tail said when one did not).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "process/processes.hpp"

namespace pbnbv::testing {

class ProcessGroup {
 public:
  void start(const std::filesystem::path& log_dir, const std::string& name, const std::vector<std::string>& argv) {
    process::Child c;
    c.name = name;
    c.argv = argv;
    c.log_path = (log_dir / (name + ".log")).string();
    children_.push_back(c);
    process::start(children_.back());
  }

  void stop_expecting_clean_exits(double grace_s = 5.0) {
    process::stop_all(children_, grace_s);
    for (const auto& c : children_) {
      EXPECT_EQ(c.exit_code, 0) << c.name << " did not exit cleanly:\n" << process::tail_lines(c.log_path, 20);
    }
  }

 private:
  std::vector<process::Child> children_;
};

}  // namespace pbnbv::testing
