#pragma once
// The thin LCM layer every process shares: one connection, typed subscriptions that turn a
// malformed message into a logged, counted rejection (never a crash), publishing, a 1 Hz
// heartbeat, and clean shutdown on SIGINT/SIGTERM.
#include <lcm/lcm-cpp.hpp>

#include <csignal>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "bus/channels.hpp"
#include "bus/message_guard.hpp"
#include "core/base/log.hpp"
#include "core/base/signals.hpp"

namespace pbnbv {
class arm_status_t;
class turntable_status_t;
class depth_frame_t;
class heartbeat_t;
class stop_request_t;
}  // namespace pbnbv

namespace pbnbv::bus {

// Messages that carry the scan they belong to (every pipeline message, and the rig's commands,
// statuses and frames).
template <class T, class = void>
struct HasScanId : std::false_type {};
template <class T>
struct HasScanId<T, std::void_t<decltype(std::declval<const T&>().scan_id)>> : std::true_type {};

// Messages whose sender may serve no particular scan, and then leaves scan_id empty: such a
// message is for every scan. A rig driver's statuses and frames (a real driver serves one scan at
// a time and need not echo the id), and heartbeats (a service not started for one scan).
template <class T>
struct MayBeUnscoped : std::false_type {};
template <>
struct MayBeUnscoped<arm_status_t> : std::true_type {};
template <>
struct MayBeUnscoped<turntable_status_t> : std::true_type {};
template <>
struct MayBeUnscoped<depth_frame_t> : std::true_type {};
template <>
struct MayBeUnscoped<heartbeat_t> : std::true_type {};
template <>
struct MayBeUnscoped<stop_request_t> : std::true_type {};  // "": stop every scan

// The scan a message belongs to, for the filter: its scan_id; a heartbeat's is the scan its
// sender serves (its scan_id is only the last one it handled).
template <class T>
const std::string& scan_of(const T& m) {
  return m.scan_id;
}
const std::string& scan_of(const heartbeat_t& m);

// The string member scan_of reads, by name, for the filter that runs before a message is decoded
// (message_guard finds it in the encoding).
template <class T>
constexpr const char* scope_field() {
  return std::is_same_v<T, heartbeat_t> ? "serves_scan" : "scan_id";
}

// Whether a message of `scan_id` is for a process serving `scope` ("": every scan); an empty
// scan_id is for every scan when the message MayBeUnscoped.
inline bool in_scope(std::string_view scope, std::string_view scan_id, bool may_be_unscoped) {
  return scope.empty() || scan_id == scope || (may_be_unscoped && scan_id.empty());
}

// The LCM URL every process uses: LCM_DEFAULT_URL if set, else the default multicast group on
// this host (ttl=0) with an 8 MB receive buffer (lcm-logger is given the same).
std::string lcm_url();

// Microseconds since the epoch (wall clock).
int64_t now_utime();
// Seconds on a monotonic clock, for durations.
double now_s();

// Stop signals: pbnbv::install_stop_handlers() / stop_requested() (core/base/signals.hpp).

class Bus {
 public:
  // Connects to LCM_DEFAULT_URL if set, else udpm://239.255.76.67:7667?ttl=0 with a large
  // receive buffer. Throws std::runtime_error when LCM cannot start.
  explicit Bus(const std::string& service_name);
  // Publishes a last heartbeat (state "stopped") so the final counts are seen.
  ~Bus();

  // Serves the scan `scan_id` only (set once, at start; "" = every scan): a message of another
  // scan is counted as ignored and dropped before any handler sees it.
  void serve_scan(const std::string& scan_id) {
    scope_ = scan_id;
    if (scan_id_.empty()) scan_id_ = scan_id;  // the heartbeat names the scan from the start
  }
  const std::string& scope() const { return scope_; }

  // Messages of a status type (ARM_STATUS, TURNTABLE_STATUS) LCM keeps for a subscriber that is
  // busy: 4 s of statuses at 100 Hz on one channel, 0.5 s of a twin's at 20x (at most about 1 MB).
  static constexpr int kStatusQueue = 2000;
  static bool is_status_type(std::string_view type_name) {
    return type_name == "arm_status_t" || type_name == "turntable_status_t";
  }


  // Subscribes to `channel`; each message is decoded as T and passed to `handler`. A message
  // that fails the message guard (check_message: its size, type hash, string lengths and array
  // counts against its bytes and the contract's limits; before any decoding), that does not
  // decode, or whose handler throws std::exception (its validation failing), is counted as
  // rejected and dropped; a message of another scan (serve_scan) is counted as ignored and
  // dropped, its scan id read from the checked bytes so it is never decoded. Both are logged with the channel and the reason, at most one line per
  // channel and kind every 10 s (then with the count of the lines left out).
  // The statuses are queued deeper than LCM's default of 30 messages (kStatusQueue): they are small
  // and frequent, and 30 is 15 ms of a twin's statuses at 20x real time.
  template <class T>
  void subscribe(const std::string& channel, std::function<void(const T&)> handler) {
    // Owned by the LCM connection for the process's lifetime (subscriptions are never removed).
    auto* dispatch = new Dispatch<T>{this, std::move(handler)};
    lcm::Subscription* s = lcm_.subscribe(channel, &Dispatch<T>::on_message, dispatch);
    if (s && is_status_type(T::getTypeName())) s->setQueueCapacity(kStatusQueue);
  }

  template <class T>
  void publish(const std::string& channel, const T& msg) {
    if (lcm_.publish(channel, &msg) != 0) {
      note_error("publish on " + channel + " failed");
    }
  }

  // Handles messages for at most timeout_ms (returns after the first batch or the timeout),
  // and publishes the heartbeat when it is due.
  void spin_once(int timeout_ms);

  // Heartbeat content.
  void set_state(const std::string& state) { state_ = state; }
  void set_scan(const std::string& scan_id, int iteration) {
    scan_id_ = scan_id;
    iteration_ = iteration;
  }
  void note_error(const std::string& what);  // logs and remembers as last_error
  // Sends the heartbeat when one is due (at most once a second): for a handler that computes
  // for long (the oracle's plan), so the launcher does not take the service for hung.
  void keep_alive() { heartbeat(); }
  int64_t handled() const { return handled_; }
  int64_t rejected() const { return rejected_; }
  int64_t ignored() const { return ignored_; }
  lcm::LCM& raw() { return lcm_; }

 private:
  template <class T>
  struct Dispatch {
    Bus* bus;
    std::function<void(const T&)> handler;
    void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& chan) {
      Dispatch* d = this;
      const MessageCheck check = check_message(rbuf->data, rbuf->data_size, T::getTypeName(), T::getHash(),
                                               HasScanId<T>::value ? scope_field<T>() : "", d->bus->limits_);
      if (!check.ok) {
        d->bus->reject(chan, check.reason);
        return;
      }
      if constexpr (HasScanId<T>::value) {
        if (!in_scope(d->bus->scope_, check.scope, MayBeUnscoped<T>::value)) {
          d->bus->ignore(chan, std::string(check.scope));
          return;
        }
      }
      T msg;
      bool decoded = false;
      try {
        decoded = msg.decode(rbuf->data, 0, rbuf->data_size) >= 0;
      } catch (const std::exception& e) {  // the guard passed it: a decoder it does not know of
        decoded = false;
      }
      if (!decoded) {
        d->bus->reject(chan, "malformed message (" + std::to_string(rbuf->data_size) +
                                 " bytes) does not decode as " + T::getTypeName());
        return;
      }
      try {
        d->handler(msg);
        ++d->bus->handled_;
      } catch (const std::exception& e) {
        d->bus->reject(chan, e.what());
      }
    }
  };
  void reject(const std::string& channel, const std::string& why);
  void ignore(const std::string& channel, const std::string& scan_id);
  void heartbeat(bool force = false);
  void report_suppressed(bool all);

  lcm::LCM lcm_;
  std::string service_;
  std::string state_ = "idle";
  std::string scan_id_;
  int iteration_ = -1;
  std::string last_error_;
  int64_t handled_ = 0;
  int64_t rejected_ = 0;
  int64_t ignored_ = 0;
  std::string scope_;
  DecodeLimits limits_;
  LogLimiter log_limit_;
  double next_heartbeat_s_ = 0;
};

}  // namespace pbnbv::bus
