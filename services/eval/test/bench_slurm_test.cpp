// The Slurm side of pbnbv bench without Slurm: squeue's lines read, sbatch's command, the options.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "eval/bench_slurm.hpp"

using namespace pbnbv::eval;

TEST(SlurmQueueLines, EachTaskOfTheArrayWithItsStateAndReason) {
  // squeue -h -r --states=all -j 12 -o '%i|%T|%r' while 12's tasks 2..5 wait, and another job's.
  const std::string text =
      "12_[2-5]|PENDING|Resources\n"
      "12_0|RUNNING|None\n"
      "12_1|FAILED|NonZeroExitCode\n"
      "120_1|COMPLETED|None\n"
      "12_7|CANCELLED|None  \n"
      "garbage\n";
  const auto tasks = parse_squeue(text, "12");
  ASSERT_EQ(tasks.size(), 3u);
  EXPECT_EQ(tasks.at(0).state, "RUNNING");
  EXPECT_FALSE(tasks.at(0).ended());
  EXPECT_EQ(tasks.at(1).state, "FAILED");
  EXPECT_EQ(tasks.at(1).reason, "NonZeroExitCode");
  EXPECT_TRUE(tasks.at(1).ended());
  EXPECT_EQ(tasks.at(7).reason, "None");
  EXPECT_TRUE(tasks.at(7).ended());
  EXPECT_TRUE(parse_squeue(text, "1").empty());
  for (const char* s : {"COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY", "PREEMPTED"}) {
    EXPECT_TRUE((SlurmTaskState{s, ""}.ended())) << s;
  }
  for (const char* s : {"PENDING", "RUNNING", "COMPLETING", "CONFIGURING", "SUSPENDED", "REQUEUED"}) {
    EXPECT_FALSE((SlurmTaskState{s, ""}.ended())) << s;
  }
}

TEST(SlurmSubmission, OneArrayOfNTasksWithTheGivenPartitionAccountAndTimeLimit) {
  EXPECT_EQ(sbatch_argv(SlurmSpec{}, "/b/slurm/submit-1.sh", 4, "/b/slurm", false),
            (std::vector<std::string>{"sbatch", "--parsable", "--job-name=pbnbv-bench", "--array=0-3", "--cpus-per-task=1",
                                      "--output=/b/slurm/slurm-%A_%a.out", "/b/slurm/submit-1.sh"}));
  const std::vector<std::string> a = sbatch_argv(SlurmSpec{"gpu", "lab7", "1:00:00"}, "/b/s.sh", 1, "/b", true);
  EXPECT_EQ(a[3], "--array=0-0");
  EXPECT_EQ(std::vector<std::string>(a.begin() + 6, a.end()),
            (std::vector<std::string>{"--partition=gpu", "--account=lab7", "--time=1:00:00", "--exclusive", "/b/s.sh"}));
}

TEST(SlurmSubmission, ValuesSbatchWouldNotTakeAsOneWordAreRefusedNamingTheOption) {
  for (const char* t : {"30", "1:00:00", "90:00", "2-00", "2-12:00", "1-00:00:00"}) {
    EXPECT_NO_THROW(validate(SlurmSpec{"", "", t})) << t;
  }
  const auto message = [](const SlurmSpec& s) {
    try {
      validate(s);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message(SlurmSpec{"", "", "1 hour"}).rfind("--time-limit '1 hour': one word", 0), 0u);
  EXPECT_EQ(message(SlurmSpec{"", "", "1h"}).rfind("--time-limit '1h': minutes, M:S, H:M:S", 0), 0u);
  EXPECT_EQ(message(SlurmSpec{"a;rm -rf /", "", ""}).rfind("--partition 'a;rm -rf /': one word", 0), 0u);
  EXPECT_EQ(message(SlurmSpec{"", "it's", ""}).rfind("--account 'it's': one word", 0), 0u);
  EXPECT_EQ(message(SlurmSpec{std::string(101, 'p'), "", ""}), "--partition: at most 100 characters, not 101");
}
