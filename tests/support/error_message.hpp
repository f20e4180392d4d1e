#pragma once
// Shared by the unit tests that check an error's exact words.
#include <exception>
#include <functional>
#include <string>

namespace pbnbv::testing {

// The message of the exception `f` throws, or "(no error)" when it returns.
inline std::string error_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace pbnbv::testing
