#include "bus/bus.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdlib>

#include "pbnbv/heartbeat_t.hpp"

namespace pbnbv::bus {

std::string lcm_url() {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  if (env && *env) return env;
  // ttl=0: never leaves the host. A 1280x720 depth frame is 1.8 MB: give the socket room.
  return "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";
}

const std::string& scan_of(const heartbeat_t& m) { return m.serves_scan; }

int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

Bus::Bus(const std::string& service_name) : lcm_(lcm_url()), service_(service_name) {
  if (!lcm_.good()) {
    throw std::runtime_error("cannot start LCM on " + lcm_url() +
                             " (is there a multicast route? see README, 'Networking')");
  }
}

Bus::~Bus() {
  report_suppressed(true);
  state_ = "stopped";
  heartbeat(true);
}

void Bus::spin_once(int timeout_ms) {
  lcm_.handleTimeout(timeout_ms);
  heartbeat();
  report_suppressed(false);
}

void Bus::note_error(const std::string& what) {
  last_error_ = what;
  log_error(what);
}

void Bus::reject(const std::string& channel, const std::string& why) {
  ++rejected_;
  last_error_ = "rejected message on " + channel + ": " + why;
  if (log_limit_.allow("rejected on " + channel, now_s())) log_warn(last_error_);
}

void Bus::ignore(const std::string& channel, const std::string& scan_id) {
  ++ignored_;
  if (log_limit_.allow("ignored on " + channel, now_s())) {
    log_info("ignored a message on " + channel + " of scan '" + scan_id + "' (this process serves scan '" + scope_ +
             "' only)");
  }
}

void Bus::report_suppressed(bool all) {
  const double t = all ? now_s() + log_limit_.window_s() : now_s();
  for (const auto& [kind, count] : log_limit_.take_due(t)) {
    log_info(std::to_string(count) + " more messages " + kind + " (" + std::to_string(rejected_) + " rejected, " +
             std::to_string(ignored_) + " of other scans ignored since start)");
  }
}

void Bus::heartbeat(bool force) {
  const double t = now_s();
  if (!force && t < next_heartbeat_s_) return;
  next_heartbeat_s_ = t + 1.0;
  heartbeat_t hb;
  hb.utime = now_utime();
  hb.service = service_;
  hb.pid = static_cast<int32_t>(getpid());
  hb.scan_id = scan_id_;
  hb.serves_scan = scope_;
  hb.iteration = iteration_;
  hb.messages_handled = handled_;
  hb.messages_rejected = rejected_;
  hb.messages_ignored = ignored_;
  hb.state = state_;
  hb.last_error = last_error_;
  lcm_.publish(channels::kHeartbeat, &hb);
}

}  // namespace pbnbv::bus
