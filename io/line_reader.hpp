#pragma once
// Bounded, line-ending-agnostic text line reading and whitespace tokenizing for the text
// formats lambert reads (OBJ, MTL, Matrix Market, radiosity CSV, camera sidecar).

#include <cstddef>
#include <istream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace lambert {

/// Longest accepted line, in bytes. Real OBJ lines are below a few kB (a 10^5-corner face
/// with 7-digit indices is ~0.8 MB); the bound keeps an endless line (`/dev/zero`, a
/// binary file) from being read into memory.
constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;

/// Reads lines from a stream: a line ends at LF, CRLF or a lone CR (the end of the
/// stream ends the last line, newline or not). A UTF-8 byte-order mark at the start is
/// skipped. Throws SceneError naming `name:line` for a line longer than kMaxLineBytes, for
/// a NUL byte (binary, or UTF-16 without a byte-order mark) and for a UTF-16 byte-order
/// mark; IoError for a read error. Not thread-safe (one reader per stream).
class LineReader {
 public:
  /// Reads from `in` (not owned, must outlive the reader); `name` is used in messages.
  LineReader(std::istream& in, std::string name);
  /// Next line without its terminator; false at the end of the stream.
  bool next(std::string_view& line);
  /// 1-based number of the line last returned.
  int line_number() const { return line_; }
  /// "name:line" of the line last returned.
  std::string where() const;

 private:
  bool fill();  // refills buf_ from the stream; false at its end
  std::istream& in_;
  std::string name_;
  /// The chunk read at once: 4 KiB, growing x4 per full read up to 64 KiB (a small file
  /// costs a small buffer). Not zeroed: only what was read is used.
  std::unique_ptr<char[]> buf_;
  std::size_t capacity_ = 0, pos_ = 0, end_ = 0;
  std::string line_buf_;
  bool eof_ = false, started_ = false;
  int line_ = 0;
};

/// True for the whitespace that separates tokens: space, tab, form feed, vertical tab.
inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }

/// Splits a line into blank-separated fields (replacing `out`'s content), '#' included.
void split_fields(std::string_view line, std::vector<std::string_view>& out);

/// Splits a line into blank-separated tokens (replacing `out`'s content); a token starting
/// with '#' begins a comment that runs to the end of the line.
void split_tokens(std::string_view line, std::vector<std::string_view>& out);

/// Tokens [first, end) joined by single spaces: how names with spaces (`newmtl Hard Shiny
/// Plastic`) are read, so that runs of blanks and leading/trailing blanks do not matter.
std::string join_tokens(const std::vector<std::string_view>& tokens, std::size_t first);

}  // namespace lambert
