#pragma once
// One handling of SIGINT and SIGTERM for every program: the handler only sets a flag that the
// program's loop polls, so it stops at a safe point (writes what it has, stops its children).
namespace pbnbv {

// Installs the handlers (idempotent) and ignores SIGPIPE.
void install_stop_handlers();
// True once SIGINT or SIGTERM arrived after install_stop_handlers().
bool stop_requested();

}  // namespace pbnbv
