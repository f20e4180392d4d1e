#pragma once
// Shared by the unit tests that check an error's exact words.
#include <gtest/gtest.h>

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

// Expects `f` to throw an error whose message contains `needle`.
inline void expect_error(const std::function<void()>& f, const std::string& needle) {
  const std::string message = error_message(f);
  EXPECT_NE(message.find(needle), std::string::npos) << "expected an error naming '" << needle << "', got: " << message;
}


}  // namespace pbnbv::testing
