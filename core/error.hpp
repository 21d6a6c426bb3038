#pragma once
// Error types (input and environment failures) and the always-on invariant check.

#include <stdexcept>
#include <string>

namespace lambert {

/// Base of every failure reported to the user; the CLI maps it to an exit code.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file could not be read or written.
class IoError : public Error {
 public:
  using Error::Error;
};

/// A scene (or a file derived from one) is malformed or physically invalid.
class SceneError : public Error {
 public:
  using Error::Error;
};

/// The command line asks for something impossible (exit code 2).
class UsageError : public Error {
 public:
  using Error::Error;
};

/// The work was asked to stop (request_cancel, core/parallel.hpp: Python's Ctrl-C).
class Cancelled : public Error {
 public:
  using Error::Error;
};

/// Thrown by LAMBERT_CHECK: a bug in lambert, never a user error.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

/// Builds the message of a failed LAMBERT_CHECK.
[[noreturn]] void check_failed(const char* expr, const char* file, int line, const std::string& msg);

}  // namespace lambert

/// Always-on invariant check (release builds too). For things that must never happen.
#define LAMBERT_CHECK(cond, msg)                                   \
  do {                                                             \
    if (!(cond)) ::lambert::check_failed(#cond, __FILE__, __LINE__, (msg)); \
  } while (0)
