#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/exr.hpp"
#include "pipeline/ff_stage.hpp"

namespace lambert {

using testing::run;
using testing::slurp;
namespace {

// A tiny open box (unit cube without its z = 0 face, faces pointing inward) lit by an
// emissive patch on the ceiling; without a .camera sidecar the default camera looks in
// through the opening from -z.
void write_tiny_scene(const lambert::testing::TempDir& dir) {
  dir.write("tiny.mtl",
            "newmtl white\nKd 0.6 0.6 0.6\n"
            "newmtl red\nKd 0.7 0.1 0.1\n"
            "newmtl light\nKd 0.2 0.2 0.2\nKe 10 9 8\n");
  dir.write("tiny.obj",
            "mtllib tiny.mtl\n"
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
            "v 0.4 0.999 0.4\nv 0.6 0.999 0.4\nv 0.6 0.999 0.6\nv 0.4 0.999 0.6\n"
            "g back\nusemtl white\nf 5 8 7 6\n"
            "g floor\nusemtl white\nf 1 5 6 2\n"
            "g ceiling\nusemtl white\nf 4 3 7 8\n"
            "g left\nusemtl red\nf 1 4 8 5\n"
            "g right\nusemtl white\nf 2 6 7 3\n"
            "g light\nusemtl light\nf 9 10 11 12\n");
}

// The tiny scene solved on 60 patches into dir/B.csv; returns the scene's path.
std::string solve_tiny_scene(const lambert::testing::TempDir& dir) {
  write_tiny_scene(dir);
  const std::string scene = dir.file("tiny.obj");
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(
      run({"solve", scene, "--patches", "60", "--samples", "4", "-o", dir.file("B.csv"), "-q"}),
      kExitOk);
  ::testing::internal::GetCapturedStdout();
  return scene;
}

}  // namespace

TEST(RunCommand, TinySceneProducesEveryFile) {
  lambert::testing::TempDir dir;
  write_tiny_scene(dir);
  const std::string out = dir.file("results");  // does not exist yet: created by run
  ::testing::internal::CaptureStdout();
  const int code = run({"run", dir.file("tiny.obj"), "-o", out, "--patches", "80", "--samples", "4",
                        "--size", "40x30", "-q", "-j", "2"});
  const std::string stdout_text = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk) << stdout_text;
  for (const char* f : {"tiny.exr", "tiny.png", "tiny_vertices.exr", "tiny.ply", "tiny.glb",
                        "index.html", "report.json"}) {
    const std::string path = out + "/" + f;
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    EXPECT_GT(std::filesystem::file_size(path), 0u) << path;
    EXPECT_NE(stdout_text.find(path), std::string::npos) << "summary does not list " << path;
  }
  // Nothing else (no temporaries) is left in the output directory.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(out),
                          std::filesystem::directory_iterator()),
            7);
  EXPECT_EQ(slurp(out + "/tiny.png").substr(1, 3), "PNG");
  EXPECT_EQ(slurp(out + "/tiny.ply").substr(0, 4), "ply\n");
  const nlohmann::json report = nlohmann::json::parse(slurp(out + "/report.json"));
  EXPECT_EQ(report.at("surfaces").get<int>(), 6);
  const auto& ff = report.at("form_factors");
  EXPECT_EQ(ff.at("estimator"), "hybrid");
  EXPECT_EQ(ff.at("samples").get<int>(), 4);
  EXPECT_EQ(ff.at("seed").get<int>(), 1);
  EXPECT_EQ(ff.at("loaded_from"), "");
  EXPECT_GT(ff.at("rays").get<std::int64_t>(), 0);
  EXPECT_EQ(report.at("solver").at("status"), "converged");
  ASSERT_EQ(report.at("energy_balance").size(), 3u);
  for (const auto& e : report.at("energy_balance")) {
    // Light Ke 10 9 8 on a 0.2 x 0.2 patch: emitted = 0.04 Ke per channel.
    EXPECT_GT(e.at("emitted").get<double>(), 0.0);
    // Converged to tol 1e-8 on hybrid's reciprocal F: the imbalance is the residual part,
    // |sum A r| / emitted <= ||A||_2 ||r||_2 / emitted ~ 1e-8; 1e-6 leaves a margin.
    EXPECT_LE(e.at("relative_imbalance").get<double>(), 1e-6);
  }
  const auto& emitted = report.at("energy_balance");
  // The light is 0.2 x 0.2 (area exact to rounding of its corners, ~1e-16): emitted = 0.04 Ke,
  // a sum of a few patch terms, so 1e-12 is rounding with a wide margin.
  EXPECT_NEAR(emitted[0].at("emitted").get<double>(), 0.4, 1e-12);
  EXPECT_NEAR(emitted[2].at("emitted").get<double>(), 0.32, 1e-12);
  const auto& power = report.at("vertex_power");
  EXPECT_EQ(power.at("interpolation"), "conservative");
  EXPECT_LE(power.at("max_relative_error").get<double>(), power.at("tolerance").get<double>());
  EXPECT_EQ(power.at("surfaces").size(), 6u);
  EXPECT_EQ(report.at("render").at("width").get<int>(), 40);
  EXPECT_EQ(report.at("render").at("height").get<int>(), 30);
  EXPECT_GE(report.at("seconds").at("total").get<double>(), 0.0);
  EXPECT_EQ(report.at("rays_total").get<std::int64_t>(),
            ff.at("rays").get<std::int64_t>() + report.at("render").at("rays").get<std::int64_t>());
  EXPECT_EQ(report.at("files").size(), 7u);
  const Image img = read_image_exr(out + "/tiny.exr");
  EXPECT_EQ(img.width, 40);
  EXPECT_EQ(img.height, 30);
  const VertexExr v = read_vertex_exr(out + "/tiny_vertices.exr");
  EXPECT_GT(v.vertex_count, 80);
  EXPECT_EQ(v.info.surface_names.size(), 6u);
  // The summary reports the stages.
  for (const char* word : {"patches", "rays", "solver", "energy", "time", "files"})
    EXPECT_NE(stdout_text.find(word), std::string::npos) << word;
}

// report.json "timings" (issue 37): every stage of the matrix run under its key with wall
// and CPU seconds, and their total. A run on one thread (-j 1) cannot use more CPU time than
// wall time in any stage; 10 ms absorbs the two clocks' granularity (both are read at each
// stage boundary, microseconds apart).
TEST(RunCommand, TheReportTimesEveryStageInWallAndCpuSeconds) {
  lambert::testing::TempDir dir;
  write_tiny_scene(dir);
  const std::string out = dir.file("results");
  const auto [code, printed] =
      lambert::testing::run_stdout({"run", dir.file("tiny.obj"), "-o", out, "--patches", "80",
                                    "--samples", "4", "--size", "40x30", "-q", "-j", "1"});
  ASSERT_EQ(code, kExitOk) << printed;
  const nlohmann::json t = nlohmann::json::parse(slurp(out + "/report.json")).at("timings");
  std::vector<std::string> keys;
  for (const auto& [key, value] : t.items()) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(keys, (std::vector<std::string>{"form_factors", "load_and_mesh", "render", "solve",
                                            "total", "vertices", "write"}));
  double wall = 0.0, cpu = 0.0;
  for (const auto& [key, value] : t.items()) {
    if (key == "total") continue;
    const double w = value.at("wall").get<double>(), c = value.at("cpu").get<double>();
    EXPECT_GE(w, 0.0) << key;
    EXPECT_GE(c, 0.0) << key;
    EXPECT_LE(c, w + 0.01) << key;
    wall += w, cpu += c;
  }
  EXPECT_NEAR(t.at("total").at("wall").get<double>(), wall, 1e-12);
  EXPECT_NEAR(t.at("total").at("cpu").get<double>(), cpu, 1e-12);
}

// One Embree device per process, one BVH per run, shared by form factors and rendering.
// The counters are process-wide and other tests may have run in this process before (ctest
// runs one test per process, a plain run of the executable does not), so the test reads
// them before and after: one build more, and at most one device for this thread count.
TEST(RunCommand, BuildsOneBvhOnOneDeviceForFormFactorsAndRendering) {
  lambert::testing::TempDir dir;
  write_tiny_scene(dir);
  const std::int64_t builds_before = Bvh::builds(), devices_before = Bvh::devices();
  const int code = run({"run", dir.file("tiny.obj"), "-o", dir.file("out/"), "--patches", "80",
                        "--samples", "4", "--size", "40x30", "-q", "-j", "2"});
  ASSERT_EQ(code, kExitOk);
  EXPECT_EQ(Bvh::builds() - builds_before, 1);
  EXPECT_LE(Bvh::devices() - devices_before, 1);
  const std::int64_t devices_after_first = Bvh::devices();
  ASSERT_EQ(run({"run", dir.file("tiny.obj"), "-o", dir.file("out2/"), "--patches", "80",
                 "--samples", "4", "--size", "40x30", "-q", "-j", "2"}),
            kExitOk);
  EXPECT_EQ(Bvh::builds() - builds_before, 2);
  EXPECT_EQ(Bvh::devices(), devices_after_first) << "a second run made a second device";
}

TEST(RunCommand, NamePrefixAndBuiltInCornellBox) {
  lambert::testing::TempDir dir;
  ::testing::internal::CaptureStdout();
  const int code = run({"run", "-o", dir.file("o"), "--patches", "150", "--samples", "2", "--size",
                        "32x32", "--antialias", "1", "-q"});
  ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk);
  for (const char* f : {"cornell.exr", "cornell.png", "cornell_vertices.exr", "cornell.ply"})
    EXPECT_TRUE(std::filesystem::exists(dir.file("o/") + f)) << f;
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run({"run", "-o", dir.file("o"), "--name", "x", "--patches", "60", "--samples", "2",
                 "--size", "16x16", "--flat", "-q"}),
            kExitOk);
  ::testing::internal::GetCapturedStdout();
  EXPECT_TRUE(std::filesystem::exists(dir.file("o/x.png")));
}

TEST(RenderCommand, RendersASolvedCsvAndRefusesOneForAnotherMesh) {
  lambert::testing::TempDir dir;
  const std::string scene = solve_tiny_scene(dir);
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run({"render", scene, "--patches", "60", "--radiosity", dir.file("B.csv"), "-o",
                 dir.file("img.exr"), "--size", "24x24", "--vertex-exr", dir.file("v.exr"), "--ply",
                 dir.file("m.ply"), "-q"}),
            kExitOk);
  ::testing::internal::GetCapturedStdout();
  for (const char* f : {"img.exr", "img.png", "v.exr", "m.ply"})
    EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
  // The same CSV on a different meshing: a one-line error (exit 1), nothing written.
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(run({"render", scene, "--patches", "200", "--radiosity", dir.file("B.csv"), "-o",
                 dir.file("bad.exr"), "-q"}),
            kExitFailure);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("B.csv"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.exr")));
}

TEST(RenderCommand, RaytraceAndFinalGatherWriteOutputsAndRecordTheirSettings) {
  lambert::testing::TempDir dir;
  const std::string scene = solve_tiny_scene(dir);
  ::testing::internal::CaptureStdout();
  const std::vector<std::string> common = {"render", scene,         "--patches",
                                           "60",     "--radiosity", dir.file("B.csv"),
                                           "--size", "24x18",       "-q"};
  const auto render_with = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = common;
    args.insert(args.end(), {"-o", dir.file(name + ".exr")});
    args.insert(args.end(), extra.begin(), extra.end());
    return run(args);
  };
  EXPECT_EQ(render_with("gouraud", {}), kExitOk);
  EXPECT_EQ(render_with("traced", {"--shading", "raytrace", "--specular-depth", "3"}), kExitOk);
  EXPECT_EQ(render_with("gathered", {"--final-gather", "4"}), kExitOk);
  EXPECT_EQ(render_with("flat", {"--flat"}), kExitOk);
  ::testing::internal::GetCapturedStdout();
  ExrInfo info;
  const Image gouraud = read_image_exr(dir.file("gouraud.exr"), &info);
  EXPECT_NE(info.settings.find("shading=gouraud"), std::string::npos) << info.settings;
  const Image traced = read_image_exr(dir.file("traced.exr"), &info);
  EXPECT_NE(info.settings.find("shading=raytrace specular_depth=3 final_gather=0"),
            std::string::npos)
      << info.settings;
  // A diffuse scene: the view pass reads the same field (float rounding, 2^-23 relative).
  ASSERT_EQ(traced.rgb.size(), gouraud.rgb.size());
  for (size_t k = 0; k < traced.rgb.size(); ++k)
    EXPECT_NEAR(traced.rgb[k], gouraud.rgb[k], 1.2e-7 * std::abs(gouraud.rgb[k]));
  const Image gathered = read_image_exr(dir.file("gathered.exr"), &info);
  EXPECT_NE(info.settings.find("shading=raytrace specular_depth=8 final_gather=4"),
            std::string::npos)
      << info.settings;
  EXPECT_EQ(gathered.alpha, gouraud.alpha);
  read_image_exr(dir.file("flat.exr"), &info);
  EXPECT_NE(info.settings.find("shading=flat"), std::string::npos) << info.settings;
  for (const char* f : {"traced.png", "gathered.png"})
    EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
}

TEST(RunCommand, ReportRecordsTheViewPass) {
  lambert::testing::TempDir dir;
  write_tiny_scene(dir);
  const std::string out = dir.file("results");
  ::testing::internal::CaptureStdout();
  const int code = run({"run", dir.file("tiny.obj"), "-o", out, "--patches", "60", "--samples", "4",
                        "--size", "16x12", "--final-gather", "2", "-q"});
  ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk);
  const nlohmann::json report = nlohmann::json::parse(slurp(out + "/report.json"));
  const auto& r = report.at("render");
  EXPECT_EQ(r.at("shading"), "raytrace");
  EXPECT_EQ(r.at("final_gather").get<int>(), 2);
  EXPECT_EQ(r.at("specular_depth").get<int>(), FormFactorArgs().specular_depth);
  // At least the camera rays and two gather rays per diffuse camera hit.
  EXPECT_GT(r.at("rays").get<std::int64_t>(), 16 * 12 * 4);
  EXPECT_NE(report.at("settings").get<std::string>().find("final_gather=2"), std::string::npos);
}

TEST(RenderCommand, BadShadingOptionsAreUsageErrors) {
  for (const char* cmd : {"render", "run"}) {
    EXPECT_EQ(run({cmd, "--shading", "phong", "-q"}), kExitUsage);
    EXPECT_EQ(run({cmd, "--final-gather", "0", "-q"}), kExitUsage);
    EXPECT_EQ(run({cmd, "--final-gather", "-3", "-q"}), kExitUsage);
    EXPECT_EQ(run({cmd, "--final-gather", "many", "-q"}), kExitUsage);
    EXPECT_EQ(run({cmd, "--final-gather", "4", "--shading", "gouraud", "-q"}), kExitUsage);
    EXPECT_EQ(run({cmd, "--final-gather", "4", "--flat", "-q"}), kExitUsage);
    EXPECT_EQ(run({cmd, "--flat", "--shading", "raytrace", "-q"}), kExitUsage);
    EXPECT_EQ(run({cmd, "--shading", "raytrace", "--specular-depth", "65", "-q"}), kExitUsage);
  }
}

TEST(RenderCommand, BadOptionsAreUsageErrors) {
  EXPECT_EQ(run({"render", "--size", "12", "-q"}), kExitUsage);
  EXPECT_EQ(run({"render", "--antialias", "0", "-q"}), kExitUsage);
  EXPECT_EQ(run({"render", "--exposure", "bright", "-q"}), kExitUsage);
  EXPECT_EQ(run({"run", "--vertex-interp", "cubic", "-q"}), kExitUsage);
  EXPECT_EQ(run({"run", "--eye", "1", "2", "-q"}), kExitUsage);
}

}  // namespace lambert

namespace lambert {

// --vertex-interp auto is exact-direct on a --discontinuity mesh solved here (report and
// settings say so), linear on an --adapt mesh and conservative otherwise; exact-direct is
// refused, before any work, where B comes without its F (--radiosity, --method
// hierarchical).
TEST(RunCommand, VertexInterpAutoIsExactDirectOnDiscontinuityMeshes) {
  lambert::testing::TempDir dir;
  write_tiny_scene(dir);
  const std::string scene = dir.file("tiny.obj");
  auto interpolation = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"run",         scene,       "-o", dir.file("o/"), "--max-edge",
                                     "0.3",         "--samples", "2",  "--size",       "16x16",
                                     "--antialias", "1",         "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    ::testing::internal::CaptureStdout();
    const int code = run(args);
    ::testing::internal::GetCapturedStdout();
    EXPECT_EQ(code, kExitOk);
    std::ifstream in(dir.file("o/report.json"));
    return nlohmann::json::parse(in)["vertex_power"]["interpolation"].get<std::string>();
  };
  EXPECT_EQ(interpolation({"--discontinuity"}), "exact-direct");
  EXPECT_EQ(interpolation({}), "conservative");
  EXPECT_EQ(interpolation({"--vertex-interp", "exact-direct"}), "exact-direct");
  EXPECT_EQ(interpolation({"--discontinuity", "--vertex-interp", "area"}), "area");
  // An --adapt mesh is graded: auto shades it with the local linear fit (issue 35 item 7).
  EXPECT_EQ(interpolation({"--adapt", "1"}), "linear");
  EXPECT_EQ(interpolation({"--adapt", "1", "--vertex-interp", "conservative"}), "conservative");

  ::testing::internal::CaptureStdout();
  ASSERT_EQ(
      run({"solve", scene, "--max-edge", "0.3", "--samples", "2", "-o", dir.file("B.csv"), "-q"}),
      kExitOk);
  ::testing::internal::GetCapturedStdout();
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(run({"render", scene, "--max-edge", "0.3", "--radiosity", dir.file("B.csv"),
                 "--vertex-interp", "exact-direct", "-o", dir.file("r.exr"), "-q"}),
            kExitUsage);
  EXPECT_EQ(run({"run", scene, "--method", "hierarchical", "--vertex-interp", "exact-direct", "-o",
                 dir.file("h/"), "-q"}),
            kExitUsage);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("exact-direct"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("r.exr")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("h/report.json")));
}

}  // namespace lambert
