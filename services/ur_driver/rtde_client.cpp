#include "rtde_client.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

#include "core/base/log.hpp"

namespace pbnbv::ur_driver {

namespace {

namespace rtde = driver::rtde;
namespace ur = driver::ur;
using Clock = std::chrono::steady_clock;

Clock::time_point after(double s) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// Milliseconds left until `end` (0 when past).
int ms_left(Clock::time_point end) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now()).count();
  return left > 0 ? static_cast<int>(left) : 0;
}

// Waits for `events` on fd until `end`; true when ready.
bool wait_for(int fd, short events, Clock::time_point end) {
  for (;;) {
    pollfd p{fd, events, 0};
    const int r = ::poll(&p, 1, ms_left(end));
    if (r > 0) return true;
    if (r == 0) return false;
    if (errno != EINTR) return false;
    if (Clock::now() >= end) return false;
  }
}

}  // namespace

Connection::Connection(const std::string& host, int port, double timeout_s)
    : address_(host + ":" + std::to_string(port)) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (const int e = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found); e != 0) {
    throw std::runtime_error("cannot resolve " + address_ + ": " + ::gai_strerror(e));
  }
  fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd_ < 0) {
    ::freeaddrinfo(found);
    throw std::runtime_error("socket for " + address_ + ": " + std::strerror(errno));
  }
  ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL, 0) | O_NONBLOCK);
  const int one = 1;
  ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  const int r = ::connect(fd_, found->ai_addr, found->ai_addrlen);
  ::freeaddrinfo(found);
  std::string why;
  if (r != 0 && errno != EINPROGRESS) {
    why = std::strerror(errno);
  } else if (r != 0 && !wait_for(fd_, POLLOUT, after(timeout_s))) {
    why = "no answer in " + std::to_string(timeout_s).substr(0, 4) + " s";
  } else {
    int error = 0;
    socklen_t len = sizeof error;
    ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &error, &len);
    if (error != 0) why = std::strerror(error);
  }
  if (!why.empty()) {
    ::close(fd_);
    throw std::runtime_error("cannot connect to " + address_ + ": " + why);
  }
}

Connection::~Connection() { ::close(fd_); }

void Connection::send_all(const std::vector<uint8_t>& bytes, double timeout_s) {
  const auto end = after(timeout_s);
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
      if (!wait_for(fd_, POLLOUT, end)) throw std::runtime_error("sending to " + address_ + " timed out");
    } else {
      throw std::runtime_error("sending to " + address_ + ": " + std::strerror(errno));
    }
  }
}

std::size_t Connection::receive(uint8_t* buffer, std::size_t size, double timeout_s) {
  if (!wait_for(fd_, POLLIN, after(timeout_s))) return 0;
  const ssize_t n = ::recv(fd_, buffer, size, 0);
  if (n == 0) throw std::runtime_error("the controller closed the connection");
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
    throw std::runtime_error(std::string("receive: ") + std::strerror(errno));
  }
  return static_cast<std::size_t>(n);
}

RtdeClient::RtdeClient(const std::string& host, int port, double frequency_hz, double step_timeout_s,
                       const std::function<void()>& tick)
    : connection_(host, port, step_timeout_s) {
  connection_.send_all(rtde::encode(rtde::request_protocol_version()), step_timeout_s);
  if (!rtde::parse_accepted(answer(rtde::kRequestProtocolVersion, step_timeout_s, tick), rtde::kRequestProtocolVersion)) {
    throw rtde::RtdeError("the controller at " + address() + " refuses RTDE protocol version 2 (a CB3 before 3.5?)");
  }
  connection_.send_all(rtde::encode(rtde::get_urcontrol_version()), step_timeout_s);
  version_ = rtde::parse_urcontrol_version(answer(rtde::kGetUrControlVersion, step_timeout_s, tick));

  connection_.send_all(rtde::encode(rtde::setup_outputs(frequency_hz, ur::output_names())), step_timeout_s);
  const rtde::SetupAnswer outputs = rtde::parse_setup_answer(answer(rtde::kSetupOutputs, step_timeout_s, tick), rtde::kSetupOutputs);
  rtde::recipe_types(outputs, ur::output_names(), ur::output_types());
  output_recipe_ = outputs.recipe_id;

  connection_.send_all(rtde::encode(rtde::setup_inputs(ur::input_names())), step_timeout_s);
  const rtde::SetupAnswer inputs = rtde::parse_setup_answer(answer(rtde::kSetupInputs, step_timeout_s, tick), rtde::kSetupInputs);
  rtde::recipe_types(inputs, ur::input_names(), ur::input_types());
  input_recipe_ = inputs.recipe_id;

  connection_.send_all(rtde::encode(rtde::start()), step_timeout_s);
  if (!rtde::parse_accepted(answer(rtde::kStart, step_timeout_s, tick), rtde::kStart)) {
    throw rtde::RtdeError("the controller at " + address() + " refused to start the data stream");
  }
}

std::optional<rtde::Package> RtdeClient::next_package(double timeout_s) {
  const auto end = after(timeout_s);
  for (;;) {
    while (std::optional<rtde::Package> p = framer_.next()) {
      if (p->type != rtde::kTextMessage) return p;
      const rtde::TextMessage m = rtde::parse_text_message(*p);
      log_info("controller says (" + m.source + ", level " + std::to_string(m.level) + "): " + m.message);
    }
    uint8_t buffer[4096];
    const std::size_t n = connection_.receive(buffer, sizeof buffer, ms_left(end) / 1000.0);
    if (n == 0) return std::nullopt;
    framer_.feed(buffer, n);
  }
}

rtde::Package RtdeClient::answer(uint8_t type, double timeout_s, const std::function<void()>& tick) {
  const auto end = after(timeout_s);
  while (Clock::now() < end) {
    std::optional<rtde::Package> p = next_package(std::min(0.01, ms_left(end) / 1000.0));
    if (tick) tick();
    if (!p) continue;
    if (p->type == type) return *p;
    if (p->type != rtde::kDataPackage) throw rtde::RtdeError("expected the answer " + rtde::type_label(type) + ", got " + rtde::type_label(p->type));
  }
  throw std::runtime_error("no answer to " + rtde::type_label(type) + " from " + address() + " in " +
                           std::to_string(timeout_s).substr(0, 4) + " s");
}

std::optional<ur::State> RtdeClient::next_state(double timeout_s) {
  const std::optional<rtde::Package> p = next_package(timeout_s);
  if (!p) return std::nullopt;
  if (p->type != rtde::kDataPackage) {
    log_warn("RTDE: ignored an unexpected " + rtde::type_label(p->type) + " from " + address());
    return std::nullopt;
  }
  return ur::state_of(rtde::parse_data_package(*p, output_recipe_, ur::output_types()));
}

void RtdeClient::write(const ur::Registers& registers, double timeout_s) {
  connection_.send_all(rtde::encode(rtde::data_package(ur::data_of(input_recipe_, registers))), timeout_s);
}

void RtdeClient::pause(double timeout_s) {
  connection_.send_all(rtde::encode(rtde::pause()), timeout_s);
  answer(rtde::kPause, timeout_s, nullptr);
}

void send_program(const std::string& host, int port, const std::string& program, double timeout_s) {
  Connection c(host, port, timeout_s);
  c.send_all(std::vector<uint8_t>(program.begin(), program.end()), timeout_s);
}

}  // namespace pbnbv::ur_driver
