#include "twin/ur_controller.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "core/base/log.hpp"

namespace pbnbv::twin {

namespace {

namespace rtde = driver::rtde;
namespace ur = driver::ur;

constexpr uint8_t kOutputRecipe = 1;
constexpr uint8_t kInputRecipe = 2;
constexpr std::size_t kMaxQueued = 1 << 20;      // bytes queued for a client that does not read
constexpr std::size_t kMaxScript = 64 * 1024;    // bytes of URScript text
constexpr rtde::UrControlVersion kVersion{5, 11, 0, 0};

void set_non_blocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

// A non-blocking listening socket on 127.0.0.1:port.
int listen_on(int port, const char* what) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw std::runtime_error(std::string(what) + ": socket: " + std::strerror(errno));
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd, 4) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error(std::string(what) + ": cannot listen on 127.0.0.1:" + std::to_string(port) + ": " + why);
  }
  set_non_blocking(fd);
  return fd;
}

// The types of `names` as this controller answers them: the outputs (or inputs) it serves, else
// NOT_FOUND.
rtde::SetupAnswer answer_for(const std::vector<std::string>& names, const std::vector<std::string>& known,
                             const std::vector<rtde::Type>& types, uint8_t recipe_id, bool* all_found) {
  rtde::SetupAnswer a;
  a.recipe_id = recipe_id;
  *all_found = names == known;  // the twin serves exactly the driver's recipe, in its order
  for (const std::string& n : names) {
    std::string t = "NOT_FOUND";
    for (std::size_t i = 0; i < known.size(); ++i) {
      if (known[i] == n) t = rtde::type_name(types[i]);
    }
    a.types.push_back(t);
  }
  return a;
}

}  // namespace

UrController::UrController(int rtde_port, int script_port)
    : rtde_listener_(listen_on(rtde_port, "--rtde-port")) {
  try {
    script_listener_ = listen_on(script_port, "--ur-script-port");
  } catch (...) {
    ::close(rtde_listener_);
    throw;
  }
  log_info("playing a UR controller: RTDE on 127.0.0.1:" + std::to_string(rtde_port) + ", URScript on 127.0.0.1:" +
           std::to_string(script_port));
}

UrController::~UrController() {
  for (int fd : {client_, script_, rtde_listener_, script_listener_}) {
    if (fd >= 0) ::close(fd);
  }
}

void UrController::poll() {
  accept_client();
  accept_script();
  if (client_ >= 0) read_client();
  if (script_ >= 0) read_script();
  if (client_ >= 0) flush();
}

bool UrController::take_program() {
  const bool arrived = program_arrived_;
  program_arrived_ = false;
  return arrived;
}

void UrController::accept_client() {
  const int fd = ::accept(rtde_listener_, nullptr, nullptr);
  if (fd < 0) return;
  if (client_ >= 0) {  // one client at a time, as the driver is the only one
    log_warn("RTDE: a second client refused (one is connected)");
    ::close(fd);
    return;
  }
  set_non_blocking(fd);
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  client_ = fd;
  framer_ = rtde::Framer();
  out_.clear();
  protocol_ok_ = streaming_ = outputs_ok_ = inputs_ok_ = false;
  next_data_s_ = -1;
  log_info("RTDE: client connected");
}

void UrController::accept_script() {
  const int fd = ::accept(script_listener_, nullptr, nullptr);
  if (fd < 0) return;
  if (script_ >= 0) close_script();
  set_non_blocking(fd);
  script_ = fd;
  script_text_.clear();
}

void UrController::read_client() {
  uint8_t buffer[4096];
  for (;;) {
    const ssize_t n = ::recv(client_, buffer, sizeof buffer, 0);
    if (n == 0) return close_client("the client closed the connection");
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      return close_client(std::string("recv: ") + std::strerror(errno));
    }
    framer_.feed(buffer, static_cast<std::size_t>(n));
  }
  try {
    while (client_ >= 0) {
      const std::optional<rtde::Package> p = framer_.next();
      if (!p) break;
      handle(*p);
    }
  } catch (const std::exception& e) {
    close_client(std::string("malformed package: ") + e.what());
  }
}

// A controller's answer to each request; a data package writes the input registers.
void UrController::handle(const rtde::Package& p) {
  switch (p.type) {
    case rtde::kRequestProtocolVersion:
      protocol_ok_ = rtde::parse_protocol_version_request(p) == rtde::kProtocolVersion;
      return send(rtde::accepted_answer(p.type, protocol_ok_));
    case rtde::kGetUrControlVersion:
      return send(rtde::urcontrol_version_answer(kVersion));
    case rtde::kSetupOutputs: {
      const rtde::SetupRequest r = rtde::parse_setup_request(p);
      send(rtde::setup_answer(p.type, answer_for(r.names, ur::output_names(), ur::output_types(), kOutputRecipe, &outputs_ok_)));
      frequency_hz_ = r.frequency_hz;
      return;
    }
    case rtde::kSetupInputs: {
      const rtde::SetupRequest r = rtde::parse_setup_request(p);
      return send(rtde::setup_answer(p.type, answer_for(r.names, ur::input_names(), ur::input_types(), kInputRecipe, &inputs_ok_)));
    }
    case rtde::kStart:
      streaming_ = protocol_ok_ && outputs_ok_;
      return send(rtde::accepted_answer(p.type, streaming_));
    case rtde::kPause:
      streaming_ = false;
      return send(rtde::accepted_answer(p.type, true));
    case rtde::kDataPackage:
      if (!inputs_ok_) throw rtde::RtdeError("a data package before the input recipe was set up");
      registers_ = ur::registers_of(rtde::parse_data_package(p, kInputRecipe, ur::input_types()));
      return;
    default:
      throw rtde::RtdeError("unexpected " + rtde::type_label(p.type));
  }
}

void UrController::stream(double rig_time_s, const ur::State& state) {
  if (client_ < 0 || !streaming_ || frequency_hz_ <= 0) return;
  if (next_data_s_ >= 0 && rig_time_s + 1e-9 < next_data_s_) return;
  next_data_s_ = (next_data_s_ < 0 ? rig_time_s : next_data_s_) + 1.0 / frequency_hz_;
  if (next_data_s_ < rig_time_s) next_data_s_ = rig_time_s + 1.0 / frequency_hz_;  // after a render's pause
  send(rtde::data_package(ur::data_of(kOutputRecipe, state)));
}

void UrController::send(const rtde::Package& p) {
  const std::vector<uint8_t> bytes = rtde::encode(p);
  if (out_.size() + bytes.size() > kMaxQueued) return close_client("the client does not read its data");
  out_.insert(out_.end(), bytes.begin(), bytes.end());
}

void UrController::flush() {
  while (!out_.empty()) {
    const ssize_t n = ::send(client_, out_.data(), out_.size(), MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      return close_client(std::string("send: ") + std::strerror(errno));
    }
    out_.erase(out_.begin(), out_.begin() + n);
  }
}

void UrController::drop(const std::string& why) { close_client(why); }

void UrController::close_client(const std::string& why) {
  if (client_ < 0) return;
  ::close(client_);
  client_ = -1;
  streaming_ = false;
  out_.clear();
  log_warn("RTDE: client connection closed: " + why);
}

void UrController::read_script() {
  char buffer[4096];
  bool ended = false;
  for (;;) {
    const ssize_t n = ::recv(script_, buffer, sizeof buffer, 0);
    if (n == 0) {
      ended = true;
      break;
    }
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      ended = true;
      break;
    }
    script_text_.append(buffer, static_cast<std::size_t>(n));
    if (script_text_.size() > kMaxScript) {
      log_warn("URScript port: over " + std::to_string(kMaxScript) + " bytes of script: closed");
      return close_script();
    }
  }
  if (!ended && !ur::is_program(script_text_)) return;  // more to come
  if (ur::is_program(script_text_)) {
    log_info("URScript port: pbnbv-ur-driver's program received (" + std::to_string(script_text_.size()) +
             " bytes): following the input registers");
    program_arrived_ = true;
  } else {
    log_warn("URScript port: a script that is not pbnbv-ur-driver's program (" + std::to_string(script_text_.size()) +
             " bytes): ignored");
  }
  close_script();
}

void UrController::close_script() {
  ::close(script_);
  script_ = -1;
  script_text_.clear();
}

}  // namespace pbnbv::twin
