// Participating media (geometry/formfactors/media.hpp) on the Cornell box filled with fog
// (sigma_s 0.0005, sigma_a 0.0002 per mm: the "done when" command), measured in one
// run: `lambert run` without a medium and with 8³, 16³ and 32³ zones, each in a forked child
// (its own peak RSS): the zones, F's entries, the medium's exchange factors' time, the
// solve's, the total, and the peak RSS. The images are kept in --out (fog_<N>.png).
// Usage: medium_bench [--voxels 8,16,32] [--patches N] [--medium-rays K] [--out DIR] [-j N]

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "bench/child.hpp"

namespace {

struct Figures {
  int zones = 0;
  long long entries = 0;
  double medium_seconds = 0, ff_seconds = 0, solve_seconds = 0, render_seconds = 0, total = 0;
  int ok = 0;
};

int run_cli_args(std::vector<std::string> args) {
  args.insert(args.begin(), "lambert");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return lambert::run_cli(static_cast<int>(argv.size()), argv.data());
}

Figures run_case(int voxels, const std::string& patches, const std::string& rays,
                 const std::string& out, const std::string& threads) {
  const std::string name = voxels > 0 ? "fog_" + std::to_string(voxels) : "clear";
  std::vector<std::string> args = {"run", "-o", out, "--name", name, "--patches", patches, "-q"};
  if (threads != "0") args.insert(args.end(), {"-j", threads});
  if (voxels > 0) {
    const std::vector<std::string> fog = {"--medium-box",  "0,0,0,556,548.8,559.2",
                                          "--sigma-s",     "0.0005,0.0005,0.0005",
                                          "--sigma-a",     "0.0002,0.0002,0.0002",
                                          "--voxels",      std::to_string(voxels),
                                          "--medium-rays", rays};
    args.insert(args.end(), fog.begin(), fog.end());
  }
  Figures f;
  const int saved = dup(1);  // the run's summary is not the bench's output
  std::freopen("/dev/null", "w", stdout);
  const int code = run_cli_args(args);
  std::fflush(stdout);
  dup2(saved, 1);
  if (code != 0) return f;
  std::ifstream in(out + "/report.json");
  const nlohmann::json r = nlohmann::json::parse(in);
  const auto& s = r.at("seconds");
  f.ff_seconds = s.at("form_factors").get<double>();
  f.solve_seconds = s.at("solve").get<double>();
  f.render_seconds = s.at("render").get<double>();
  f.total = s.at("total").get<double>();
  if (r.contains("medium")) {
    f.zones = r["medium"].at("zones").get<int>();
    f.entries = r["medium"].at("entries").get<long long>();
    f.medium_seconds = r["medium"].at("seconds").get<double>();
  } else {
    f.entries = r.at("form_factors").at("entries").get<long long>();
  }
  std::filesystem::rename(out + "/report.json", out + "/report_" + name + ".json");
  f.ok = 1;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  std::string voxel_list = "8,16,32", patches = "1600", rays = "256", out = "medium_bench_out",
              threads = "0";
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string a = argv[k];
    if (a == "--voxels")
      voxel_list = argv[k + 1];
    else if (a == "--patches")
      patches = argv[k + 1];
    else if (a == "--medium-rays")
      rays = argv[k + 1];
    else if (a == "--out")
      out = argv[k + 1];
    else if (a == "-j")
      threads = argv[k + 1];
    else {
      std::fprintf(stderr,
                   "usage: medium_bench [--voxels 8,16,32] [--patches N] "
                   "[--medium-rays K] [--out DIR] [-j N]\n");
      return 2;
    }
  }
  std::vector<int> voxels = {0};
  std::stringstream ss(voxel_list);
  for (std::string item; std::getline(ss, item, ',');) voxels.push_back(std::atoi(item.c_str()));
  std::filesystem::create_directories(out);
  std::printf(
      "Cornell box in fog (sigma_s 5e-4, sigma_a 2e-4 /mm), %s patches, %s rays per "
      "patch and zone\n",
      patches.c_str(), rays.c_str());
  std::printf("%8s %7s %12s %10s %10s %8s %8s %10s\n", "voxels", "zones", "F entries", "medium s",
              "F total s", "solve s", "total s", "peak RSS");
  for (int v : voxels) {
    long rss_kb = 0;
    std::fflush(stdout);  // the child must not print the parent's buffered lines again
    const Figures f =
        run_in_child<Figures>([&] { return run_case(v, patches, rays, out, threads); }, rss_kb);
    const std::string label = v > 0 ? std::to_string(v) + "^3" : "none";
    if (!f.ok) {
      std::printf("%8s failed\n", label.c_str());
      continue;
    }
    std::printf("%8s %7d %12lld %10.2f %10.2f %8.2f %8.2f %8.0f MB\n", label.c_str(), f.zones,
                f.entries, f.medium_seconds, f.ff_seconds, f.solve_seconds, f.total,
                rss_kb / 1024.0);
    std::fflush(stdout);
  }
  std::printf("images: %s/fog_<N>.png\n", out.c_str());
  return 0;
}
