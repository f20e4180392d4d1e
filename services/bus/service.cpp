#include "bus/service.hpp"

#include <iostream>

namespace pbnbv::bus {

int run_service(const std::string& name, const std::string& usage, int argc, char** argv, int spin_ms,
                const std::function<std::function<void()>(const Args&, Bus&)>& make) {
  set_log_name(name);
  install_stop_handlers();
  try {
    const Args args(argc, argv);
    Bus bus(name);
    const std::function<void()> tick = make(args, bus);
    args.reject_unknown();
    while (!stop_requested()) {
      bus.spin_once(spin_ms);
      if (tick) tick();
    }
    return 0;
  } catch (const std::exception& e) {
    log_error(e.what());
    std::cerr << "usage: " << usage << "\n";
    return 2;
  }
}

}  // namespace pbnbv::bus
