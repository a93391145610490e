// Small helpers shared by the test suites: temporary paths and folders, whole-file reads and
// writes, InputError messages.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "base/check.h"

namespace raycell::testing {

// A path in the test temporary folder, unique per process: TEMP/raycell_PREFIX_PID_NAME.
inline std::string TempPath(const std::string& prefix, const std::string& name) {
  return ::testing::TempDir() + "raycell_" + prefix + "_" + std::to_string(::getpid()) + "_" + name;
}

// A fresh, empty folder TEMP/raycell_test_NAME_PID (what it held before is removed).
inline std::filesystem::path TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("raycell_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), bytes.size());
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
