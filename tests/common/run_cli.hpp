#pragma once
// Runs the lambert CLI in-process, as the tests' stand-in for the `lambert` binary.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "apps/cli.hpp"

namespace lambert::testing {

/// run_cli with argv = {"lambert", args...}; returns the exit code.
inline int run(std::vector<std::string> args) {
  args.insert(args.begin(), "lambert");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return run_cli(static_cast<int>(argv.size()), argv.data());
}

/// What a captured run printed.
struct Captured {
  int code;
  std::string out, err;
};

/// run(args) with stdout and stderr captured.
inline Captured run_captured(const std::vector<std::string>& args) {
  ::testing::internal::CaptureStderr();
  ::testing::internal::CaptureStdout();
  const int code = run(args);
  std::string out = ::testing::internal::GetCapturedStdout();
  return {code, std::move(out), ::testing::internal::GetCapturedStderr()};
}

/// run(args) with stdout and stderr captured: the exit code and what went to stderr.
inline std::pair<int, std::string> run_capturing(const std::vector<std::string>& args) {
  Captured c = run_captured(args);
  return {c.code, std::move(c.err)};
}

/// run(args) with stdout and stderr captured: the exit code and what went to stdout.
inline std::pair<int, std::string> run_stdout(const std::vector<std::string>& args) {
  Captured c = run_captured(args);
  return {c.code, std::move(c.out)};
}

/// The whole content of a file ("" if it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A JSON file a command wrote, parsed (throws nlohmann::json::parse_error if it is not JSON).
inline nlohmann::json read_json(const std::string& path) {
  return nlohmann::json::parse(slurp(path));
}

}  // namespace lambert::testing
