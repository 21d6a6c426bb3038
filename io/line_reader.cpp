#include "io/line_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "core/error.hpp"

namespace lambert {
namespace {
constexpr std::size_t kFirstChunkBytes = std::size_t{1} << 12, kChunkBytes = std::size_t{1} << 16;
}  // namespace

LineReader::LineReader(std::istream& in, std::string name) : in_(in), name_(std::move(name)) {}

std::string LineReader::where() const { return name_ + ":" + std::to_string(line_); }

bool LineReader::fill() {
  if (eof_) return false;
  if (capacity_ < kChunkBytes && end_ == capacity_) {  // the first read, or the last was full
    capacity_ = capacity_ == 0 ? kFirstChunkBytes : std::min(kChunkBytes, 4 * capacity_);
    buf_.reset(new char[capacity_]);
  }
  in_.read(buf_.get(), static_cast<std::streamsize>(capacity_));
  end_ = static_cast<std::size_t>(in_.gcount());
  pos_ = 0;
  if (in_.bad()) throw IoError(name_ + ": read error: " + std::strerror(errno));
  if (end_ < capacity_) eof_ = true;
  if (!started_ && end_ > 0) {
    started_ = true;
    const auto u = [&](std::size_t k) { return k < end_ ? static_cast<unsigned char>(buf_[k]) : 0u; };
    if ((u(0) == 0xFF && u(1) == 0xFE) || (u(0) == 0xFE && u(1) == 0xFF))
      throw SceneError(name_ + ": UTF-16 text: convert to UTF-8");
    if (u(0) == 0xEF && u(1) == 0xBB && u(2) == 0xBF) pos_ = 3;
  }
  return end_ > pos_;
}

bool LineReader::next(std::string_view& line) {
  line_buf_.clear();
  bool any = false;  // something (text or a terminator) was read for this line
  for (;;) {
    if (pos_ == end_ && !fill()) {
      if (!any) return false;
      break;
    }
    any = true;
    std::size_t k = pos_;
    while (k < end_ && buf_[k] != '\n' && buf_[k] != '\r' && buf_[k] != '\0') ++k;
    if (line_buf_.size() + (k - pos_) > kMaxLineBytes)
      throw SceneError(name_ + ":" + std::to_string(line_ + 1) + ": line longer than " +
                       std::to_string(kMaxLineBytes >> 20) + " MiB (not a text file?)");
    line_buf_.append(buf_.get() + pos_, k - pos_);
    pos_ = k;
    if (k == end_) continue;
    if (buf_[k] == '\0')
      throw SceneError(name_ + ":" + std::to_string(line_ + 1) +
                       ": NUL byte: a binary or UTF-16 file (convert to UTF-8 text)");
    ++pos_;
    if (buf_[k] == '\r') {  // CRLF: swallow the LF, even across a chunk boundary
      if (pos_ == end_) fill();
      if (pos_ < end_ && buf_[pos_] == '\n') ++pos_;
    }
    break;
  }
  ++line_;
  line = line_buf_;
  return true;
}

void split_fields(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t k = 0;
  while (k < line.size()) {
    while (k < line.size() && is_blank(line[k])) ++k;
    if (k == line.size()) break;
    const std::size_t b = k;
    while (k < line.size() && !is_blank(line[k])) ++k;
    out.push_back(line.substr(b, k - b));
  }
}

void split_tokens(std::string_view line, std::vector<std::string_view>& out) {
  split_fields(line, out);
  const auto comment =
      std::find_if(out.begin(), out.end(), [](std::string_view t) { return t[0] == '#'; });
  out.erase(comment, out.end());
}

std::string join_tokens(const std::vector<std::string_view>& tokens, std::size_t first) {
  std::string out;
  for (std::size_t k = first; k < tokens.size(); ++k) {
    if (!out.empty()) out.push_back(' ');
    out.append(tokens[k]);
  }
  return out;
}

}  // namespace lambert
