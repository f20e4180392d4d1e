// The reply caches evict the oldest entry, whatever its key; the latest-per-scan store keeps each
// scan's newest message.
#include "bus/reply_cache.hpp"

#include <gtest/gtest.h>

#include <cstdint>
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
  int64_t request_id = 7;
};
}  // namespace

// Two kept per scan, by arrival: a map claiming view 1000 or 2^31 - 1 is refused, one claiming
// view 999 is kept but does not push out the map of view 1 that arrives after it.
TEST(RecentPerScan, AForgedLaterIterationDoesNotPushOutTheMapARequestWillAskFor) {
  RecentPerScan<Map> maps(2, 999, 4);
  EXPECT_TRUE(maps.offer({"bunny", 0}));
  EXPECT_FALSE(maps.offer({"bunny", 2147483647}));
  EXPECT_FALSE(maps.offer({"bunny", 1000}));
  EXPECT_FALSE(maps.offer({"bunny", -1}));
  EXPECT_TRUE(maps.offer({"bunny", 999}));  // forged, in range
  EXPECT_TRUE(maps.offer({"bunny", 1}));
  ASSERT_NE(maps.find("bunny", 1, 7), nullptr);
  EXPECT_NE(maps.find("bunny", 999, 7), nullptr);
  EXPECT_EQ(maps.find("bunny", 0, 7), nullptr) << "the oldest arrival went";
  for (int k = 0; k < 20; ++k) maps.offer({"bunny", 1});  // repeats replace, push nothing out
  EXPECT_NE(maps.find("bunny", 999, 7), nullptr);
  EXPECT_EQ(maps.find("bunny", 2, 7), nullptr);
}

// Four scans kept, the one heard from longest ago dropped first; hearing a scan again keeps it.
TEST(RecentPerScan, KeepsTheScansHeardFromMostRecently) {
  RecentPerScan<Map> maps(2, 999, 4);
  maps.offer({"bunny", 0});
  maps.offer({"teapot", 0});
  maps.offer({"elk", 0});
  maps.offer({"bunny", 1});  // bunny heard again
  maps.offer({"cow", 0});
  maps.offer({"dino", 0});  // a fifth scan: teapot, heard longest ago, goes
  EXPECT_EQ(maps.find("teapot", 0, 7), nullptr);
  EXPECT_NE(maps.find("bunny", 0, 7), nullptr);
  EXPECT_NE(maps.find("bunny", 1, 7), nullptr);
  EXPECT_NE(maps.find("elk", 0, 7), nullptr);
  EXPECT_NE(maps.find("dino", 0, 7), nullptr);
}

// A map of the same view for another request (forged with a guessed id) is kept beside the real
// one, never in its place: a request finds the map of the id it names. (Before, kept by view
// only, the later arrival replaced the real map.)
TEST(RecentPerScan, AMapOfAnotherRequestForTheSameViewDoesNotReplaceTheRealOne) {
  RecentPerScan<Map> maps(4, 999, 4);
  maps.offer({"bunny", 1, 4100});
  maps.offer({"bunny", 1, 9999});  // forged, arrives later
  ASSERT_NE(maps.find("bunny", 1, 4100), nullptr);
  EXPECT_EQ(maps.find("bunny", 1, 4100)->request_id, 4100);
  EXPECT_EQ(maps.find("bunny", 1, 9999)->request_id, 9999);
  EXPECT_EQ(maps.find("bunny", 1, 5), nullptr);
}
