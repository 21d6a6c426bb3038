#include "io/ff_file.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "core/sampling.hpp"
#include "geometry/analytic.hpp"

namespace lambert {
namespace {

struct Fixture {
  PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  FormFactors ff = [this] {
    FormFactorOptions o;
    o.pair.samples = 4;
    o.run.with_stderr = true;
    o.run.progress = false;
    return compute_form_factors(mesh, o);
  }();
  FormFactorFileInfo info{mesh_hash(mesh), "estimator=hybrid samples=4"};
};

void expect_same(const SparseF& a, const SparseF& b) {
  ASSERT_EQ(a.rows(), b.rows());
  ASSERT_EQ(a.nonZeros(), b.nonZeros());
  for (std::int64_t k = 0; k < a.nonZeros(); ++k) {
    ASSERT_EQ(a.innerIndexPtr()[k], b.innerIndexPtr()[k]);
    // %.17g round-trips a double exactly; the binary format stores the bits.
    ASSERT_EQ(a.valuePtr()[k], b.valuePtr()[k]);
  }
}

}  // namespace

TEST(FormFactorFile, MatrixMarketRoundTripsExactly) {
  Fixture f;
  testing::TempDir dir;
  write_matrix_market(dir.file("F.mtx"), f.ff.F, f.info);
  FormFactorFileInfo info;
  const FormFactors back = read_form_factors(dir.file("F.mtx"), f.info.mesh_hash, f.mesh.size(), &info);
  expect_same(f.ff.F, back.F);
  EXPECT_EQ(info.settings, f.info.settings);
  std::ifstream in(dir.file("F.mtx"));
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "%%MatrixMarket matrix coordinate real general");
}

TEST(FormFactorFile, BinaryRoundTripsValuesAndErrors) {
  Fixture f;
  testing::TempDir dir;
  write_ff_binary(dir.file("F.bin"), f.ff, f.info);
  const FormFactors back = read_form_factors(dir.file("F.bin"), f.info.mesh_hash, f.mesh.size());
  expect_same(f.ff.F, back.F);
  expect_same(f.ff.stderr_F, back.stderr_F);
}

TEST(FormFactorFile, FileFromAnotherMeshIsRefused) {
  Fixture f;
  testing::TempDir dir;
  write_ff_binary(dir.file("F.bin"), f.ff, f.info);
  write_matrix_market(dir.file("F.mtx"), f.ff.F, f.info);
  const PatchMesh other = mesh_scene(unit_cube(), {0.3, 0});
  for (const char* name : {"F.bin", "F.mtx"}) {
    try {
      read_form_factors(dir.file(name), mesh_hash(other), other.size());
      FAIL() << name;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("different scene or meshing"), std::string::npos);
    }
    // Same size, different geometry: the hash alone must catch it.
    EXPECT_THROW(read_form_factors(dir.file(name), f.info.mesh_hash ^ 1, f.mesh.size()), SceneError);
  }
}

TEST(FormFactorFile, TruncatedOrCorruptBinaryIsRefused) {
  Fixture f;
  testing::TempDir dir;
  write_ff_binary(dir.file("F.bin"), f.ff, f.info);
  std::ifstream in(dir.file("F.bin"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir.file("cut.bin"), std::ios::binary) << bytes.substr(0, bytes.size() - 20);
  EXPECT_THROW(read_form_factors(dir.file("cut.bin"), f.info.mesh_hash, f.mesh.size()), IoError);
  bytes[bytes.size() / 2] ^= 0x40;
  std::ofstream(dir.file("flip.bin"), std::ios::binary) << bytes;
  EXPECT_THROW(read_form_factors(dir.file("flip.bin"), f.info.mesh_hash, f.mesh.size()), IoError);
}

}  // namespace lambert

namespace lambert {

TEST(FormFactorFile, SettingsTextRecoversEverySettingExactly) {
  FormFactorOptions o;
  o.estimator = "hemicube";
  o.pair.samples = 77;
  o.run.seed = 18446744073709551615ull;  // the largest seed: all 64 bits survive
  o.threshold = 1.0 / 3.0;           // %.17g reads back to the same double
  o.hemicube.resolution = 96;
  o.gather.rays = 4321;
  o.reciprocity = "average";
  FormFactorOptions back;
  ASSERT_TRUE(parse_ff_settings(format_ff_settings(o) + " patches=24 max_edge=0.5", back));
  EXPECT_EQ(back.estimator, "hemicube");
  EXPECT_EQ(back.pair.samples, 77);
  EXPECT_EQ(back.run.seed, o.run.seed);
  EXPECT_EQ(back.threshold, o.threshold);
  EXPECT_EQ(back.hemicube.resolution, 96);
  EXPECT_EQ(back.gather.rays, 4321);
  EXPECT_EQ(back.reciprocity, "average");
}

TEST(FormFactorFile, SymmetrizeKeyOfOlderFilesReadsAsReciprocity) {
  FormFactorOptions o;
  ASSERT_TRUE(parse_ff_settings(
      "estimator=hemicube samples=32 seed=1 threshold=0 hemicube_res=64 symmetrize=1", o));
  EXPECT_EQ(o.reciprocity, "average");
  EXPECT_EQ(o.gather.rays, FormFactorOptions().gather.rays);  // absent: kept
}

TEST(FormFactorFile, SettingsOfOlderFilesAreRecoveredAndForeignTextIsRefused) {
  // What `formfactors` wrote before every key was stored: no hemicube_res/symmetrize.
  FormFactorOptions o;
  ASSERT_TRUE(
      parse_ff_settings("estimator=mc samples=64 seed=5 threshold=0 patches=9 max_edge=1", o));
  EXPECT_EQ(o.estimator, "mc");
  EXPECT_EQ(o.pair.samples, 64);
  EXPECT_EQ(o.run.seed, 5u);
  EXPECT_EQ(o.reciprocity, "none");
  for (const char* foreign :
       {"", "made by hand", "estimator=mc samples=64", "estimator=mc samples=x seed=1 threshold=0",
        "estimator=mc samples=4 seed=-1 threshold=0"}) {
    FormFactorOptions untouched;
    untouched.estimator = "keep";
    EXPECT_FALSE(parse_ff_settings(foreign, untouched)) << foreign;
    EXPECT_EQ(untouched.estimator, "keep") << foreign;
  }
}

TEST(FormFactorFile, MatrixMarketKeepsTheSettingsInItsHeaderComments) {
  Fixture f;
  testing::TempDir dir;
  FormFactorOptions o;
  o.estimator = "mc";
  o.pair.samples = 64;
  o.run.seed = 5;
  write_matrix_market(dir.file("F.mtx"), f.ff.F, {f.info.mesh_hash, format_ff_settings(o)});
  std::ifstream in(dir.file("F.mtx"));
  bool found = false;
  for (std::string line; std::getline(in, line) && line[0] == '%';)
    found = found || line == "% lambert-settings: " + format_ff_settings(o);
  EXPECT_TRUE(found);
  FormFactorFileInfo info;
  read_form_factors(dir.file("F.mtx"), f.info.mesh_hash, f.mesh.size(), &info);
  FormFactorOptions back;
  ASSERT_TRUE(parse_ff_settings(info.settings, back));
  EXPECT_EQ(back.estimator, "mc");
  EXPECT_EQ(back.pair.samples, 64);
  EXPECT_EQ(back.run.seed, 5u);
}

}  // namespace lambert

// Hostile form-factor files (issue 10): each is generated here and must be refused with one
// message naming the file and the first offending entry, never crash or allocate by its
// header.
namespace lambert {
namespace {

constexpr std::uint64_t kHash = 0x1234;

// A 3-patch F with the given CSR arrays, written with write_ff_binary (so the checksum is
// valid and only the content is wrong).
std::string write_csr(const testing::TempDir& dir, std::vector<std::int32_t> outer,
                      std::vector<std::int32_t> cols, std::vector<double> values,
                      std::vector<double> errors = {}, const std::string& settings = "") {
  const auto put = [&](SparseF& m, const std::vector<double>& v) {
    m.resize(3, 3);
    m.resizeNonZeros(static_cast<Eigen::Index>(cols.size()));
    std::copy(outer.begin(), outer.end(), m.outerIndexPtr());
    std::copy(cols.begin(), cols.end(), m.innerIndexPtr());
    std::copy(v.begin(), v.end(), m.valuePtr());
  };
  FormFactors ff;
  put(ff.F, values);
  if (!errors.empty()) put(ff.stderr_F, errors);
  const std::string path = dir.file("F.bin");
  write_ff_binary(path, ff, {kHash, settings});
  return path;
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The message of the error read_form_factors throws (of type E), or a failure.
template <typename E>
std::string refusal(const std::string& path, std::int32_t n = 3) {
  try {
    read_form_factors(path, kHash, n);
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << path << " was accepted";
  return "";
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST(FormFactorFile, BinaryHeaderImplyingMoreBytesIsTruncatedBeforeAllocating) {
  Fixture f;
  testing::TempDir dir;
  write_ff_binary(dir.file("F.bin"), f.ff, f.info);
  std::string bytes = bytes_of(dir.file("F.bin"));
  // n at byte 16, nnz at byte 24 (little-endian i64): the largest the header bounds allow,
  // a few hundred bytes of file; allocating by the header would take 2^31 × 20 B = 43 GB.
  const std::int64_t n = INT32_MAX, nnz = INT32_MAX;
  std::memcpy(&bytes[16], &n, 8);
  std::memcpy(&bytes[24], &nnz, 8);
  std::ofstream(dir.file("huge.bin"), std::ios::binary) << bytes;
  EXPECT_TRUE(has(refusal<IoError>(dir.file("huge.bin"), f.mesh.size()), "truncated"));
  // One flipped bit in nnz (still <= n^2) must also say truncated, not read garbage.
  bytes = bytes_of(dir.file("F.bin"));
  bytes[24] ^= 0x40;
  std::ofstream(dir.file("flip.bin"), std::ios::binary) << bytes;
  EXPECT_TRUE(has(refusal<IoError>(dir.file("flip.bin"), f.mesh.size()), "implies"));
  std::ofstream(dir.file("long.bin"), std::ios::binary) << bytes_of(dir.file("F.bin")) << "x";
  EXPECT_TRUE(has(refusal<IoError>(dir.file("long.bin"), f.mesh.size()), "trailing bytes"));
}

TEST(FormFactorFile, BinaryWithBadStructureIsRefused) {
  testing::TempDir dir;
  // Row starts must run from 0 to nnz and never decrease; columns in range, increasing.
  EXPECT_TRUE(has(refusal<IoError>(write_csr(dir, {0, 2, 1, 2}, {1, 2}, {.1, .1})),
                  "decrease at patch 2"));
  EXPECT_TRUE(has(refusal<IoError>(write_csr(dir, {1, 1, 2, 2}, {1, 2}, {.1, .1})), "begin at 1"));
  EXPECT_TRUE(has(refusal<IoError>(write_csr(dir, {0, 1, 2, 2}, {3, 2}, {.1, .1})),
                  "column 3 out of range"));
  EXPECT_TRUE(has(refusal<IoError>(write_csr(dir, {0, 2, 2, 2}, {2, 1}, {.1, .1})),
                  "entry (0, 1) unsorted"));
  EXPECT_TRUE(has(refusal<IoError>(write_csr(dir, {0, 2, 2, 2}, {1, 1}, {.1, .1})),
                  "entry (0, 1) repeated"));
}

TEST(FormFactorFile, BinaryWithImpossibleValuesIsRefused) {
  testing::TempDir dir;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 1, 2, 2}, {1, 0}, {.1, nan})),
                  "entry (1, 0): value nan is not finite"));
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 1, 2, 2}, {1, 0}, {inf, .1})),
                  "entry (0, 1): value inf"));
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 1, 2, 2}, {1, 0}, {.1, -.5})),
                  "entry (1, 0): value -0.5 is negative"));
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 1, 1, 2}, {1, 2}, {.1, .3})),
                  "entry (2, 2): nonzero diagonal"));
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 1, 2, 2}, {1, 0}, {.1, .1}, {.01, nan})),
                  "entry (1, 0): standard error nan"));
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 1, 2, 2}, {1, 0}, {.1, .1}, {-1, .1})),
                  "entry (0, 1): standard error -1 is negative"));
  // An explicit zero on the diagonal is harmless and accepted.
  EXPECT_NO_THROW(read_form_factors(write_csr(dir, {0, 1, 2, 2}, {0, 0}, {0, .5}), kHash, 3));
}

TEST(FormFactorFile, RowSumAboveOneByMoreThanTheStatedErrorIsRefused) {
  testing::TempDir dir;
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 2, 2, 2}, {1, 2}, {5, 5})),
                  "row of patch 0 sums to 10"));
  // Without stored errors only rounding is allowed (1e-9, see ff_file.cpp): 1 + 1e-8 fails,
  // 1 + 1e-10 passes.
  EXPECT_TRUE(has(refusal<SceneError>(write_csr(dir, {0, 2, 2, 2}, {1, 2}, {.5, .5 + 1e-8})),
                  "above 1 by more than its stated error"));
  EXPECT_NO_THROW(read_form_factors(write_csr(dir, {0, 2, 2, 2}, {1, 2}, {.5, .5 + 1e-10}), kHash, 3));
  // With stored errors the allowance is 1e-9 + 4 Σ_j stderr_ij: stderrs of 2e-9 each give
  // 1e-9 + 1.6e-8 = 1.7e-8, so an excess of 1e-8 passes and one of 3e-8 fails.
  EXPECT_NO_THROW(read_form_factors(
      write_csr(dir, {0, 2, 2, 2}, {1, 2}, {.5, .5 + 1e-8}, {2e-9, 2e-9}), kHash, 3));
  EXPECT_TRUE(has(refusal<SceneError>(
                      write_csr(dir, {0, 2, 2, 2}, {1, 2}, {.5, .5 + 3e-8}, {2e-9, 2e-9})),
                  "row of patch 0"));
  // A lambert F saved without errors states no bound (noisy estimators: mc row sums reach
  // 1.77 on the Cornell box): only its entries are checked.
  EXPECT_NO_THROW(read_form_factors(
      write_csr(dir, {0, 2, 2, 2}, {1, 2}, {.9, .9}, {},
                "estimator=hemicube samples=4 seed=0 threshold=0"),
      kHash, 3));
}

TEST(FormFactorFile, MatrixMarketWithHugeNnzInATinyFileIsTruncated) {
  testing::TempDir dir;
  // 115 bytes promising 2^31 - 1 entries: reserving them would take 34 GB.
  const std::string path = dir.write(
      "F.mtx", "%%MatrixMarket matrix coordinate real general\n% lambert-mesh-hash: "
               "0000000000001234\n100000 100000 2147483647\n1 2 0.5\n");
  EXPECT_TRUE(has(refusal<IoError>(path), "truncated: the size line promises 2147483647"));
}

TEST(FormFactorFile, MatrixMarketWithBadEntriesIsRefusedNamingTheLine) {
  testing::TempDir dir;
  const std::string head =
      "%%MatrixMarket matrix coordinate real general\n% lambert-mesh-hash: 0000000000001234\n";
  // {body after the header (line 3 is the size line), expected part of the message}
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"3 3 2\n1 2 0.25\n1 2 0.25\n", ":5: entry (1, 2) repeated (first on line 4)"},
      {"3 3 1\n1 2 -0.25\n", ":4: value -0.25 is negative"},
      {"3 3 1\n1 2 nan\n", ":4: value 'nan': not finite"},
      {"3 3 1\n1 2 1e400\n", ":4: value '1e400': out of the range"},
      {"3 3 1\n1 4 0.5\n", ":4: entry (1, 4) out of range [1, 3]"},
      {"3 3 1\n0 1 0.5\n", ":4: entry (0, 1) out of range"},
      {"3 3 1\n2 2 0.5\n", ":4: nonzero diagonal"},
      {"3 3 1\n1 2 0.5 extra\n", ":4: expected 'row column value', found 4 fields"},
      {"3 3 1\n1 2 0.5 % comment\n", ":4: expected 'row column value'"},
      {"3 3 1\n1 2 0.5\n2 1 0.5\n", ":5: extra line after the 1 entries"},
      {"3 3 3\n1 2 0.5\n2 1 0.5\n", ": truncated: 2 of 3 entries"},
      {"3 3 2\n1 2 0.75\n1 3 0.75\n", ": row of patch 0 sums to 1.5"},
      {"3 3 1 x\n1 2 0.5\n", ":3: malformed size line"},
      {"3 3 1\n1 2.0 0.5\n", ":4: index: not an integer"},
  };
  for (const auto& [body, expected] : cases) {
    const std::string path = dir.write("F.mtx", head + body);
    std::string message;
    try {
      read_form_factors(path, kHash, 3);
    } catch (const Error& e) {
      message = e.what();
    }
    EXPECT_TRUE(has(message, path + expected)) << body << "-> " << message;
  }
  // Blank lines (a final newline, CRLF) are fine.
  EXPECT_NO_THROW(read_form_factors(dir.write("ok.mtx", head + "3 3 2\r\n1 2 0.5\r\n\r\n2 1 0.5\r\n\n"), kHash, 3));
}

}  // namespace lambert

namespace lambert {
namespace {

// The file checksum (ff_file.cpp's Checksum), recomputed here to forge a version-1 file: a
// chain over 8-byte words, restarted word alignment at each field the writer puts.
std::uint64_t file_checksum(const std::string& bytes, const std::vector<size_t>& fields) {
  std::uint64_t h = 0x6C616D62657274ull;
  size_t at = 0;
  for (const size_t size : fields) {
    std::uint64_t word = 0;
    size_t k = 0;
    for (; k + 8 <= size; k += 8) {
      std::memcpy(&word, bytes.data() + at + k, 8);
      h = mix64(h ^ word);
    }
    word = 0;
    if (k < size) {
      std::memcpy(&word, bytes.data() + at + k, size - k);
      h = mix64(h ^ word ^ (size - k));
    }
    at += size;
  }
  return h;
}

}  // namespace

// Version 2 widened the row starts to 64 bits (nnz beyond 2^31); files written before, with
// 32-bit row starts, must still load, to the same matrix.
TEST(FormFactorFile, VersionOneFilesStillLoad) {
  Fixture f;
  testing::TempDir dir;
  write_ff_binary(dir.file("F.bin"), f.ff, f.info);
  const std::string v2 = bytes_of(dir.file("F.bin"));
  std::uint32_t version = 0, len = 0;
  std::memcpy(&version, &v2[8], 4);
  ASSERT_EQ(version, 2u);
  std::memcpy(&len, &v2[40], 4);
  const size_t starts = 44 + len, n = static_cast<size_t>(f.mesh.size());
  std::string v1 = v2.substr(0, starts);
  const std::uint32_t one = 1;
  std::memcpy(&v1[8], &one, 4);
  for (size_t i = 0; i <= n; ++i) {
    std::int64_t s = 0;
    std::memcpy(&s, &v2[starts + 8 * i], 8);
    const auto s32 = static_cast<std::int32_t>(s);
    v1.append(reinterpret_cast<const char*>(&s32), 4);
  }
  v1.append(v2, starts + 8 * (n + 1), v2.size() - 8 - (starts + 8 * (n + 1)));
  const size_t nnz = static_cast<size_t>(f.ff.F.nonZeros());
  const std::uint64_t sum = file_checksum(
      v1, {8, 4, 4, 8, 8, 8, 4, len, 4 * (n + 1), 4 * nnz, 8 * nnz, 8 * nnz});
  v1.append(reinterpret_cast<const char*>(&sum), 8);
  std::ofstream(dir.file("v1.bin"), std::ios::binary) << v1;
  const FormFactors back = read_form_factors(dir.file("v1.bin"), f.info.mesh_hash, f.mesh.size());
  expect_same(f.ff.F, back.F);
  expect_same(f.ff.stderr_F, back.stderr_F);
  // An unknown version is refused by number.
  std::string v9 = v2;
  v9[8] = 9;
  std::ofstream(dir.file("v9.bin"), std::ios::binary) << v9;
  EXPECT_TRUE(has(refusal<IoError>(dir.file("v9.bin"), f.mesh.size()), "version 9"));
}

}  // namespace lambert

namespace lambert {

// --ff-precision float: every value and error comes back as the nearest float (relative
// change <= 2^-24), the header says so, and the value arrays take half the bytes.
TEST(FormFactorFile, FloatPrecisionStoresTheNearestFloats) {
  Fixture f;
  testing::TempDir dir;
  write_ff_binary(dir.file("d.bin"), f.ff, f.info);
  write_ff_binary(dir.file("f.bin"), f.ff, f.info, ValuePrecision::Float);
  const FormFactors back = read_form_factors(dir.file("f.bin"), f.info.mesh_hash, f.mesh.size());
  ASSERT_EQ(back.F.nonZeros(), f.ff.F.nonZeros());
  ASSERT_EQ(back.stderr_F.nonZeros(), f.ff.F.nonZeros());
  for (std::int64_t k = 0; k < f.ff.F.nonZeros(); ++k) {
    ASSERT_EQ(back.F.innerIndexPtr()[k], f.ff.F.innerIndexPtr()[k]);
    EXPECT_EQ(back.F.valuePtr()[k], static_cast<double>(static_cast<float>(f.ff.F.valuePtr()[k])));
    EXPECT_LE(std::abs(back.F.valuePtr()[k] - f.ff.F.valuePtr()[k]), 0x1p-24 * f.ff.F.valuePtr()[k]);
    EXPECT_EQ(back.stderr_F.valuePtr()[k],
              static_cast<double>(static_cast<float>(f.ff.stderr_F.valuePtr()[k])));
  }
  const auto nnz = static_cast<std::int64_t>(f.ff.F.nonZeros());
  EXPECT_EQ(static_cast<std::int64_t>(bytes_of(dir.file("d.bin")).size() -
                                      bytes_of(dir.file("f.bin")).size()),
            2 * 4 * nnz);  // values and errors: 8 -> 4 bytes each
  // Matrix Market with float precision: 9 significant digits, a relative change of at most
  // 5e-9; the reader allows row sums that rounding (a 4-sample F of the unit cube has rows
  // just above 1).
  write_matrix_market(dir.file("f.mtx"), f.ff.F, f.info, ValuePrecision::Float);
  const FormFactors mm = read_form_factors(dir.file("f.mtx"), f.info.mesh_hash, f.mesh.size());
  for (std::int64_t k = 0; k < f.ff.F.nonZeros(); ++k)
    EXPECT_LE(std::abs(mm.F.valuePtr()[k] - f.ff.F.valuePtr()[k]), 5e-9 * f.ff.F.valuePtr()[k]);
}

}  // namespace lambert

namespace lambert {

// A foreign Matrix Market file written with 6 significant digits (View3D-style output):
// its row sums may exceed 1 by the rounding of the digits written, and no more.
TEST(FormFactorFile, TextRowSumsAllowTheRoundingOfTheDigitsWritten) {
  testing::TempDir dir;
  const auto mm = [&](const std::string& a, const std::string& b) {
    const std::string path = dir.file("v.mtx");
    std::ofstream(path) << "%%MatrixMarket matrix coordinate real general\n3 3 2\n1 2 " << a
                        << "\n1 3 " << b << "\n";
    return path;
  };
  // 0.500001 + 0.500000 = 1 + 1e-6: within the two half units of 5e-7 each.
  EXPECT_NO_THROW(read_form_factors(mm("0.500001", "0.500000"), 0, -1));
  EXPECT_NO_THROW(read_form_factors(mm("5.00001e-1", "5e-1"), 0, -1));  // 5e-7 + 5e-2 allowed
  // 0.500002 + 0.500000 = 1 + 2e-6 is above 1 + 1e-6 + 1e-9.
  EXPECT_THROW(read_form_factors(mm("0.500002", "0.500000"), 0, -1), SceneError);
}

// Regression of the review: the specular bookkeeping (flag 4) is only meaningful for
// extended form factors; a file that carries it with plain settings is a corrupt header.
TEST(FormFactorFile, SpecularBookkeepingWithoutExtendedSettingsIsRefused) {
  Fixture f;
  testing::TempDir dir;
  f.ff.specular_continued = Eigen::VectorXd::Zero(f.mesh.size());
  write_ff_binary(dir.file("F.bin"), f.ff, f.info);
  EXPECT_THROW(read_form_factors(dir.file("F.bin"), f.info.mesh_hash, f.mesh.size()), IoError);
  // With extended settings it loads and keeps the vector.
  FormFactorFileInfo extended = f.info;
  extended.settings = "estimator=hybrid samples=4 seed=1 threshold=0 specular_depth=8 specular_rays=64";
  write_ff_binary(dir.file("G.bin"), f.ff, extended);
  const FormFactors back = read_form_factors(dir.file("G.bin"), f.info.mesh_hash, f.mesh.size());
  EXPECT_EQ(back.specular_continued.size(), f.mesh.size());
}

TEST(FormFactorFile, MediumZonesFollowThePatchesAndMaySeeThemselves) {
  // A 3 x 3 F with settings announcing 1 medium zone: 2 patches, then zone 2, whose rays are
  // partly extinguished in itself (a nonzero diagonal in its row only).
  testing::TempDir dir;
  const std::string settings =
      "estimator=hybrid samples=4 seed=1 threshold=0 medium_zones=1 medium_extinction=77 "
      "medium_rays=16 transmittance_samples=4";
  const std::string path =
      write_csr(dir, {0, 1, 2, 4}, {2, 2, 0, 2}, {.3, .3, .2, .4}, {}, settings);
  FormFactorFileInfo info;
  const FormFactors ff = read_form_factors(path, kHash, 2, &info);  // the mesh has 2 patches
  EXPECT_EQ(ff.F.rows(), 3);
  FormFactorOptions o;
  ASSERT_TRUE(parse_ff_settings(info.settings, o));
  EXPECT_EQ(o.contents.medium_zones, 1);
  EXPECT_EQ(o.contents.medium_extinction, 77u);
  EXPECT_EQ(o.contents.medium_rays, 16);
  EXPECT_EQ(o.contents.transmittance_samples, 4);
  // The same file is from another mesh for 3 patches, and a patch row still sees none of
  // itself.
  EXPECT_TRUE(has(refusal<SceneError>(path, 3), "different scene"));
  const std::string patch_diag =
      write_csr(dir, {0, 1, 2, 3}, {0, 2, 2}, {.3, .3, .4}, {}, settings);
  EXPECT_TRUE(has(refusal<SceneError>(patch_diag, 2), "entry (0, 0): nonzero diagonal"));
  // More zones than rows is a corrupt header; the settings survive a round trip.
  const std::string too_many =
      write_csr(dir, {0, 1, 2, 4}, {2, 2, 0, 2}, {.3, .3, .2, .4}, {},
                "estimator=hybrid samples=4 seed=1 threshold=0 medium_zones=5");
  EXPECT_TRUE(has(refusal<IoError>(too_many, 2), "5 medium zones in a matrix of 3 rows"));
  FormFactorOptions back;
  ASSERT_TRUE(parse_ff_settings(format_ff_settings(o), back));
  EXPECT_EQ(back.contents.medium_zones, 1);
  EXPECT_EQ(back.contents.medium_extinction, 77u);
}

}  // namespace lambert

namespace lambert {

TEST(FormFactorFile, AHeaderWhoseSizeOverflows64BitsIsRefusedAsTruncated) {
  // ff_fuzz's find: n = 905,969,666 (< 2^31) and nnz = 7.9e17 (<= n^2) pass the header's
  // bounds, but the implied size, 12 nnz bytes, overflowed int64 (UBSan: signed overflow).
  std::string bytes("LMBRTFF\0", 8);
  const auto put = [&](auto v) { bytes.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(std::uint32_t{2});                  // version
  put(std::uint32_t{0});                  // flags
  put(std::int64_t{905969666});           // n
  put(std::int64_t{792633541402651904});  // nnz
  put(std::uint64_t{0});                  // mesh hash
  put(std::uint32_t{0});                  // settings length
  bytes.append(100, '\0');
  std::istringstream in(bytes);
  try {
    read_form_factors(in, "huge.bin", 0, -1);
    ADD_FAILURE() << "accepted";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("huge.bin: truncated"), std::string::npos) << e.what();
  }
}

}  // namespace lambert
