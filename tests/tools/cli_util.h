// Running the raycell binary from the command-line tests.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace raycell::testing {

struct Result {
  int code;
  std::string out;
};

// Runs `raycell ARGS` through the shell; its output is stdout, and stderr too unless
// `with_stderr` is false; in the folder `cwd` when it is given.
inline Result Raycell(const std::string& args, bool with_stderr = true,
                      const std::string& cwd = "") {
  const std::string cmd = (cwd.empty() ? "" : "cd '" + cwd + "' && ") +
                          std::string(RAYCELL_BINARY) + " " + args +
                          (with_stderr ? " 2>&1" : " 2>/dev/null");
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  for (std::size_t n; (n = fread(buf.data(), 1, buf.size(), p)) > 0;) out.append(buf.data(), n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

struct SplitResult {
  int code;
  std::string out, err;
};

// Runs `raycell ARGS` through the shell with stdout and stderr apart (stderr through the file
// stderr.txt of CliDir(name)).
inline SplitResult RaycellSplit(const std::string& args, const std::string& name);

// A folder for one test's files, unique per process: TEMP/raycell_NAME_PID.
inline std::filesystem::path CliDir(const std::string& name) {
  const auto d =
      std::filesystem::temp_directory_path() / ("raycell_" + name + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(d);
  return d;
}

inline SplitResult RaycellSplit(const std::string& args, const std::string& name) {
  const std::string err_file = (CliDir(name) / "stderr.txt").string();
  const std::string cmd = std::string(RAYCELL_BINARY) + " " + args + " 2>'" + err_file + "'";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  for (std::size_t n; (n = fread(buf.data(), 1, buf.size(), p)) > 0;) out.append(buf.data(), n);
  const int status = pclose(p);
  std::ifstream err(err_file, std::ios::binary);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out,
          std::string(std::istreambuf_iterator<char>(err), {})};
}

// The fields of one CSV line (quoted fields unquoted, "" inside them a quote).
inline std::vector<std::string> CsvRow(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"' && quoted && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"', ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

// The rows of CSV text without its comment lines (# ...) and empty lines, each split into
// fields.
inline std::vector<std::vector<std::string>> CsvText(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') rows.push_back(CsvRow(line));
  }
  return rows;
}

}  // namespace raycell::testing
