// The reply caches evict the oldest entry, whatever its key; the latest-per-scan store keeps each
// scan's newest message.
#include "bus/reply_cache.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>

using namespace pbnbv::bus;

TEST(ReplyCache, EvictsTheOldestEntryNotTheSmallestKey) {
  ReplyCache<std::pair<std::string, int>, int> cache(2);
  cache.put({"scan-b", 0}, 10);  // oldest, though "scan-b" > "scan-a"
  cache.put({"scan-a", 0}, 20);
  cache.put({"scan-a", 1}, 30);  // full: scan-b's answer goes
  EXPECT_EQ(cache.find({"scan-b", 0}), nullptr);
  ASSERT_NE(cache.find({"scan-a", 0}), nullptr);
  EXPECT_EQ(*cache.find({"scan-a", 0}), 20);
  EXPECT_EQ(*cache.find({"scan-a", 1}), 30);
  EXPECT_EQ(cache.size(), 2u);
}

TEST(ReplyCache, ReplacingAnAnswerMakesItTheNewest) {
  ReplyCache<int, int> cache(2);
  cache.put(1, 1);
  cache.put(2, 2);
  cache.put(1, 11);  // 1 is now newer than 2
  cache.put(3, 3);   // 2 goes
  EXPECT_EQ(cache.find(2), nullptr);
  EXPECT_EQ(*cache.find(1), 11);
  EXPECT_EQ(*cache.find(3), 3);
  using Small = ReplyCache<int, int>;
  EXPECT_THROW(Small(0), std::invalid_argument);
}

namespace {
struct Map {
  std::string scan_id;
  int iteration;
};
}  // namespace

TEST(LatestPerScan, KeepsEachScansNewestMapHoweverManyOtherScansSpeak) {
  LatestPerScan<Map> maps(4);
  EXPECT_TRUE(maps.offer({"bunny", 0}));
  for (int i = 0; i < 20; ++i) maps.offer({"bunny", 0});  // repeats
  EXPECT_TRUE(maps.offer({"teapot", 3}));
  EXPECT_FALSE(maps.offer({"teapot", 2}));  // older than the kept one
  ASSERT_NE(maps.find("bunny", 0), nullptr);
  EXPECT_EQ(maps.find("bunny", 1), nullptr);
  EXPECT_EQ(maps.latest("teapot"), 3);
  EXPECT_EQ(maps.latest("elk"), -1);
  EXPECT_TRUE(maps.offer({"bunny", 5}));
  EXPECT_EQ(maps.find("bunny", 0), nullptr);  // replaced by the newer map
  EXPECT_EQ(maps.latest("bunny"), 5);
}
