#include "io/ff_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstring>
#include <fstream>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/sampling.hpp"
#include "io/line_reader.hpp"
#include "io/strict_number.hpp"

namespace lambert {
namespace {

// Binary layout (little-endian), version 2:
//   char[8]  magic "LMBRTFF\0"
//   u32      version (2)          u32 flags (bit 0: standard errors follow the values;
//                                            bit 1: values and errors are f32, not f64)
//   i64      n                    i64 nnz
//   u64      mesh hash            u32 settings length, then that many bytes (UTF-8)
//   i64[n+1] row starts           i32[nnz] column indices       f64[nnz] values
//   f64[nnz] standard errors (if flag bit 0)                      (f32 for both if bit 1)
//   u64      checksum: mix64 chain over every byte above (detects truncation/corruption)
// Version 1 (read, never written) is the same with i32 row starts, so nnz < 2^31.
constexpr char kMagic[8] = {'L', 'M', 'B', 'R', 'T', 'F', 'F', '\0'};
constexpr std::uint32_t kVersion = 2;
// Arrays whose width on disk differs from memory go through a buffer of this many elements
// (a multiple of 8 bytes for 4- and 8-byte elements, so the checksum, a chain over 8-byte
// words, is the same as over the whole array in one piece).
constexpr std::int64_t kChunk = 1 << 14;
// The binary format is little-endian and read and written as raw memory: a big-endian host
// refuses it (reading and writing) rather than swapping, and is pointed to Matrix Market.
constexpr bool kHostIsLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
constexpr const char* kMmHashKey = "% lambert-mesh-hash: ";
constexpr const char* kMmSettingsKey = "% lambert-settings: ";

struct Checksum {
  std::uint64_t h = 0x6C616D62657274ull;
  void add(const void* data, size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::uint64_t word = 0;
    size_t k = 0;
    for (; k + 8 <= size; k += 8) {
      std::memcpy(&word, p + k, 8);
      h = mix64(h ^ word);
    }
    word = 0;
    if (k < size) {
      std::memcpy(&word, p + k, size - k);
      h = mix64(h ^ word ^ (size - k));
    }
  }
};

class Writer {
 public:
  explicit Writer(std::ostream& out) : out_(out) {}
  void put(const void* data, size_t size) {
    out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    sum_.add(data, size);
  }
  template <typename T>
  void put(const T& v) {
    put(&v, sizeof v);
  }
  /// Writes `count` elements of `from` as Disk (a narrowing the caller has checked).
  template <typename Disk, typename Mem>
  void put_array(const Mem* from, std::int64_t count) {
    std::vector<Disk> buf(static_cast<size_t>(std::min(count, kChunk)));
    for (std::int64_t at = 0; at < count; at += kChunk) {
      const std::int64_t m = std::min(kChunk, count - at);
      for (std::int64_t k = 0; k < m; ++k) buf[k] = static_cast<Disk>(from[at + k]);
      put(buf.data(), sizeof(Disk) * static_cast<size_t>(m));
    }
  }
  std::uint64_t checksum() const { return sum_.h; }

 private:
  std::ostream& out_;
  Checksum sum_;
};

class Reader {
 public:
  Reader(std::istream& in, const std::string& path) : in_(in), path_(path) {}
  void get(void* data, size_t size) {
    in_.read(static_cast<char*>(data), static_cast<std::streamsize>(size));
    if (static_cast<size_t>(in_.gcount()) != size)
      throw IoError(path_ + ": truncated form-factor file");
    sum_.add(data, size);
  }
  template <typename T>
  T get() {
    T v;
    get(&v, sizeof v);
    return v;
  }
  /// Reads `count` elements stored as Disk into `to`.
  template <typename Disk, typename Mem>
  void get_array(Mem* to, std::int64_t count) {
    std::vector<Disk> buf(static_cast<size_t>(std::min(count, kChunk)));
    for (std::int64_t at = 0; at < count; at += kChunk) {
      const std::int64_t m = std::min(kChunk, count - at);
      get(buf.data(), sizeof(Disk) * static_cast<size_t>(m));
      for (std::int64_t k = 0; k < m; ++k) to[at + k] = static_cast<Mem>(buf[k]);
    }
  }
  std::uint64_t checksum() const { return sum_.h; }

 private:
  std::istream& in_;
  const std::string& path_;
  Checksum sum_;
};

void check_identity(const std::string& path, std::uint64_t hash, std::int64_t n,
                    std::uint64_t expected_hash, std::int32_t expected_n) {
  if (n != expected_n || hash != expected_hash) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  ": made from a different scene or meshing (file: %" PRId64
                  " patches, mesh hash %016" PRIx64 "; now: %d patches, %016" PRIx64 ")",
                  n, hash, expected_n, expected_hash);
    throw SceneError(path + buf);
  }
}

// Checks shared by both readers. Every message is one line naming the file and the first
// offending entry. Entries are named by patch index (0-based, as in the radiosity CSV).

// A row sum above 1 + tolerance is refused. The values round-trip exactly (bits, or %.17g),
// so without stored errors only the summation rounds: Σ over m terms ≤ 1 errs by at most
// m·2^-53 ≈ 1.1e-16·m, below 1e-9 for any row of up to 9e6 entries.
constexpr double kRowSumRounding = 1e-9;
// With stored standard errors the allowance adds kRowSumErrors × Σ_j stderr_ij: the
// entries' errors may be fully correlated (hybrid's quadrature bound is 1e-6 × G of every
// pair), so the row sum's error is bounded by Σ_j stderr_ij, not by its root-sum-square; 4
// of them exceed a (correlated, normal) error with probability 3e-5 per row.
constexpr double kRowSumErrors = 4.0;

// The allowance above 1 of a row sum, from what the file states about its own error.
struct RowSumRule {
  bool check = true;  // false: a lambert F saved without errors, which states no bound
  bool with_errors = false;
};

RowSumRule row_sum_rule(const FormFactors& ff, const std::string& settings) {
  RowSumRule rule;
  rule.with_errors = ff.stderr_F.nonZeros() == ff.F.nonZeros() && ff.F.nonZeros() > 0;
  FormFactorOptions o;
  // lambert's estimators are noisy (mc: infinite variance for neighbours, a 64-sample mc F
  // of the Cornell box at 150 patches has row sums up to 1.77; hybrid's visible fraction
  // is sampled, 1.001 at 4 samples; the hemicube has its proximity error): saved without
  // errors they state no bound, so only their entries are checked. A file without lambert
  // settings (another tool's) gets the rounding allowance only.
  rule.check = rule.with_errors || !parse_ff_settings(settings, o);
  return rule;
}

// True when the settings describe extended form factors (specular paths included): a patch
// may then see itself through a mirror (diagonal entries) and rows count light again after
// each specular bounce.
bool extended_settings(const std::string& settings) {
  FormFactorOptions o;
  return parse_ff_settings(settings, o) && o.contents.extended;
}

// The number of participating-medium zones the settings say F holds after its patches
// (media.hpp: they are rows and columns n - zones .. n - 1; a zone extinguishes part of
// its own rays, so its diagonal may be nonzero), 0 for none.
std::int64_t medium_zones_of(const std::string& settings) {
  FormFactorOptions o;
  return parse_ff_settings(settings, o) ? o.contents.medium_zones : 0;
}

// The first row whose diagonal entry may be nonzero: every row of extended form factors (a
// patch sees itself through a mirror), the zone rows of a medium's, else none (n).
std::int64_t first_self_row(const std::string& settings, std::int64_t n) {
  return extended_settings(settings) ? 0 : n - medium_zones_of(settings);
}

// The zones the settings announce, checked against the matrix size n (IoError: a header
// that does not fit its matrix is corrupt).
std::int64_t checked_zones(const std::string& settings, std::int64_t n, const std::string& path) {
  const std::int64_t zones = medium_zones_of(settings);
  if (zones > n)
    throw IoError(path + ": corrupt header: " + std::to_string(zones) +
                  " medium zones in a matrix of " + std::to_string(n) + " rows");
  return zones;
}

std::string patch_pair(std::int64_t i, std::int64_t j) {
  return "entry (" + std::to_string(i) + ", " + std::to_string(j) + ")";
}

std::string value_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// What is physically wrong with the value of F_ij (or its standard error), or "".
std::string bad_value(double v, std::int64_t i, std::int64_t j, bool is_stderr, bool self_allowed) {
  const char* what = is_stderr ? "standard error" : "value";
  if (!std::isfinite(v)) return std::string(what) + " " + value_text(v) + " is not finite";
  if (v < 0) return std::string(what) + " " + value_text(v) + " is negative";
  if (!is_stderr && i == j && v != 0 && !self_allowed)
    return "nonzero diagonal " + value_text(v) + " (a planar patch sees none of itself)";
  return "";
}

// Row sums against 1: Σ_j F_ij ≤ 1 + kRowSumRounding + the file's stated error (row_sum_rule).
// `value_rounding`: the relative rounding of each stored value (0 for f64 values, which
// kRowSumRounding covers; 2^-24 for f32), so a sum of n rounded values may exceed the
// exact one by value_rounding times itself; `row_rounding` (text files): per row, the sum
// of the half units in the last digit of its values as written.
void check_row_sums(const FormFactors& ff, const std::string& settings, const std::string& path,
                    double value_rounding = 0.0,
                    const std::vector<double>* row_rounding = nullptr) {
  const RowSumRule rule = row_sum_rule(ff, settings);
  // Extended rows exceed 1 by what they carried on (specular_continued); without it (a
  // Matrix Market file) they state no bound.
  const bool extended = extended_settings(settings);
  if (extended && ff.specular_continued.size() != ff.F.rows()) return;
  for (std::int32_t i = 0; rule.check && i < ff.F.outerSize(); ++i) {
    double sum = 0, err = 0;
    const auto begin = ff.F.outerIndexPtr()[i], end = ff.F.outerIndexPtr()[i + 1];
    for (auto k = begin; k < end; ++k) {
      sum += ff.F.valuePtr()[k];
      if (rule.with_errors) err += ff.stderr_F.valuePtr()[k];
    }
    const double allowed = 1.0 + kRowSumRounding + kRowSumErrors * err + value_rounding * sum +
                           (row_rounding ? (*row_rounding)[i] : 0.0) +
                           (extended ? ff.specular_continued[i] : 0.0);
    if (sum > allowed)
      throw SceneError(path + ": row of patch " + std::to_string(i) + " sums to " +
                       value_text(sum) + ", above 1 by more than its stated error (allowed " +
                       value_text(allowed) + "): not a form-factor matrix");
  }
}

// Binary structure and values: row starts from 0 to nnz and monotone, columns in range,
// strictly increasing within a row, values (and standard errors) finite, non-negative,
// zero on the diagonal. Linear in nnz.
void check_binary_entries(const FormFactors& ff, const std::string& path, std::int64_t self_from) {
  const std::int64_t n = ff.F.rows(), nnz = ff.F.nonZeros();
  const auto* outer = ff.F.outerIndexPtr();
  const auto* col = ff.F.innerIndexPtr();
  const bool with_err = ff.stderr_F.nonZeros() == nnz && nnz > 0;
  auto corrupt = [&](const std::string& what) { return IoError(path + ": " + what); };
  if (outer[0] != 0) throw corrupt("row starts begin at " + std::to_string(outer[0]) + ", not 0");
  if (outer[n] != nnz)
    throw corrupt("row starts end at " + std::to_string(outer[n]) + ", not at nnz " +
                  std::to_string(nnz));
  for (std::int64_t i = 0; i < n; ++i) {
    if (outer[i + 1] < outer[i])
      throw corrupt("row starts decrease at patch " + std::to_string(i + 1));
    if (outer[i + 1] > nnz)
      throw corrupt("row start of patch " + std::to_string(i + 1) + " beyond nnz");
    for (auto k = outer[i]; k < outer[i + 1]; ++k) {
      if (col[k] < 0 || col[k] >= n)
        throw corrupt("patch " + std::to_string(i) + ": column " + std::to_string(col[k]) +
                      " out of range [0, " + std::to_string(n) + ")");
      if (k > outer[i] && col[k] <= col[k - 1])
        throw corrupt(patch_pair(i, col[k]) + (col[k] == col[k - 1] ? " repeated" : " unsorted") +
                      " (columns must increase within a row)");
      std::string why = bad_value(ff.F.valuePtr()[k], i, col[k], false, i >= self_from);
      if (why.empty() && with_err)
        why = bad_value(ff.stderr_F.valuePtr()[k], i, col[k], true, i >= self_from);
      if (!why.empty()) throw SceneError(path + ": " + patch_pair(i, col[k]) + ": " + why);
    }
  }
}

// Size of the file behind `in` (from the current end), restoring the position to 0.
std::int64_t stream_size(std::istream& in, const std::string& path) {
  in.clear();
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0);
  if (size < 0 || !in) throw IoError(path + ": cannot determine the file size (not a regular file?)");
  return size;
}

constexpr std::int64_t kBinaryHeaderBytes = 8 + 4 + 4 + 8 + 8 + 8 + 4;
// Header flags; kContinued: f64[n] specular_continued follow the values and errors
// (extended form factors, specular.hpp).
constexpr std::uint32_t kWithErrors = 1u, kFloatValues = 2u, kContinued = 4u;
constexpr double kFloatRounding = 0x1p-24;  // relative rounding of a double stored as f32

// The byte count a binary F file with this header has: header, settings, row starts,
// columns, values (and standard errors), checksum; INT64_MAX for a size beyond 4e18 bytes.
// With n < 2^31 and nnz <= n^2 (< 2^62) a corrupt header's 20 nnz overflows 64 bits (ff_fuzz
// found 12 nnz doing so): the size is first estimated in double (relative error ~1e-15), and
// summed in 64 bits only when it is far below their limit (9.2e18).
std::int64_t binary_size(std::uint32_t version, std::int64_t n, std::int64_t nnz,
                         std::uint32_t len, std::uint32_t flags) {
  const std::int64_t row_start_bytes = version == 1 ? 4 : 8;
  const std::int64_t value_bytes = flags & kFloatValues ? 4 : 8;
  const std::int64_t per_entry = 4 + value_bytes + (flags & kWithErrors ? value_bytes : 0);
  const std::int64_t per_row = row_start_bytes + (flags & kContinued ? 8 : 0);
  const double estimate = static_cast<double>(per_row) * static_cast<double>(n) +
                          static_cast<double>(per_entry) * static_cast<double>(nnz);
  if (estimate > 4e18) return INT64_MAX;
  return kBinaryHeaderBytes + len + row_start_bytes + per_row * n + per_entry * nnz + 8;
}

FormFactors read_binary(std::istream& in, const std::string& path, std::uint64_t expected_hash,
                        std::int32_t expected_n, FormFactorFileInfo* info) {
  if (!kHostIsLittleEndian)
    throw IoError(path + ": binary form-factor files are little-endian and this host is not: "
                         "use a Matrix Market (.mtx) file");
  const std::int64_t file_size = stream_size(in, path);
  Reader r(in, path);
  char magic[8];
  r.get(magic, 8);
  const auto version = r.get<std::uint32_t>();
  if (version != 1 && version != kVersion)
    throw IoError(path + ": unsupported form-factor file version " + std::to_string(version) +
                  " (this lambert reads versions 1 and 2)");
  const auto flags = r.get<std::uint32_t>();
  const auto n = r.get<std::int64_t>();
  const auto nnz = r.get<std::int64_t>();
  const auto hash = r.get<std::uint64_t>();
  const auto len = r.get<std::uint32_t>();
  // Bounds before any allocation: a corrupt header must not trigger a huge allocation or
  // signed overflow (n <= INT32_MAX makes n * n fit in 64 bits).
  const std::uint32_t known =
      version == 1 ? kWithErrors : kWithErrors | kFloatValues | kContinued;
  if (flags & ~known)
    throw IoError(path + ": corrupt header: unknown flags " + std::to_string(flags));
  if (n < 0 || n > INT32_MAX || nnz < 0 || nnz > n * n || (version == 1 && nnz > INT32_MAX) ||
      len > (1u << 20))
    throw IoError(path + ": corrupt header (n " + std::to_string(n) + ", nnz " +
                  std::to_string(nnz) + ", settings length " + std::to_string(len) + ")");
  const std::int64_t implied = binary_size(version, n, nnz, len, flags);
  if (implied != file_size)
    throw IoError(path + ": " + (implied > file_size ? "truncated" : "trailing bytes") +
                  ": the header (n " + std::to_string(n) + ", nnz " + std::to_string(nnz) +
                  ") implies " + std::to_string(implied) + " bytes, the file has " +
                  std::to_string(file_size));
  std::string settings(len, '\0');
  r.get(settings.data(), len);
  const std::int64_t zones = checked_zones(settings, n, path);
  if (expected_n >= 0) check_identity(path, hash, n - zones, expected_hash, expected_n);
  FormFactors ff;
  ff.F.resize(n, n);
  ff.F.resizeNonZeros(nnz);
  if (version == 1)
    r.get_array<std::int32_t>(ff.F.outerIndexPtr(), n + 1);
  else
    r.get_array<std::int64_t>(ff.F.outerIndexPtr(), n + 1);
  r.get_array<std::int32_t>(ff.F.innerIndexPtr(), nnz);
  const bool f32 = flags & kFloatValues;
  if (f32)
    r.get_array<float>(ff.F.valuePtr(), nnz);
  else
    r.get(ff.F.valuePtr(), sizeof(double) * nnz);
  if (flags & kWithErrors) {
    ff.stderr_F = ff.F;
    if (f32)
      r.get_array<float>(ff.stderr_F.valuePtr(), nnz);
    else
      r.get(ff.stderr_F.valuePtr(), sizeof(double) * nnz);
  }
  if (flags & kContinued) {
    ff.specular_continued.resize(n);
    r.get(ff.specular_continued.data(), sizeof(double) * n);
  }
  const std::uint64_t computed = r.checksum();
  const auto stored = r.get<std::uint64_t>();
  if (stored != computed) throw IoError(path + ": form-factor file is corrupt (checksum mismatch)");
  if ((flags & kContinued) && !extended_settings(settings))
    throw IoError(path + ": corrupt header: specular bookkeeping (flag 4) without extended "
                         "form-factor settings (specular_depth)");
  for (Eigen::Index i = 0; i < ff.specular_continued.size(); ++i)
    if (!(ff.specular_continued[i] >= 0.0) || !std::isfinite(ff.specular_continued[i]))
      throw SceneError(path + ": specular bookkeeping of patch " + std::to_string(i) + " is " +
                       value_text(ff.specular_continued[i]) + " (must be finite and >= 0)");
  check_binary_entries(ff, path, first_self_row(settings, n));
  check_row_sums(ff, settings, path, f32 ? kFloatRounding : 0.0);
  if (info) *info = {hash, settings};
  return ff;
}

// Matrix Market: every entry line is "i j value" (1-based), at least 6 bytes with its
// newline ("1 2 0\n"), which bounds the entry count by the file size before reserving.
constexpr std::int64_t kMinEntryBytes = 6;

struct MmEntry {
  std::int32_t i, j;  // 0-based
  double v;
  int line;
  double half_ulp;  // half a unit in the last decimal digit written: the text's rounding
};

// Half a unit in the last digit of a decimal number as written ("0.1234" -> 5e-5,
// "1.5e-3" -> 5e-5, "3" -> 0.5), so a sum of written values is within the sum of these of
// the values before they were written.
double half_unit_in_last_digit(std::string_view text) {
  const size_t e = text.find_first_of("eE");
  const std::string_view mantissa = text.substr(0, e);
  const size_t dot = mantissa.find('.');
  const int decimals = dot == std::string_view::npos ? 0 : static_cast<int>(mantissa.size() - dot - 1);
  long exponent = 0;
  if (e != std::string_view::npos) {
    const std::string_view ex = text.substr(e + 1);
    const bool plus = !ex.empty() && ex[0] == '+';
    std::from_chars(ex.data() + plus, ex.data() + ex.size(), exponent);
  }
  exponent = std::clamp<long>(exponent - decimals, -400, 400);
  return 0.5 * std::pow(10.0, static_cast<double>(exponent));
}

bool equal_ignoring_case(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t k = 0; k < a.size(); ++k)
    if (std::tolower(static_cast<unsigned char>(a[k])) != std::tolower(static_cast<unsigned char>(b[k])))
      return false;
  return true;
}

bool is_blank_line(std::string_view line) {
  return std::all_of(line.begin(), line.end(), [](char c) { return is_blank(c); });
}

// The header line and the comments up to the size line (returned in `line`).
FormFactorFileInfo read_mm_header(LineReader& lines, std::string_view& line, bool& have_hash) {
  std::vector<std::string_view> tok;
  if (lines.next(line)) split_fields(line, tok);
  const char* expected[] = {"%%MatrixMarket", "matrix", "coordinate", "real", "general"};
  bool ok = tok.size() == 5;
  for (size_t k = 0; ok && k < 5; ++k) ok = equal_ignoring_case(tok[k], expected[k]);
  if (!ok) throw IoError(lines.where() + ": not a Matrix Market 'coordinate real general' file");
  FormFactorFileInfo meta;
  have_hash = false;
  const std::string_view hash_key = kMmHashKey, settings_key = kMmSettingsKey;
  while (lines.next(line)) {
    if (is_blank_line(line)) continue;
    if (line[0] != '%') return meta;
    if (line.substr(0, hash_key.size()) == hash_key) {
      const std::string_view hex = line.substr(hash_key.size());
      const auto [end, ec] = std::from_chars(hex.data(), hex.data() + hex.size(), meta.mesh_hash, 16);
      if (have_hash || ec != std::errc() || end != hex.data() + hex.size() || hex.size() != 16)
        throw SceneError(lines.where() + ": " + (have_hash ? "second mesh hash" :
                         "mesh hash must be 16 hexadecimal digits"));
      have_hash = true;
    } else if (line.substr(0, settings_key.size()) == settings_key) {
      meta.settings = std::string(line.substr(settings_key.size()));
    }
  }
  throw IoError(lines.where() + ": truncated: no size line");
}

// One entry line "i j value": exactly three fields, indices in [1, n], value finite, >= 0
// and 0 on the diagonal.
MmEntry parse_mm_entry(const LineReader& lines, std::string_view line, std::int64_t n,
                       std::int64_t self_from, std::vector<std::string_view>& tok) {
  split_fields(line, tok);
  if (tok.size() != 3)
    throw SceneError(lines.where() + ": expected 'row column value', found " +
                     std::to_string(tok.size()) + " fields");
  std::int64_t i = 0, j = 0;
  double v = 0;
  std::string why = parse_integer(tok[0], i);
  if (why.empty()) why = parse_integer(tok[1], j);
  if (!why.empty()) throw SceneError(lines.where() + ": index: " + why);
  why = parse_finite(tok[2], v);
  if (!why.empty()) throw SceneError(lines.where() + ": value '" + std::string(tok[2]) + "': " + why);
  if (i < 1 || i > n || j < 1 || j > n)
    throw SceneError(lines.where() + ": entry (" + std::to_string(i) + ", " + std::to_string(j) +
                     ") out of range [1, " + std::to_string(n) + "]");
  why = bad_value(v, i, j, false, i - 1 >= self_from);
  if (!why.empty()) throw SceneError(lines.where() + ": " + why);
  return {static_cast<std::int32_t>(i - 1), static_cast<std::int32_t>(j - 1), v, lines.line_number(),
          half_unit_in_last_digit(tok[2])};
}

// F from entries sorted by (row, column), refusing a repeated entry (Matrix Market would
// sum them; a form-factor file never has any). `rounding` gets each row's sum of half_ulp.
SparseF assemble_mm(std::vector<MmEntry>& entries, std::int64_t n, const std::string& path,
                    std::vector<double>& rounding) {
  rounding.assign(static_cast<size_t>(n), 0.0);
  std::sort(entries.begin(), entries.end(), [](const MmEntry& a, const MmEntry& b) {
    return a.i != b.i ? a.i < b.i : a.j != b.j ? a.j < b.j : a.line < b.line;
  });
  SparseF F(n, n);
  F.resizeNonZeros(static_cast<Eigen::Index>(entries.size()));
  auto* outer = F.outerIndexPtr();
  std::fill(outer, outer + n + 1, 0);
  for (size_t k = 0; k < entries.size(); ++k) {
    const MmEntry& e = entries[k];
    if (k > 0 && e.i == entries[k - 1].i && e.j == entries[k - 1].j)
      throw SceneError(path + ":" + std::to_string(e.line) + ": entry (" + std::to_string(e.i + 1) +
                       ", " + std::to_string(e.j + 1) + ") repeated (first on line " +
                       std::to_string(entries[k - 1].line) + ")");
    ++outer[e.i + 1];
    F.innerIndexPtr()[k] = e.j;
    F.valuePtr()[k] = e.v;
    rounding[e.i] += e.half_ulp;
  }
  for (std::int64_t i = 0; i < n; ++i) outer[i + 1] += outer[i];
  return F;
}

FormFactors read_matrix_market(std::istream& in, const std::string& path,
                               std::uint64_t expected_hash, std::int32_t expected_n,
                               FormFactorFileInfo* info) {
  const std::int64_t file_size = stream_size(in, path);
  LineReader lines(in, path);
  std::string_view line;
  bool have_hash = false;
  const FormFactorFileInfo meta = read_mm_header(lines, line, have_hash);
  if (!have_hash && expected_n >= 0)
    throw SceneError(path + ": no lambert mesh hash in the header: cannot check it belongs to "
                            "this scene");
  std::vector<std::string_view> tok;
  split_fields(line, tok);
  std::int64_t rows = 0, cols = 0, nnz = 0;
  const bool parsed = tok.size() == 3 && parse_integer(tok[0], rows).empty() &&
                      parse_integer(tok[1], cols).empty() && parse_integer(tok[2], nnz).empty();
  if (!parsed || rows != cols || rows < 0 || rows > INT32_MAX || nnz < 0 || nnz > rows * rows)
    throw IoError(lines.where() + ": malformed size line (expected 'N N NNZ', a square matrix)");
  if (nnz > (file_size + 1) / kMinEntryBytes)
    throw IoError(lines.where() + ": truncated: the size line promises " + std::to_string(nnz) +
                  " entries, a file of " + std::to_string(file_size) + " bytes holds at most " +
                  std::to_string((file_size + 1) / kMinEntryBytes));
  const std::int64_t zones = checked_zones(meta.settings, rows, path);
  if (expected_n >= 0)
    check_identity(path, meta.mesh_hash, rows - zones, expected_hash, expected_n);
  const std::int64_t self_from = first_self_row(meta.settings, rows);
  std::vector<MmEntry> entries;
  entries.reserve(static_cast<size_t>(nnz));
  while (lines.next(line)) {
    if (is_blank_line(line)) continue;
    if (static_cast<std::int64_t>(entries.size()) == nnz)
      throw SceneError(lines.where() + ": extra line after the " + std::to_string(nnz) +
                       " entries the size line announced");
    entries.push_back(parse_mm_entry(lines, line, rows, self_from, tok));
  }
  if (static_cast<std::int64_t>(entries.size()) != nnz)
    throw IoError(path + ": truncated: " + std::to_string(entries.size()) + " of " +
                  std::to_string(nnz) + " entries");
  FormFactors ff;
  std::vector<double> rounding;
  ff.F = assemble_mm(entries, rows, path, rounding);
  check_row_sums(ff, meta.settings, path, 0.0, &rounding);
  if (info) *info = meta;
  return ff;
}

}  // namespace

void write_matrix_market(const std::string& path, const SparseF& F, const FormFactorFileInfo& info,
                         ValuePrecision precision) {
  // %.17g round-trips a double; float precision writes 9 significant digits (a float's
  // worth), whose rounding the reader allows for in row sums (half_unit_in_last_digit).
  const bool f32 = precision == ValuePrecision::Float;
  write_stream_atomically(path, [&](std::ostream& out) {
    char buf[96];
    out << "%%MatrixMarket matrix coordinate real general\n";
    out << "% lambert form factors: entry (i, j) = F_ij, the fraction of the power leaving patch i that reaches patch j\n";
    std::snprintf(buf, sizeof buf, "%016" PRIx64, info.mesh_hash);
    out << kMmHashKey << buf << '\n';
    out << kMmSettingsKey << info.settings << '\n';
    out << F.rows() << ' ' << F.cols() << ' ' << F.nonZeros() << '\n';
    for (std::int32_t i = 0; i < F.outerSize(); ++i) {
      for (SparseF::InnerIterator it(F, i); it; ++it) {
        if (f32)
          std::snprintf(buf, sizeof buf, "%d %d %.9g\n", i + 1, static_cast<int>(it.col()) + 1,
                        it.value());
        else
          std::snprintf(buf, sizeof buf, "%d %d %.17g\n", i + 1, static_cast<int>(it.col()) + 1,
                        it.value());
        out << buf;
      }
    }
  });
}

void write_ff_binary(const std::string& path, const FormFactors& ff, const FormFactorFileInfo& info,
                     ValuePrecision precision) {
  const bool f32 = precision == ValuePrecision::Float;
  LAMBERT_CHECK(ff.F.isCompressed(), "F must be compressed");
  if (!kHostIsLittleEndian)
    throw IoError(path + ": binary form-factor files are little-endian and this host is not: "
                         "write a Matrix Market (.mtx) file");
  write_stream_atomically(
      path,
      [&](std::ostream& out) {
        Writer w(out);
        const std::int64_t n = ff.F.rows(), nnz = ff.F.nonZeros();
        const bool err = ff.stderr_F.nonZeros() == nnz && nnz > 0;
        const bool continued = ff.specular_continued.size() == n && n > 0;
        w.put(kMagic, 8);
        w.put(kVersion);
        w.put(static_cast<std::uint32_t>((err ? kWithErrors : 0u) | (f32 ? kFloatValues : 0u) |
                                         (continued ? kContinued : 0u)));
        w.put(n);
        w.put(nnz);
        w.put(info.mesh_hash);
        w.put(static_cast<std::uint32_t>(info.settings.size()));
        w.put(info.settings.data(), info.settings.size());
        w.put_array<std::int64_t>(ff.F.outerIndexPtr(), n + 1);
        w.put_array<std::int32_t>(ff.F.innerIndexPtr(), nnz);  // columns < n <= 2^31
        if (f32) {
          w.put_array<float>(ff.F.valuePtr(), nnz);
          if (err) w.put_array<float>(ff.stderr_F.valuePtr(), nnz);
        } else {
          w.put(ff.F.valuePtr(), sizeof(double) * nnz);
          if (err) w.put(ff.stderr_F.valuePtr(), sizeof(double) * nnz);
        }
        if (continued) w.put(ff.specular_continued.data(), sizeof(double) * n);
        const std::uint64_t sum = w.checksum();
        out.write(reinterpret_cast<const char*>(&sum), sizeof sum);
      },
      true);
}

FormFactors read_form_factors(std::istream& in, const std::string& name,
                              std::uint64_t expected_mesh_hash, std::int32_t expected_n,
                              FormFactorFileInfo* info) {
  char magic[8] = {};
  in.read(magic, 8);
  in.clear();
  in.seekg(0);
  if (std::memcmp(magic, kMagic, 8) == 0)
    return read_binary(in, name, expected_mesh_hash, expected_n, info);
  return read_matrix_market(in, name, expected_mesh_hash, expected_n, info);
}

FormFactors read_form_factors(const std::string& path, std::uint64_t expected_mesh_hash,
                              std::int32_t expected_n, FormFactorFileInfo* info) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  return read_form_factors(in, path, expected_mesh_hash, expected_n, info);
}

}  // namespace lambert
