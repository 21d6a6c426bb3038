#include "io/ff_file.hpp"

#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/sampling.hpp"

namespace lambert {
namespace {

// Binary layout (little-endian), version 1:
//   char[8]  magic "LMBRTFF\0"
//   u32      version (1)          u32 flags (bit 0: standard errors follow the values)
//   i64      n                    i64 nnz
//   u64      mesh hash            u32 settings length, then that many bytes (UTF-8)
//   i32[n+1] row starts           i32[nnz] column indices       f64[nnz] values
//   f64[nnz] standard errors (if flag bit 0)
//   u64      checksum: mix64 chain over every byte above (detects truncation/corruption)
constexpr char kMagic[8] = {'L', 'M', 'B', 'R', 'T', 'F', 'F', '\0'};
constexpr std::uint32_t kVersion = 1;
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

FormFactors read_binary(std::istream& in, const std::string& path, std::uint64_t expected_hash,
                        std::int32_t expected_n, FormFactorFileInfo* info) {
  Reader r(in, path);
  char magic[8];
  r.get(magic, 8);
  const auto version = r.get<std::uint32_t>();
  if (version != kVersion)
    throw IoError(path + ": unsupported form-factor file version " + std::to_string(version));
  const auto flags = r.get<std::uint32_t>();
  const auto n = r.get<std::int64_t>();
  const auto nnz = r.get<std::int64_t>();
  const auto hash = r.get<std::uint64_t>();
  const auto len = r.get<std::uint32_t>();
  // Bounds before any allocation: a corrupt header must not trigger a huge allocation or
  // signed overflow (n <= INT32_MAX makes n * n fit in 64 bits).
  if (n < 0 || n > INT32_MAX || nnz < 0 || nnz > n * n || nnz > INT32_MAX || len > (1u << 20))
    throw IoError(path + ": corrupt form-factor file header");
  std::string settings(len, '\0');
  r.get(settings.data(), len);
  check_identity(path, hash, n, expected_hash, expected_n);
  FormFactors ff;
  ff.F.resize(n, n);
  ff.F.resizeNonZeros(nnz);
  r.get(ff.F.outerIndexPtr(), sizeof(std::int32_t) * (n + 1));
  r.get(ff.F.innerIndexPtr(), sizeof(std::int32_t) * nnz);
  r.get(ff.F.valuePtr(), sizeof(double) * nnz);
  if (flags & 1u) {
    ff.stderr_F = ff.F;
    r.get(ff.stderr_F.valuePtr(), sizeof(double) * nnz);
  }
  const std::uint64_t computed = r.checksum();
  std::uint64_t stored;
  in.read(reinterpret_cast<char*>(&stored), sizeof stored);
  if (in.gcount() != sizeof stored || stored != computed)
    throw IoError(path + ": form-factor file is corrupt (checksum mismatch)");
  // Structural sanity, so that a corrupt file can never index out of bounds later.
  const auto* outer = ff.F.outerIndexPtr();
  bool ok = outer[0] == 0 && outer[n] == nnz;
  for (std::int64_t i = 0; ok && i < n; ++i) ok = outer[i] <= outer[i + 1];
  for (std::int64_t k = 0; ok && k < nnz; ++k)
    ok = ff.F.innerIndexPtr()[k] >= 0 && ff.F.innerIndexPtr()[k] < n;
  if (!ok) throw IoError(path + ": form-factor file is corrupt (bad indices)");
  if (info) *info = {hash, settings};
  return ff;
}

FormFactors read_matrix_market(std::istream& in, const std::string& path,
                               std::uint64_t expected_hash, std::int32_t expected_n,
                               FormFactorFileInfo* info) {
  std::string line;
  int lineno = 1;
  std::getline(in, line);
  if (line.rfind("%%MatrixMarket matrix coordinate real general", 0) != 0)
    throw IoError(path + ":1: not a Matrix Market 'coordinate real general' file");
  FormFactorFileInfo meta;
  bool have_hash = false;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    if (line[0] != '%') break;
    if (line.rfind(kMmHashKey, 0) == 0) {
      meta.mesh_hash = std::strtoull(line.c_str() + std::strlen(kMmHashKey), nullptr, 16);
      have_hash = true;
    } else if (line.rfind(kMmSettingsKey, 0) == 0) {
      meta.settings = line.substr(std::strlen(kMmSettingsKey));
    }
  }
  if (!have_hash)
    throw SceneError(path + ": no lambert mesh hash in the header: cannot check it belongs to "
                            "this scene");
  std::int64_t rows = 0, cols = 0, nnz = 0;
  std::istringstream size_line(line);
  if (!(size_line >> rows >> cols >> nnz) || rows != cols || rows < 0 || rows > INT32_MAX ||
      nnz < 0 || nnz > rows * rows || nnz > INT32_MAX)
    throw IoError(path + ":" + std::to_string(lineno) + ": malformed size line");
  check_identity(path, meta.mesh_hash, rows, expected_hash, expected_n);
  std::vector<Eigen::Triplet<double, std::int32_t>> t;
  t.reserve(nnz);
  for (std::int64_t k = 0; k < nnz; ++k) {
    ++lineno;
    std::int64_t i, j;
    double v;
    if (!std::getline(in, line)) throw IoError(path + ": truncated: expected " + std::to_string(nnz) + " entries");
    std::istringstream ls(line);
    if (!(ls >> i >> j >> v) || i < 1 || j < 1 || i > rows || j > rows || !std::isfinite(v))
      throw IoError(path + ":" + std::to_string(lineno) + ": malformed entry");
    t.emplace_back(static_cast<std::int32_t>(i - 1), static_cast<std::int32_t>(j - 1), v);
  }
  FormFactors ff;
  ff.F.resize(rows, rows);
  ff.F.setFromTriplets(t.begin(), t.end());
  if (info) *info = meta;
  return ff;
}

// strtoll/strtoull/strtod over the whole of `s`.
bool parse_int(const std::string& s, long long& v) {
  char* end = nullptr;
  errno = 0;
  v = std::strtoll(s.c_str(), &end, 10);
  return !s.empty() && *end == '\0' && errno == 0;
}
bool parse_uint(const std::string& s, std::uint64_t& v) {
  char* end = nullptr;
  errno = 0;
  v = std::strtoull(s.c_str(), &end, 10);
  return !s.empty() && s[0] != '-' && *end == '\0' && errno == 0;
}
bool parse_double(const std::string& s, double& v) {
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == '\0' && std::isfinite(v);
}

}  // namespace

std::string format_ff_settings(const FormFactorOptions& o) {
  char threshold[32];
  std::snprintf(threshold, sizeof threshold, "%.17g", o.threshold);
  return "estimator=" + o.estimator + " samples=" + std::to_string(o.samples) +
         " seed=" + std::to_string(o.seed) + " threshold=" + threshold +
         " hemicube_res=" + std::to_string(o.hemicube_resolution) +
         " symmetrize=" + (o.symmetrize ? "1" : "0");
}

bool parse_ff_settings(const std::string& text, FormFactorOptions& options) {
  FormFactorOptions o = options;
  bool estimator = false, samples = false, seed = false, threshold = false;
  std::istringstream in(text);
  for (std::string pair; in >> pair;) {
    const size_t eq = pair.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = pair.substr(0, eq), value = pair.substr(eq + 1);
    long long k = 0;
    if (key == "estimator") {
      o.estimator = value;
      estimator = !value.empty();
    } else if (key == "samples") {
      samples = parse_int(value, k) && k >= 1 && k <= INT32_MAX;
      o.samples = static_cast<int>(k);
    } else if (key == "seed") {
      seed = parse_uint(value, o.seed);
    } else if (key == "threshold") {
      threshold = parse_double(value, o.threshold);
    } else if (key == "hemicube_res") {
      if (!parse_int(value, k) || k < 1 || k > INT32_MAX) return false;
      o.hemicube_resolution = static_cast<int>(k);
    } else if (key == "symmetrize") {
      if (value != "0" && value != "1") return false;
      o.symmetrize = value == "1";
    }
  }
  if (!(estimator && samples && seed && threshold)) return false;
  options = o;
  return true;
}

void write_matrix_market(const std::string& path, const SparseF& F, const FormFactorFileInfo& info) {
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
        std::snprintf(buf, sizeof buf, "%d %d %.17g\n", i + 1, static_cast<int>(it.col()) + 1, it.value());
        out << buf;
      }
    }
  });
}

void write_ff_binary(const std::string& path, const FormFactors& ff, const FormFactorFileInfo& info) {
  LAMBERT_CHECK(ff.F.isCompressed(), "F must be compressed");
  write_stream_atomically(
      path,
      [&](std::ostream& out) {
        Writer w(out);
        const std::int64_t n = ff.F.rows(), nnz = ff.F.nonZeros();
        const bool err = ff.stderr_F.nonZeros() == nnz && nnz > 0;
        w.put(kMagic, 8);
        w.put(kVersion);
        w.put(static_cast<std::uint32_t>(err ? 1u : 0u));
        w.put(n);
        w.put(nnz);
        w.put(info.mesh_hash);
        w.put(static_cast<std::uint32_t>(info.settings.size()));
        w.put(info.settings.data(), info.settings.size());
        w.put(ff.F.outerIndexPtr(), sizeof(std::int32_t) * (n + 1));
        w.put(ff.F.innerIndexPtr(), sizeof(std::int32_t) * nnz);
        w.put(ff.F.valuePtr(), sizeof(double) * nnz);
        if (err) w.put(ff.stderr_F.valuePtr(), sizeof(double) * nnz);
        const std::uint64_t sum = w.checksum();
        out.write(reinterpret_cast<const char*>(&sum), sizeof sum);
      },
      true);
}

FormFactors read_form_factors(const std::string& path, std::uint64_t expected_mesh_hash,
                              std::int32_t expected_n, FormFactorFileInfo* info) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  char magic[8] = {};
  in.read(magic, 8);
  in.clear();
  in.seekg(0);
  if (std::memcmp(magic, kMagic, 8) == 0)
    return read_binary(in, path, expected_mesh_hash, expected_n, info);
  return read_matrix_market(in, path, expected_mesh_hash, expected_n, info);
}

}  // namespace lambert
