// Small helpers shared by the test suites: temporary paths and whole-file reads.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <string>

namespace raycell::testing {

// A path in the test temporary folder, unique per process: TEMP/raycell_PREFIX_PID_NAME.
inline std::string TempPath(const std::string& prefix, const std::string& name) {
  return ::testing::TempDir() + "raycell_" + prefix + "_" + std::to_string(::getpid()) + "_" + name;
}

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace raycell::testing
