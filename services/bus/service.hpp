#pragma once
// The skeleton every service process shares: options, the bus, the message loop, clean exit.
#include <functional>
#include <string>

#include "bus/bus.hpp"
#include "core/base/args.hpp"

namespace pbnbv::bus {

// Runs a service: parses argv, connects to the bus, builds the service with `make` (which
// reads its options and subscribes; it returns the periodic tick, or nullptr), rejects unknown
// options, then handles messages (waiting at most `spin_ms` at a time) and ticks until SIGINT
// or SIGTERM. Returns the process exit code: 0 on a clean stop, 2 on bad options or a failure
// to start (printed with `usage`).
int run_service(const std::string& name, const std::string& usage, int argc, char** argv, int spin_ms,
                const std::function<std::function<void()>(const Args&, Bus&)>& make);

}  // namespace pbnbv::bus
