#include "bus/service.hpp"

#include <iostream>

namespace pbnbv::bus {

int run_service(const std::string& name, CLI::App& app, int argc, char** argv, int spin_ms,
                const std::function<std::function<void()>(Bus&)>& make) {
  set_log_name(name);
  std::string scope;
  cli::add_text(app, "scan", &scope,
                "serve this scan only: messages of other scans are ignored and counted (default: every scan)", "ID");
  if (const std::optional<int> code = cli::parse(app, argc, argv, std::cout, std::cerr)) return *code;
  install_stop_handlers();
  try {
    Bus bus(name);
    bus.serve_scan(scope);
    const std::function<void()> tick = make(bus);
    while (!stop_requested()) {
      bus.spin_once(spin_ms);
      if (tick) tick();
    }
    return 0;
  } catch (const std::exception& e) {
    log_error(e.what());
    return 2;
  }
}

}  // namespace pbnbv::bus
