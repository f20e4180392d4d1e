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

#include "bus/channels.hpp"
#include "core/base/log.hpp"
#include "core/base/signals.hpp"

namespace pbnbv::bus {

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

  // Subscribes to `channel`; each message is decoded as T and passed to `handler`. A message
  // that does not decode, or whose handler throws std::exception (its validation failing),
  // is logged with the channel and the reason, counted as rejected, and dropped.
  template <class T>
  void subscribe(const std::string& channel, std::function<void(const T&)> handler) {
    // Owned by the LCM connection for the process's lifetime (subscriptions are never removed).
    auto* dispatch = new Dispatch<T>{this, std::move(handler)};
    lcm_.subscribe(channel, &Dispatch<T>::on_message, dispatch);
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
  int64_t handled() const { return handled_; }
  int64_t rejected() const { return rejected_; }
  lcm::LCM& raw() { return lcm_; }

 private:
  template <class T>
  struct Dispatch {
    Bus* bus;
    std::function<void(const T&)> handler;
    void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& chan) {
      Dispatch* d = this;
      T msg;
      bool decoded = false;
      try {
        decoded = msg.decode(rbuf->data, 0, rbuf->data_size) >= 0;
      } catch (const std::exception& e) {  // e.g. a corrupt array length
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
  void heartbeat(bool force = false);

  lcm::LCM lcm_;
  std::string service_;
  std::string state_ = "idle";
  std::string scan_id_;
  int iteration_ = -1;
  std::string last_error_;
  int64_t handled_ = 0;
  int64_t rejected_ = 0;
  double next_heartbeat_s_ = 0;
};

}  // namespace pbnbv::bus
