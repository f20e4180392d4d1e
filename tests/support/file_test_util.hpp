#pragma once
// Shared by the file-format tests: a fresh temporary folder per test, byte writers, and an
// expectation that a call throws a message containing given words.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbnbv::testing {

// A fresh temporary directory per test, removed afterwards.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = std::filesystem::temp_directory_path() /
           ("pbnbv_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& content) const {
    const std::string p = path(name);
    std::ofstream f(p, std::ios::binary);
    f.write(content.data(), static_cast<std::streamsize>(content.size()));
    return p;
  }
  std::filesystem::path dir_;
};

// The whole file at `path` ("" when it cannot be read: the test's own expectations then fail).
inline std::string file_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Appends n bytes of *p big-endian (the host is little-endian).
inline void put_be(std::string& s, const void* p, size_t n) {
  const auto* b = static_cast<const unsigned char*>(p);
  for (size_t k = 0; k < n; ++k) s.push_back(static_cast<char>(b[n - 1 - k]));
}

// Throws std::runtime_error, and the message contains every one of `needles`. An initializer list
// (not a vector), so that expect_error(f, {"a"}) picks this one beside error_message.hpp's
// expect_error(f, needle) when a translation unit includes both.
inline void expect_error(const std::function<void()>& fn, std::initializer_list<std::string> needles) {
  try {
    fn();
    ADD_FAILURE() << "no exception thrown";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    for (const auto& n : needles) {
      EXPECT_NE(msg.find(n), std::string::npos) << "message '" << msg << "' lacks '" << n << "'";
    }
  }
}

}  // namespace pbnbv::testing
