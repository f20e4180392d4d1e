#pragma once
// What a service keeps to answer a repeated request again instead of doing the work twice (the
// requester re-sends when an answer is lost), and the latest input of each scan a service plans
// from. One eviction policy everywhere: the oldest entry goes first.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace pbnbv::bus {

// Answers by request key (e.g. scan id and request id), at most `capacity` of them; when full,
// the entry stored longest ago is dropped (not the smallest key).
template <class Key, class Reply>
class ReplyCache {
 public:
  explicit ReplyCache(std::size_t capacity) : capacity_(capacity) {
    if (capacity == 0) throw std::invalid_argument("ReplyCache: capacity must be at least 1");
  }

  // The stored answer to `key`, or nullptr.
  const Reply* find(const Key& key) const {
    const auto it = entries_.find(key);
    return it == entries_.end() ? nullptr : &it->second;
  }
  Reply* find(const Key& key) {
    const auto it = entries_.find(key);
    return it == entries_.end() ? nullptr : &it->second;
  }

  // Makes `key`'s entry the newest (the last to be dropped); nothing when it is not stored.
  void touch(const Key& key) {
    for (auto it = order_.begin(); it != order_.end(); ++it) {
      if (*it == key) {
        order_.erase(it);
        order_.push_back(key);
        return;
      }
    }
  }

  // Stores (or replaces) the answer to `key`; it becomes the newest entry.
  void put(const Key& key, Reply reply) {
    if (entries_.count(key)) {
      for (auto it = order_.begin(); it != order_.end(); ++it) {
        if (*it == key) {
          order_.erase(it);
          break;
        }
      }
    }
    entries_.insert_or_assign(key, std::move(reply));
    order_.push_back(key);
    while (order_.size() > capacity_) {
      entries_.erase(order_.front());
      order_.pop_front();
    }
  }

  std::size_t size() const { return entries_.size(); }
  void clear() {
    entries_.clear();
    order_.clear();
  }

 private:
  std::size_t capacity_;
  std::map<Key, Reply> entries_;
  std::deque<Key> order_;  // oldest first
};

// The messages of each scan a service plans from (e.g. the VOXEL_MAPs), for a service that answers
// requests about "the map of view i, answering request r": the `per_scan` received last of each
// scan, by arrival, so that a message claiming a later view (a forged iteration 2^31 - 1) cannot
// push out the one a request will ask for; iterations outside 0..max_iteration are refused. Kept
// by view and request id (Message::request_id): a message of another request for the same view (a
// forgery with a guessed id) is kept beside the real one, never in its place. Keeps the
// `max_scans` scans heard from most recently.
template <class Message>
class RecentPerScan {
 public:
  explicit RecentPerScan(std::size_t per_scan = 4, int max_iteration = 999, std::size_t max_scans = 16)
      : per_scan_(per_scan), max_iteration_(max_iteration), scans_(max_scans) {}

  // Keeps `m` as its scan's newest arrival (replacing one of the same iteration). Returns false,
  // keeping nothing, for an iteration outside 0..max_iteration.
  bool offer(const Message& m) {
    if (m.iteration < 0 || m.iteration > max_iteration_) return false;
    Kept* kept = scans_.find(m.scan_id);
    if (!kept) {
      scans_.put(m.scan_id, Kept(per_scan_));
      kept = scans_.find(m.scan_id);
    } else {
      scans_.touch(m.scan_id);
    }
    kept->put({m.iteration, m.request_id}, m);
    return true;
  }

  // The kept message of `scan_id` for `iteration` and `request_id`, or nullptr.
  const Message* find(const std::string& scan_id, int iteration, int64_t request_id) const {
    const Kept* kept = scans_.find(scan_id);
    return kept ? kept->find({iteration, request_id}) : nullptr;
  }

 private:
  using Kept = ReplyCache<std::pair<int, int64_t>, Message>;
  std::size_t per_scan_;
  int max_iteration_;
  ReplyCache<std::string, Kept> scans_;
};

}  // namespace pbnbv::bus
