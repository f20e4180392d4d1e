#pragma once
// What a service keeps to answer a repeated request again instead of doing the work twice (the
// requester re-sends when an answer is lost), and the latest input of each scan a service plans
// from. One eviction policy everywhere: the oldest entry goes first.
#include <cstddef>
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
    entries_[key] = std::move(reply);
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

// The newest message of each scan by its iteration (e.g. the latest VOXEL_MAP of every scan), for
// a service that answers requests about "the map of view i". A message older than the one kept
// for its scan is ignored. Keeps the `max_scans` scans heard from most recently.
template <class Message>
class LatestPerScan {
 public:
  explicit LatestPerScan(std::size_t max_scans = 16) : scans_(max_scans) {}

  // Keeps `m` if it is the newest of its scan (m.scan_id, m.iteration). Returns whether it did.
  bool offer(const Message& m) {
    const Message* kept = scans_.find(m.scan_id);
    if (kept && kept->iteration > m.iteration) return false;
    scans_.put(m.scan_id, m);
    return true;
  }

  // The kept message of `scan_id` for `iteration`, or nullptr.
  const Message* find(const std::string& scan_id, int iteration) const {
    const Message* kept = scans_.find(scan_id);
    return kept && kept->iteration == iteration ? kept : nullptr;
  }

  // The iteration kept for the scan (-1: none): a request for an older one can never be met.
  int latest(const std::string& scan_id) const {
    const Message* kept = scans_.find(scan_id);
    return kept ? kept->iteration : -1;
  }

 private:
  ReplyCache<std::string, Message> scans_;
};

}  // namespace pbnbv::bus
