#include "io/ff_file.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "geometry/analytic.hpp"

namespace lambert {
namespace {

struct Fixture {
  PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  FormFactors ff = [this] {
    FormFactorOptions o;
    o.samples = 4;
    o.with_stderr = true;
    o.progress = false;
    return compute_form_factors(mesh, o);
  }();
  FormFactorFileInfo info{mesh_hash(mesh), "estimator=hybrid samples=4"};
};

void expect_same(const SparseF& a, const SparseF& b) {
  ASSERT_EQ(a.rows(), b.rows());
  ASSERT_EQ(a.nonZeros(), b.nonZeros());
  for (std::int32_t k = 0; k < a.nonZeros(); ++k) {
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
  o.samples = 77;
  o.seed = 18446744073709551615ull;  // the largest seed: all 64 bits survive
  o.threshold = 1.0 / 3.0;           // %.17g reads back to the same double
  o.hemicube_resolution = 96;
  o.symmetrize = true;
  FormFactorOptions back;
  ASSERT_TRUE(parse_ff_settings(format_ff_settings(o) + " patches=24 max_edge=0.5", back));
  EXPECT_EQ(back.estimator, "hemicube");
  EXPECT_EQ(back.samples, 77);
  EXPECT_EQ(back.seed, o.seed);
  EXPECT_EQ(back.threshold, o.threshold);
  EXPECT_EQ(back.hemicube_resolution, 96);
  EXPECT_TRUE(back.symmetrize);
}

TEST(FormFactorFile, SettingsOfOlderFilesAreRecoveredAndForeignTextIsRefused) {
  // What `formfactors` wrote before every key was stored: no hemicube_res/symmetrize.
  FormFactorOptions o;
  ASSERT_TRUE(
      parse_ff_settings("estimator=mc samples=64 seed=5 threshold=0 patches=9 max_edge=1", o));
  EXPECT_EQ(o.estimator, "mc");
  EXPECT_EQ(o.samples, 64);
  EXPECT_EQ(o.seed, 5u);
  EXPECT_FALSE(o.symmetrize);
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
  o.samples = 64;
  o.seed = 5;
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
  EXPECT_EQ(back.samples, 64);
  EXPECT_EQ(back.seed, 5u);
}

}  // namespace lambert
