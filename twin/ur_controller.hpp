#pragma once
// The twin playing a Universal Robots controller for pbnbv-ur-driver (pbnbv-twin --rtde-port N
// --ur-script-port M): an RTDE server on 127.0.0.1:N for one client (protocol 2, the outputs and
// input registers of driver/ur_arm.hpp, NOT_FOUND for any other variable, data packages at the
// client's frequency of rig time) and a script port on 127.0.0.1:M taking the driver's URScript
// text. No URScript interpreter: the twin plays the program's part itself (twin_main.cpp) once a
// script that is the driver's program has arrived. Plain non-blocking sockets, polled from the
// twin's loop; nothing here waits.
#include <cstdint>
#include <string>
#include <vector>

#include "driver/rtde.hpp"
#include "driver/ur_arm.hpp"

namespace pbnbv::twin {

class UrController {
 public:
  // Listens on 127.0.0.1 at both ports. Throws std::runtime_error naming the port that cannot be
  // bound.
  UrController(int rtde_port, int script_port);
  ~UrController();
  UrController(const UrController&) = delete;
  UrController& operator=(const UrController&) = delete;

  // Accepts connections, reads what arrived, answers requests, flushes what is queued. Never
  // blocks. A malformed package closes the client (logged, naming it).
  void poll();
  // Queues a data package with `state` when the client has started the stream and its period of
  // rig time has passed since the last one.
  void stream(double rig_time_s, const driver::ur::State& state);
  // Closes the client connection (the rtde-drop fault), as a controller whose link failed.
  void drop(const std::string& why);

  bool client_connected() const { return client_ >= 0; }
  bool streaming() const { return streaming_; }
  // The input registers as the client last wrote them (all zero before).
  const driver::ur::Registers& registers() const { return registers_; }
  // True once for each script received that is the driver's program (others are logged and
  // ignored, as a controller would fail to run them).
  bool take_program();

 private:
  void accept_client();
  void accept_script();
  void read_client();
  void read_script();
  void handle(const driver::rtde::Package& p);
  void send(const driver::rtde::Package& p);
  void flush();
  void close_client(const std::string& why);
  void close_script();

  int rtde_listener_ = -1, script_listener_ = -1;
  int client_ = -1, script_ = -1;
  driver::rtde::Framer framer_;
  std::vector<uint8_t> out_;  // queued for the client
  std::string script_text_;
  bool protocol_ok_ = false;
  bool streaming_ = false;
  double frequency_hz_ = 0;
  double next_data_s_ = -1;
  bool outputs_ok_ = false, inputs_ok_ = false;
  driver::ur::Registers registers_;
  bool program_arrived_ = false;
};

}  // namespace pbnbv::twin
