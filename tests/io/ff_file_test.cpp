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
