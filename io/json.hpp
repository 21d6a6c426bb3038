#pragma once
// A minimal streaming JSON writer (output only) for reports and summaries.

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace lambert {

/// Writes JSON to a stream with correct commas and escaping. Usage:
///   JsonWriter j(out); j.begin_object(); j.key("n"); j.value(3); j.end_object();
/// Non-finite doubles are written as null (JSON has no NaN/Inf).
class JsonWriter {
 public:
  explicit JsonWriter(std::ostream& out) : out_(out) {}
  void begin_object();
  void end_object();
  void begin_array();
  void end_array();
  /// Writes an object key; the next call writes its value.
  void key(const std::string& k);
  void value(double v);
  void value(std::int64_t v);
  void value(int v) { value(static_cast<std::int64_t>(v)); }
  void value(bool v);
  void value(const std::string& v);
  void value(const char* v) { value(std::string(v)); }
  void null();
  /// Writes an array of numbers.
  void value(const std::vector<double>& v);
  /// Shorthand for key(k) followed by value(v).
  template <typename T>
  void field(const std::string& k, const T& v) {
    key(k);
    value(v);
  }

 private:
  void separator();
  std::ostream& out_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
  int depth_ = 0;
};

/// Escapes a string for JSON (quotes included).
std::string json_quote(const std::string& s);

}  // namespace lambert
