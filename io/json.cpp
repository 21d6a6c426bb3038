#include "io/json.hpp"

#include <cmath>
#include <cstdio>

namespace lambert {

std::string json_quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

void JsonWriter::separator() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_.empty()) {
    if (!first_.back()) out_ << ',';
    first_.back() = false;
    out_ << '\n' << std::string(2 * first_.size(), ' ');
  }
}

void JsonWriter::begin_object() {
  separator();
  out_ << '{';
  first_.push_back(true);
}
void JsonWriter::end_object() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) out_ << '\n' << std::string(2 * first_.size(), ' ');
  out_ << '}';
  if (first_.empty()) out_ << '\n';
}
void JsonWriter::begin_array() {
  separator();
  out_ << '[';
  first_.push_back(true);
}
void JsonWriter::end_array() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) out_ << '\n' << std::string(2 * first_.size(), ' ');
  out_ << ']';
}
void JsonWriter::key(const std::string& k) {
  separator();
  out_ << json_quote(k) << ": ";
  after_key_ = true;
}
void JsonWriter::value(double v) {
  separator();
  if (!std::isfinite(v)) {
    out_ << "null";
    return;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  out_ << buf;
}
void JsonWriter::value(std::int64_t v) {
  separator();
  out_ << v;
}
void JsonWriter::value(bool v) {
  separator();
  out_ << (v ? "true" : "false");
}
void JsonWriter::value(const std::string& v) {
  separator();
  out_ << json_quote(v);
}
void JsonWriter::null() {
  separator();
  out_ << "null";
}
void JsonWriter::value(const std::vector<double>& v) {
  // Numbers inline on one line: compact for long vectors.
  separator();
  out_ << '[';
  for (size_t k = 0; k < v.size(); ++k) {
    if (k) out_ << ", ";
    if (!std::isfinite(v[k])) {
      out_ << "null";
      continue;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v[k]);
    out_ << buf;
  }
  out_ << ']';
}

}  // namespace lambert
