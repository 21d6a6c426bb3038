// The run's .glb and viewer page (issue 38, pipeline/viewer_stage.hpp), read back with an
// independent glTF reader (tinygltf): COLOR_0 is the vertex field of the vertex EXR, the
// per-light-source bases sum to it (linearity) and each is the solution of a run lit by that
// source alone; the page embeds the same bytes.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "common/glb_reader.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "io/exr.hpp"
#include "pipeline/relight.hpp"

namespace lambert {
namespace {

using testing::glb_attribute;
using testing::run_capturing;

// The bytes of a base64 text (the page's embedded glb).
std::string viewer_unbase64(const std::string& text) {
  std::string out;
  unsigned v = 0;
  int bits = 0;
  for (const char c : text) {
    int d = -1;
    if (c >= 'A' && c <= 'Z') d = c - 'A';
    if (c >= 'a' && c <= 'z') d = c - 'a' + 26;
    if (c >= '0' && c <= '9') d = c - '0' + 52;
    if (c == '+') d = 62;
    if (c == '/') d = 63;
    if (d < 0) break;  // '=' padding ends it
    v = (v << 6) | static_cast<unsigned>(d);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((v >> bits) & 0xFF));
    }
  }
  return out;
}

double max_abs(const std::vector<float>& v) {
  double m = 0.0;
  for (const float x : v) m = std::max(m, static_cast<double>(std::fabs(x)));
  return m;
}

// max_k |a_k - b_k| / max |b|.
double relative_difference(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  double d = 0.0;
  for (size_t k = 0; k < std::min(a.size(), b.size()); ++k)
    d = std::max(d, std::fabs(static_cast<double>(a[k]) - b[k]));
  return d / max_abs(b);
}

struct RunGlb {
  tinygltf::Model model;
  nlohmann::json report;
  std::vector<std::string> sources;  // the primitive's extras' emitter names, in order
};

RunGlb run_glb(const testing::TempDir& dir, const std::string& out, std::vector<std::string> args) {
  args.insert(args.begin(),
              {"run", "-o", dir.file(out), "--patches", "120", "--size", "128x128", "-q"});
  const auto [code, err] = run_capturing(args);
  EXPECT_EQ(code, 0) << err;
  RunGlb r;
  r.model = testing::parse_glb(testing::slurp(dir.file(out + "/cornell.glb")));
  r.report = testing::read_json(dir.file(out + "/report.json"));
  const auto& extras = r.model.meshes.at(0).primitives.at(0).extras.Get("emitters");
  for (size_t k = 0; k < extras.ArrayLen(); ++k)
    r.sources.push_back(extras.Get(static_cast<int>(k)).Get<std::string>());
  return r;
}

std::vector<float> basis(const RunGlb& r, const std::string& source) {
  const auto it = std::find(r.sources.begin(), r.sources.end(), source);
  EXPECT_NE(it, r.sources.end()) << source;
  return glb_attribute(r.model, "COLOR_" + std::to_string(it - r.sources.begin() + 1));
}

TEST(Viewer, TheBasesSumToTheSolutionWhichIsTheVertexExrsField) {
  testing::TempDir dir;
  const RunGlb r = run_glb(dir, "out", {"--sky", "30,30,40", "--emit", "tall_block=5,1,1"});
  // Three light sources: the light, the glowing block, the sky.
  EXPECT_EQ(std::set<std::string>(r.sources.begin(), r.sources.end()),
            (std::set<std::string>{"light", "tall_block", "sky"}));
  EXPECT_EQ(r.report["viewer"]["light_sources"].size(), 3u);
  // COLOR_0 is the vertex EXR's field (the same float values).
  const std::vector<float> solution = glb_attribute(r.model, "COLOR_0");
  const VertexExr exr = read_vertex_exr(dir.file("out/cornell_vertices.exr"));
  ASSERT_EQ(static_cast<std::int64_t>(solution.size()), 3 * exr.vertex_count);
  for (std::int64_t k = 0; k < exr.vertex_count; ++k)
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(solution[3 * k + c], static_cast<float>(exr.radiosity(k, c))) << k;
  // Linearity: the bases sum to the solution within kLinearityTolerance (its derivation:
  // pipeline/relight.hpp), as the report says.
  std::vector<float> sum(solution.size(), 0.0f);
  for (size_t k = 1; k <= r.sources.size(); ++k) {
    const std::vector<float> b = glb_attribute(r.model, "COLOR_" + std::to_string(k));
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += b[i];
  }
  const double error = relative_difference(sum, solution);
  EXPECT_LE(error, kLinearityTolerance);
  EXPECT_LE(r.report["viewer"]["linearity_error"].get<double>(), kLinearityTolerance);
  // The camera and the exposure of the run's image.
  EXPECT_DOUBLE_EQ(r.model.asset.extras.Get("lambert").Get("exposure_ev").GetNumberAsDouble(),
                   r.report["render"]["exposure_ev"].get<double>());
  ASSERT_EQ(r.model.cameras.size(), 1u);
  // The page embeds exactly these bytes.
  const std::string page = testing::slurp(dir.file("out/index.html"));
  const std::string key = "window.LAMBERT_GLB_BASE64 = \"";
  const size_t at = page.find(key);
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(viewer_unbase64(
                page.substr(at + key.size(), page.find('"', at + key.size()) - at - key.size())),
            testing::slurp(dir.file("out/cornell.glb")));
}

TEST(Viewer, EachBasisIsTheSolutionOfARunLitByThatSourceAlone) {
  // The same mesh and F (same seed; light does not change F) lit three ways: light and sky,
  // light alone, sky alone (the light's emission set to 0). The combined run's "light" basis
  // must be the light-alone run's solution and its "sky" basis the sky-alone run's: the runs
  // solve to tol 1e-8 and the bases to 1e-10, so each differs from the exact solution by
  // <= cond(I - rho F) * 1e-8 <= 1.9e-7 of its size (relight.hpp), plus float32 rounding
  // (6e-8): 1e-6 of the largest value bounds the difference. The vertex values are the
  // area-weighted means (--vertex-interp area): the conservative rescale is the combined
  // solution's in the bases and each run's own otherwise, which differ by up to the
  // area-weighted power error (2e-5), not a solver error.
  testing::TempDir dir;
  const RunGlb both = run_glb(dir, "both", {"--sky", "30,30,40", "--vertex-interp", "area"});
  const RunGlb light = run_glb(dir, "light", {"--vertex-interp", "area"});
  const RunGlb sky = run_glb(
      dir, "sky", {"--sky", "30,30,40", "--emit", "light=0,0,0", "--vertex-interp", "area"});
  ASSERT_EQ(both.sources.size(), 2u);
  EXPECT_EQ(light.sources, std::vector<std::string>{"light"});
  EXPECT_EQ(sky.sources, std::vector<std::string>{"sky"});
  EXPECT_LE(relative_difference(basis(both, "light"), glb_attribute(light.model, "COLOR_0")), 1e-6);
  EXPECT_LE(relative_difference(basis(both, "sky"), glb_attribute(sky.model, "COLOR_0")), 1e-6);
  // One source: its basis is the solution itself (no extra solve).
  EXPECT_EQ(glb_attribute(light.model, "COLOR_1"), glb_attribute(light.model, "COLOR_0"));
}

TEST(Viewer, ManyEmittersShareTheLastBasisAndHierarchicalSaysWhyItCannotRelight) {
  testing::TempDir dir;
  // 13 emitting quads side by side with powers 1..13 (emission k): the 11 brightest get a
  // basis each, the two dimmest share "other emitters" (kMaxEmitterBases = 12).
  std::string obj;
  for (int k = 1; k <= 13; ++k) {
    const double x = 2.0 * k;
    obj += "v " + std::to_string(x) + " 0 0\nv " + std::to_string(x + 1) + " 0 0\nv " +
           std::to_string(x + 1) + " 1 0\nv " + std::to_string(x) + " 1 0\n";
  }
  obj += "v 0 -1 -1\nv 30 -1 -1\nv 30 2 -1\nv 0 2 -1\ng wall\nf 53 54 55 56\n";
  for (int k = 1; k <= 13; ++k) {
    const int v = 4 * (k - 1);
    obj += "g q" + std::to_string(k) + "\nf " + std::to_string(v + 1) + ' ' +
           std::to_string(v + 2) + ' ' + std::to_string(v + 3) + ' ' + std::to_string(v + 4) + "\n";
  }
  const std::string scene = dir.write("strip.obj", obj);
  std::vector<std::string> args = {"run", scene, "-o", dir.file("out"), "-q", "--patches", "100"};
  for (int k = 1; k <= 13; ++k) {
    const std::string e = std::to_string(k);
    args.insert(args.end(), {"--emit", "q" + e + "=" + e + "," + e + "," + e});
  }
  const auto [code, err] = run_capturing(args);
  ASSERT_EQ(code, 0) << err;
  const tinygltf::Model m = testing::parse_glb(testing::slurp(dir.file("out/strip.glb")));
  const auto& extras = m.meshes.at(0).primitives.at(0).extras.Get("emitters");
  ASSERT_EQ(extras.ArrayLen(), static_cast<size_t>(kMaxEmitterBases));
  EXPECT_EQ(extras.Get(0).Get<std::string>(), "q13");
  EXPECT_EQ(extras.Get(kMaxEmitterBases - 1).Get<std::string>(), "other emitters");
  const auto& last = m.asset.extras.Get("lambert").Get("emitters").Get(kMaxEmitterBases - 1);
  EXPECT_EQ(last.Get("surfaces").ArrayLen(), 2u);
  EXPECT_EQ(last.Get("kind").Get<std::string>(), "surfaces");
  EXPECT_FALSE(glb_attribute(m, "COLOR_" + std::to_string(kMaxEmitterBases)).empty());
  EXPECT_TRUE(glb_attribute(m, "COLOR_" + std::to_string(kMaxEmitterBases + 1)).empty());

  // The hierarchical method: the solution only, and why.
  const auto [hcode, herr] = run_capturing(
      {"run", "--method", "hierarchical", "-o", dir.file("h"), "-q", "--epsilon", "1e-2"});
  ASSERT_EQ(hcode, 0) << herr;
  const tinygltf::Model h = testing::parse_glb(testing::slurp(dir.file("h/cornell.glb")));
  EXPECT_FALSE(glb_attribute(h, "COLOR_0").empty());
  EXPECT_TRUE(glb_attribute(h, "COLOR_1").empty());
  const nlohmann::json report = testing::read_json(dir.file("h/report.json"));
  EXPECT_FALSE(report["viewer"]["relighting"].get<bool>());
  EXPECT_NE(report["viewer"]["no_relighting"].get<std::string>().find("hierarchical"),
            std::string::npos);
}

TEST(Viewer, RenderGlbWritesTheBasesAndThePageAndSaysWhyARadiosityFileHasNone) {
  // `render --glb FILE` writes the same glb as `run` (here two sources: the light and a glowing
  // block) and the page FILE with .html beside it; the bases sum to the solution within
  // kLinearityTolerance (pipeline/relight.hpp). With --radiosity B.csv there is no F to split
  // B by source: the glb holds the solution only and its extras say why.
  testing::TempDir dir;
  const std::string glb = dir.file("cb.glb");
  const auto [code, err] =
      run_capturing({"render", "-q", "--patches", "120", "--emit", "tall_block=5,1,1", "--glb", glb,
                     "--size", "128x128", "-o", dir.file("cb.exr")});
  ASSERT_EQ(code, 0) << err;
  const tinygltf::Model m = testing::parse_glb(testing::slurp(glb));
  const auto& lambert = m.asset.extras.Get("lambert");
  ASSERT_EQ(lambert.Get("emitters").ArrayLen(), 2u);
  const std::vector<float> solution = glb_attribute(m, "COLOR_0");
  std::vector<float> sum(solution.size(), 0.0f);
  for (int k = 1; k <= 2; ++k) {
    const std::vector<float> b = glb_attribute(m, "COLOR_" + std::to_string(k));
    ASSERT_EQ(b.size(), sum.size());
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += b[i];
  }
  EXPECT_LE(relative_difference(sum, solution), kLinearityTolerance);
  const std::string page = testing::slurp(dir.file("cb.html"));
  EXPECT_NE(page.find("window.LAMBERT_GLB_BASE64"), std::string::npos);

  // B from a file: the solution only, with the reason.
  const std::string csv = dir.file("B.csv");
  ASSERT_EQ(run_capturing({"solve", "-q", "--patches", "120", "-o", csv}).first, 0);
  const std::string glb2 = dir.file("from_csv.glb");
  const auto [code2, err2] =
      run_capturing({"render", "-q", "--patches", "120", "--radiosity", csv, "--glb", glb2,
                     "--size", "128x128", "-o", dir.file("from_csv.exr")});
  ASSERT_EQ(code2, 0) << err2;
  const tinygltf::Model m2 = testing::parse_glb(testing::slurp(glb2));
  EXPECT_FALSE(glb_attribute(m2, "COLOR_0").empty());
  EXPECT_TRUE(glb_attribute(m2, "COLOR_1").empty());
  EXPECT_NE(
      m2.asset.extras.Get("lambert").Get("no_relighting").Get<std::string>().find("--radiosity"),
      std::string::npos);
}

TEST(Viewer, HeatGlbCarriesTheVertexExrsTemperatureAndFluxAndOpensOnTheTemperature) {
  // `heat --glb FILE` (issue 38: false colour of temperature and flux for heat outputs): the
  // thermal box, 200 patches. _TEMPERATURE and _HEAT_FLUX are the vertex EXR's temperature
  // and heat_flux channels (the same area-weighted field, stored as float: equal exactly);
  // the page beside the glb embeds it and opens on the temperature (default_mode).
  testing::TempDir dir;
  const std::string root = std::string(LAMBERT_TEST_DATA_DIR) + "/thermal_box/";
  const auto [code, err] =
      run_capturing({"heat", root + "thermal_box.stl", "--surfaces", root + "surfaces.json",
                     "--length-unit", "mm", "--patches", "200", "-q", "-o", dir.file("out/"),
                     "--glb", dir.file("out/h.glb"), "--vertex-exr", dir.file("out/h.exr")});
  ASSERT_EQ(code, 0) << err;
  const tinygltf::Model m = testing::parse_glb(testing::slurp(dir.file("out/h.glb")));
  const std::vector<float> T = glb_attribute(m, "_TEMPERATURE");
  const std::vector<float> q = glb_attribute(m, "_HEAT_FLUX");
  const VertexExr exr =
      read_vertex_exr(dir.file("out/h.exr"), {"temperature", "heat_flux", "radiosity"});
  ASSERT_EQ(static_cast<std::int64_t>(T.size()), exr.vertex_count);
  ASSERT_EQ(q.size(), T.size());
  for (std::int64_t k = 0; k < exr.vertex_count; ++k) {
    ASSERT_EQ(T[k], static_cast<float>(exr.radiosity(k, 0))) << k;
    ASSERT_EQ(q[k], static_cast<float>(exr.radiosity(k, 1))) << k;
  }
  // The heater (800 K) and the cold plate (300 K) bound the walls' temperatures.
  EXPECT_EQ(*std::max_element(T.begin(), T.end()), 800.0f);
  EXPECT_EQ(*std::min_element(T.begin(), T.end()), 300.0f);
  const auto& lambert = m.asset.extras.Get("lambert");
  EXPECT_EQ(lambert.Get("default_mode").Get<std::string>(), "temperature");
  EXPECT_EQ(lambert.Get("quantity").Get<std::string>(), "heat");
  EXPECT_NE(testing::slurp(dir.file("out/h.html")).find("window.LAMBERT_GLB_BASE64"),
            std::string::npos);
}

}  // namespace
}  // namespace lambert
