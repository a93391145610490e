// Helpers shared by the recorder's tests: small recordings (temporary folders: TempDir in
// tests/test_util.h).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/test_util.h"
#include "traces/record/recorder.h"

namespace raycell::testing {

inline std::string ReadBytes(const std::filesystem::path& p) {
  return raycell::testing::ReadBytes(p.string());
}

// A small, quick recording of the built-in scene.
inline RecordOptions SmallBuiltin(const std::filesystem::path& dir, int res = 48) {
  RecordOptions o;
  o.settings.width = o.settings.height = std::uint32_t(res);
  o.out = (dir / "builtin.rct").string();
  o.images_dir.clear();
  o.progress = false;
  return o;
}

inline std::string SharedData() { return RAYCELL_SHARED_DATA; }

}  // namespace raycell::testing
