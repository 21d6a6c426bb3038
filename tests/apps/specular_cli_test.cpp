// Specular scenes through the CLI: extended form factors saved and reloaded (binary keeps
// the specular bookkeeping, so the energy balance is the same), the settings in reports,
// and the refusals (hierarchical, hemicube, coloured mirrors).

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"

namespace lambert {
namespace {

using testing::read_json;
using testing::run;

// A unit cube open at z = 0 (faces inward), a light on the ceiling, the +x wall a mirror
// (`mirror_ks`, grey or not).
std::string write_mirror_box(const testing::TempDir& dir, const std::string& mirror_ks) {
  dir.write("box.mtl",
            "newmtl white\nKd 0.6 0.6 0.6\n"
            "newmtl light\nKd 0.2 0.2 0.2\nKe 10 9 8\n"
            "newmtl mirror\nKd 0 0 0\nKs " + mirror_ks + "\nillum 3\n");
  dir.write("box.obj",
            "mtllib box.mtl\n"
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
            "v 0.4 0.999 0.4\nv 0.6 0.999 0.4\nv 0.6 0.999 0.6\nv 0.4 0.999 0.6\n"
            "g back\nusemtl white\nf 5 8 7 6\n"
            "g floor\nusemtl white\nf 1 5 6 2\n"
            "g ceiling\nusemtl white\nf 4 3 7 8\n"
            "g left\nusemtl white\nf 1 4 8 5\n"
            "g right\nusemtl mirror\nf 2 6 7 3\n"
            "g light\nusemtl light\nf 9 10 11 12\n");
  return dir.file("box.obj");
}

}  // namespace

// F saved as .bin and loaded again gives the same solve and the same energy balance (the
// specular bookkeeping travels with it); the report says the factors are extended.
TEST(SpecularCli, ExtendedFormFactorsRoundTripThroughABinaryFile) {
  testing::TempDir dir;
  const std::string obj = write_mirror_box(dir, "0.9 0.9 0.9");
  const std::vector<std::string> mesh = {"--max-edge", "0.25", "-q"};
  auto with = [&](std::vector<std::string> a) {
    a.insert(a.end(), mesh.begin(), mesh.end());
    return a;
  };
  // --specular-rays steers a computation: refused with --ff, like --samples.
  ASSERT_EQ(run(with({"formfactors", obj, "--specular-rays", "256", "-o", dir.file("F.bin")})),
            kExitOk);
  ASSERT_EQ(run(with({"solve", obj, "--specular-rays", "256", "-o", dir.file("a.csv")})),
            kExitOk);
  EXPECT_EQ(run(with({"solve", obj, "--specular-rays", "256", "--ff", dir.file("F.bin"), "-o",
                      dir.file("x.csv")})),
            kExitUsage);
  ASSERT_EQ(run(with({"solve", obj, "--ff", dir.file("F.bin"), "-o", dir.file("b.csv")})),
            kExitOk);
  const nlohmann::json a = read_json(dir.file("a.json")), b = read_json(dir.file("b.json"));
  EXPECT_TRUE(a.at("form_factors").at("extended").get<bool>());
  EXPECT_EQ(a.at("form_factors").at("specular_depth").get<int>(), 8);
  EXPECT_TRUE(b.at("form_factors").at("extended").get<bool>());
  EXPECT_EQ(b.at("form_factors").at("specular_rays").get<int>(), 256);
  // Same seed, same F: the energy balances agree to the last bit of their sums, and
  // light does not escape more than through the open side (escaped > 0).
  for (int c = 0; c < 3; ++c) {
    const nlohmann::json& ea = a.at("channels")[c].at("energy");
    const nlohmann::json& eb = b.at("channels")[c].at("energy");
    EXPECT_EQ(ea.at("escaped").get<double>(), eb.at("escaped").get<double>());
    EXPECT_EQ(ea.at("absorbed").get<double>(), eb.at("absorbed").get<double>());
    EXPECT_GT(ea.at("escaped").get<double>(), 0.0);
  }
  EXPECT_EQ(testing::slurp(dir.file("a.csv")), testing::slurp(dir.file("b.csv")));
  // Matrix Market keeps F (a patch may see itself through the mirror: diagonal entries are
  // accepted for extended factors) but not the bookkeeping: loaded with a warning.
  ASSERT_EQ(run(with({"formfactors", obj, "--specular-rays", "256", "-o", dir.file("F.mtx")})),
            kExitOk);
  ASSERT_EQ(run(with({"solve", obj, "--ff", dir.file("F.mtx"), "-o", dir.file("c.csv")})),
            kExitOk);
  EXPECT_EQ(testing::slurp(dir.file("a.csv")), testing::slurp(dir.file("c.csv")));
}

// The refusals: hierarchical radiosity and the hemicube cannot follow specular paths (usage
// errors, exit 2); a coloured mirror cannot be carried by one weight (exit 1) unless
// --specular-depth 0.
TEST(SpecularCli, RefusesWhatCannotFollowSpecularPaths) {
  testing::TempDir dir;
  const std::string grey = write_mirror_box(dir, "0.9");
  EXPECT_EQ(run({"solve", grey, "-q", "--method", "hierarchical", "-o", dir.file("h.csv")}),
            kExitUsage);
  EXPECT_EQ(run({"solve", grey, "-q", "--max-edge", "0.5", "--estimator", "hemicube", "-o",
                 dir.file("c.csv")}),
            kExitUsage);
  EXPECT_EQ(run({"solve", grey, "-q", "--max-edge", "0.5", "--estimator", "hemicube",
                 "--specular-depth", "0", "-o", dir.file("c.csv")}),
            kExitOk);
  testing::TempDir other;
  const std::string coloured = write_mirror_box(other, "0.9 0.5 0.5");
  EXPECT_EQ(run({"solve", coloured, "-q", "--max-edge", "0.5", "-o", other.file("d.csv")}),
            kExitFailure);
  EXPECT_EQ(run({"solve", coloured, "-q", "--max-edge", "0.5", "--specular-depth", "0", "-o",
                 other.file("d.csv")}),
            kExitOk);
  EXPECT_EQ(run({"solve", grey, "-q", "--specular-depth", "-1", "-o", dir.file("e.csv")}),
            kExitUsage);
}

}  // namespace lambert
