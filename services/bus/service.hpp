#pragma once
// The skeleton every service process shares: the command line, the bus, the message loop, clean
// exit.
#include <functional>
#include <string>

#include "bus/bus.hpp"
#include "cli/options.hpp"

namespace pbnbv::bus {

// Runs a service: parses argv with `app` (whose options the caller declared, bound to its own
// variables, plus --scan ID: serve that scan only; a bad option, --help or --version ends the
// run before the bus is touched),
// connects to the bus, builds the service with `make` (which subscribes and returns the periodic
// tick, or nullptr), then handles messages (waiting at most `spin_ms` at a time) and ticks until
// SIGINT or SIGTERM. Returns the process exit code: 0 on a clean stop or after --help /
// --version, 2 on a bad command line or a failure to start.
int run_service(const std::string& name, CLI::App& app, int argc, char** argv, int spin_ms,
                const std::function<std::function<void()>(Bus&)>& make);

}  // namespace pbnbv::bus
