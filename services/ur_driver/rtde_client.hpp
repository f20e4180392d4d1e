#pragma once
// pbnbv-ur-driver's side of the wire: a TCP connection where every wait has a deadline, the
// RTDE session on it (handshake, recipes, start, the data stream, the input registers, pause)
// and the URScript program sent on the secondary interface. The bytes are driver/rtde.hpp's.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "driver/rtde.hpp"
#include "driver/ur_arm.hpp"

namespace pbnbv::ur_driver {

// A TCP connection to host:port. Every call is bounded by its timeout; failures throw
// std::runtime_error naming host:port and why.
class Connection {
 public:
  Connection(const std::string& host, int port, double timeout_s);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  void send_all(const std::vector<uint8_t>& bytes, double timeout_s);
  // Waits up to timeout_s for bytes; returns how many arrived (0: none in time). Throws when the
  // peer closed the connection or it failed.
  std::size_t receive(uint8_t* buffer, std::size_t size, double timeout_s);
  const std::string& address() const { return address_; }

 private:
  std::string address_;  // "host:port", for messages
  int fd_ = -1;
};

// One RTDE session with the controller.
class RtdeClient {
 public:
  // Connects and sets the session up: protocol 2, the controller's version, the outputs at
  // `frequency_hz` and the input registers (a NOT_FOUND or IN_USE variable is refused, named),
  // then starts the stream. Each step waits at most `step_timeout_s`; `tick` is called at least
  // every 10 ms while waiting (the driver keeps publishing its statuses).
  RtdeClient(const std::string& host, int port, double frequency_hz, double step_timeout_s,
             const std::function<void()>& tick);

  // The next data package's state, waiting up to timeout_s (none: nothing in time). Text
  // messages from the controller are logged. Throws on a malformed package or a lost connection.
  std::optional<driver::ur::State> next_state(double timeout_s);
  // Writes the input registers (one data package on the input recipe).
  void write(const driver::ur::Registers& registers, double timeout_s);
  // Pauses the stream and waits up to timeout_s for the answer.
  void pause(double timeout_s);

  const driver::rtde::UrControlVersion& version() const { return version_; }
  const std::string& address() const { return connection_.address(); }

 private:
  // The next package that is not a text message, within timeout_s (none: nothing in time).
  std::optional<driver::rtde::Package> next_package(double timeout_s);
  // The answer of type `type` to a request just sent; throws naming the request when none comes.
  driver::rtde::Package answer(uint8_t type, double timeout_s, const std::function<void()>& tick);

  Connection connection_;
  driver::rtde::Framer framer_;
  driver::rtde::UrControlVersion version_;
  uint8_t output_recipe_ = 0, input_recipe_ = 0;
};

// Sends the URScript `program` (newline-terminated text) to host:port and closes, within
// timeout_s.
void send_program(const std::string& host, int port, const std::string& program, double timeout_s);

}  // namespace pbnbv::ur_driver
