// Small helpers shared by the test suites: temporary paths and whole-file reads.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <string>

#include "base/check.h"

namespace raycell::testing {

// A path in the test temporary folder, unique per process: TEMP/raycell_PREFIX_PID_NAME.
inline std::string TempPath(const std::string& prefix, const std::string& name) {
  return ::testing::TempDir() + "raycell_" + prefix + "_" + std::to_string(::getpid()) + "_" + name;
}

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The InputError message `f` throws, or "" when it throws none.
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace raycell::testing
